"""Motion behaviours: drive to a wall, drive a distance, turn, stop, wait.

All of them use odometry and the proximity scan only through :class:`~thymio_bt.robot.interface.Robot`,
slow down near their goal so that a 10 Hz controller stops within a millimetre or a tenth of a
degree, and never command more than the goal needs in one tick (no overshoot).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Literal, get_args

from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.base import RUNNING, SUCCESS, BehaviourParams, RobotBehaviour, current_pose
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import Pose, wrap_angle
from thymio_bt.inputs.fields import (
    Angle,
    AngularSpeed,
    Duration,
    Length,
    PerSecond,
    PerSecondPerMetre,
    SensedLength,
    Speed,
    plain_values,
)
from thymio_bt.robot.interface import SENSOR_NAMES, Robot
from thymio_bt.robot.model import COURSE, WIDEST_RANGE

SensorName = Literal[
    "front_left", "front_center_left", "front_center", "front_center_right", "front_right", "rear_left", "rear_right"
]
assert set(get_args(SensorName)) == set(SENSOR_NAMES)

#: Readings of the ±38° rays closer than this count as centred (about 0.15 mm off the centre line),
#: so a centred robot drives dead straight on its held heading instead of hunting around it.
CENTRE_DEADBAND = 0.0005

#: The slowest turn TurnAngle commands near its goal (rad/s).
MIN_TURN_RATE = 0.02

#: Distance between the two rear sensors (robot.md: y = ±0.0305).
REAR_SENSOR_SPACING = 0.061


#: A late robot's approach gain times its delay (latency plus a tick) stays below this, so that
#: the proportional approach settles instead of hunting (a loop with dead time oscillates as the
#: product nears pi/2; on the Playground, TurnAngle at gain 5 with 0.3 s of delay hunted for 60 s).
DAMPED_GAIN_DELAY = 0.5


def late_gain(gain: float, latency: float, period: float) -> float:
    """``gain``, capped for a robot with a ``latency`` (s; see :data:`DAMPED_GAIN_DELAY`).

    >>> late_gain(5.0, 0.0, 0.1), round(late_gain(5.0, 0.2, 0.1), 3)  # the simulation; a late robot
    (5.0, 1.667)
    """
    return min(gain, DAMPED_GAIN_DELAY / (period + latency)) if latency else gain


def approach_speed(remaining: float, cruise: float, gain: float, minimum: float, period: float) -> float:
    """Speed towards a goal ``remaining`` away: cruise, then proportional, never past it in one tick.

    >>> approach_speed(0.5, cruise=0.1, gain=5.0, minimum=0.005, period=0.1)  # far: cruise
    0.1
    >>> approach_speed(0.004, cruise=0.1, gain=5.0, minimum=0.005, period=0.1)  # near: gain x remaining
    0.02
    >>> round(approach_speed(0.0003, cruise=0.1, gain=5.0, minimum=0.005, period=0.1), 9)  # not past the goal
    0.003
    """
    if remaining <= 0.0:
        return 0.0
    # min(cruise, max(gain * remaining, minimum), remaining / period), without builtin calls (hot path)
    speed = gain * remaining
    if minimum > speed:
        speed = minimum
    best = cruise
    if speed < best:
        best = speed
    limit = remaining / period
    return limit if limit < best else best


class Motion(RobotBehaviour):
    """The base of the motions whose parameters have ``keep_moving``: the robot is then left driving
    when the motion ends (the next motion takes over without a stop)."""

    def keeps_moving(self) -> bool:
        """Its parameters' ``keep_moving``."""
        return bool(self.params.keep_moving)


class MoveUntilWallParams(BehaviourParams):
    """Drive forward until a proximity sensor reads ``distance``."""

    speed: Speed = Field(0.1, gt=0, le=0.2, description="cruise speed")
    distance: SensedLength = Field(
        0.05, ge=COURSE.range_min, le=WIDEST_RANGE, description="stop when the sensor reads this"
    )
    sensor: SensorName = Field("front_center", description="the sensor that watches the wall")
    approach_gain: PerSecond = Field(5.0, gt=0, le=10, description="slow-down gain once the wall is in range")
    min_speed: Speed = Field(0.005, gt=0, le=0.05, description="slowest approach speed")
    tolerance: Length = Field(0.0005, gt=0, le=0.01, description="stop when within this of distance")
    hold_heading: bool = Field(True, description="steer to keep the heading the robot had at the start")
    centre: bool = Field(
        False,
        description="steer to the middle of the corridor while both ±38° rays see its "
        "side walls and no wall is ahead (cancels the lateral drift odometry errors build "
        "up between turns)",
    )
    centre_gain: PerSecondPerMetre = Field(
        5.0, gt=0, le=50, description="steering per metre of difference between the left and right ±38° readings"
    )
    keep_moving: bool = Field(False, description="do not stop the robot when done")


#: how many of the latest readings MoveUntilWall averages (through odometry) to place the wall
WALL_READINGS = 4


class MoveUntilWall(Motion):
    """Cruise at ``speed``, slow down once the wall is in range, stop when the sensor reads ``distance``.

    It holds its start heading by odometry; with ``centre`` it also steers towards the middle of
    a corridor while both side walls are in view and the front ray sees nothing (near a wall ahead
    the angled rays may see it too), and holds the heading it has when that stops. Fails with
    NO_WALL when no wall comes into range within the time limit.

    Example (YAML)::

        - MoveUntilWall: {speed: 10cm/s, distance: 5cm}
    """

    Params = MoveUntilWallParams
    moves = True
    reports = "stop"

    def start(self) -> None:
        """Hold the current heading; no wall seen yet."""
        pose = current_pose(self.robot)
        self.heading = pose.yaw
        self.wall_seen = False
        self.origin = (pose.x, pose.y)
        self.walls: deque[float] = deque(maxlen=WALL_READINGS)  # the wall's place along the heading, per reading
        self.speed = 0.0  # the speed last commanded
        self.saw_nothing = False  # the last reading was out of range
        # a backend's latency and the approach gain it allows: fixed for the run
        self.latency = self.robot.latency
        self.gain = late_gain(self.params.approach_gain, self.latency, self.ctx.tick_period)
        self.values = plain_values(self.params)  # step() reads ten parameters a tick

    def _travelled(self, pose: Pose) -> float:
        """How far ``pose`` is from the start along the held heading."""
        return (pose.x - self.origin[0]) * math.cos(self.heading) + (pose.y - self.origin[1]) * math.sin(self.heading)

    def step(self) -> Status:
        """Approach the wall: cruise, slow down in range, stop at the distance (a glint holds it a tick)."""
        p = self.values
        pose = current_pose(self.robot)  # read once: nothing moves the robot within a tick
        scan = self.robot.proximity()
        assert scan is not None
        reading = scan[p.sensor]
        remaining = reading - p.distance
        finite, infinite = math.isfinite(reading), math.isinf(reading)
        if self.saw_nothing and finite and remaining <= p.tolerance:
            # nothing was in range a tick ago and now the wall would be at the stop distance: a wall
            # ahead comes into range far beyond it, so this is a glint (Enki's cones at a corner
            # read 0 once): hold still for a tick and let the next reading say
            self.saw_nothing = False
            self.robot.drive(0.0, 0.0)
            self.speed = 0.0
            self.say("{} jumped to {:.4f} m: checking", p.sensor, reading)
            return RUNNING
        self.saw_nothing = infinite
        if finite:
            self.wall_seen = True
            # where the wall is, by this reading and odometry: averaged over the last readings, one
            # noisy reading (a real sensor's) cannot stop the robot early; noise-free they all agree
            travelled = self._travelled(pose)
            self.walls.append(travelled + reading)
            remaining = sum(self.walls) / len(self.walls) - travelled - p.distance
            # a late robot (readings and commands) covers this much before anything sent now acts
            remaining -= self.speed * self.latency
        else:
            self.walls.clear()
        self.reading, self.extra = reading, self._end_fields
        if remaining <= p.tolerance:
            self.robot.drive(0.0, 0.0)
            self.say("stopped at {:.4f} m", reading)
            return SUCCESS
        speed = (
            p.speed if infinite else approach_speed(remaining, p.speed, self.gain, p.min_speed, self.ctx.tick_period)
        )
        # the side rays read only to centre: a scan cast when read (the simulation's) casts no ray else
        left, right = (scan["front_left"], scan["front_right"]) if p.centre else (math.inf, math.inf)
        if (
            p.centre
            and math.isfinite(left)
            and math.isfinite(right)
            and math.isinf(scan["front_center"])
            and abs(left - right) > CENTRE_DEADBAND
        ):
            turn = max(-0.5, min(0.5, p.centre_gain * (left - right)))  # nearer the right wall: turn left
            self.heading = pose.yaw  # hold this once a wall drops out
        else:
            turn = heading_hold(pose.yaw, self.heading) if p.hold_heading else 0.0
        self.robot.drive(speed, turn)
        self.speed = speed
        if infinite:
            self.feedback_message = "no wall in range"
        else:
            self.say("{} {:.4f} m, {:.3f} m/s", p.sensor, reading, speed)
        return RUNNING

    def _end_fields(self) -> dict[str, float | None]:
        """The behaviour_end fields: the last range read and the stop distance."""
        reading = self.reading
        return {"range": None if math.isinf(reading) else round(reading, 6), "distance": self.params.distance}

    def on_timeout(self) -> Status:
        """NO_WALL when no wall came into range in the time limit, else TIMEOUT."""
        if not self.wall_seen:
            return self.fail(
                FailureCode.NO_WALL,
                f"no wall came within {self.robot.model.range_max:g} m of {self.params.sensor} "
                f"in {self.params.timeout:g} s",
            )
        return super().on_timeout()


#: Heading errors smaller than this (0.006°, 0.04 mm of drift over a 0.4 m leg) are not corrected:
#: a P-controller only approaches zero, and every non-zero turn costs the simulation a re-aimed
#: control body in each physics sub-step.
HEADING_DEADBAND = 1e-4


def heading_hold(yaw: float, heading: float, gain: float = 3.0) -> float:
    """An angular velocity that steers a robot heading ``yaw`` back to ``heading`` (zero when already on it)."""
    error = wrap_angle(heading - yaw)
    if -HEADING_DEADBAND < error < HEADING_DEADBAND:
        return 0.0
    turn = gain * error  # max(-0.5, min(0.5, turn)) without builtin calls (hot path)
    if not turn < 0.5:
        turn = 0.5
    return turn if turn > -0.5 else -0.5


class MoveDistanceParams(BehaviourParams):
    """Drive straight by odometry; a negative distance drives backwards."""

    distance: Length = Field(description="signed distance along the heading at the start", ge=-10, le=10)
    speed: Speed = Field(0.1, gt=0, le=0.2, description="cruise speed")
    approach_gain: PerSecond = Field(5.0, gt=0, le=10, description="slow-down gain near the goal")
    min_speed: Speed = Field(0.005, gt=0, le=0.05, description="slowest approach speed")
    tolerance: Length = Field(0.0005, gt=0, le=0.01, description="done when within this of the goal")
    keep_moving: bool = Field(False, description="do not stop the robot when done")


class MoveDistance(Motion):
    """Drive ``distance`` forwards (or backwards) by odometry, holding the start heading.

    Example (YAML)::

        - MoveDistance: {distance: 30cm}
    """

    Params = MoveDistanceParams
    moves = True

    @classmethod
    def drives_forward(cls, params: MoveDistanceParams) -> float:
        """It drives ``distance`` blind (backwards: not forward)."""
        return params.distance

    def start(self) -> None:
        """Measure from here, along the current heading."""
        self.origin = current_pose(self.robot)

    def travelled(self, pose: Pose) -> float:
        """How far ``pose`` is from the start along the start heading."""
        o = self.origin
        return (pose.x - o.x) * math.cos(o.yaw) + (pose.y - o.y) * math.sin(o.yaw)

    def step(self) -> Status:
        """Drive on towards the distance, slowing down near it."""
        p = self.params
        pose = current_pose(self.robot)  # read once: nothing moves the robot within a tick
        done = self.travelled(pose)
        remaining = p.distance - done
        self.done, self.extra = done, self._end_fields
        if abs(remaining) <= p.tolerance:
            self.robot.drive(0.0, 0.0)
            return SUCCESS
        speed = approach_speed(abs(remaining), p.speed, p.approach_gain, p.min_speed, self.ctx.tick_period)
        self.robot.drive(math.copysign(speed, remaining), heading_hold(pose.yaw, self.origin.yaw))
        self.say("{:.3f} of {:.3f} m", done, p.distance)
        return RUNNING

    def _end_fields(self) -> dict[str, float]:
        """The behaviour_end fields: the distance driven."""
        return {"distance": round(self.done, 6)}


class TurnAngleParams(BehaviourParams):
    """Turn in place by a relative angle."""

    angle: Angle = Field(
        description="relative angle, left positive (may come from the blackboard)", ge=-2 * math.pi, le=2 * math.pi
    )
    mode: Literal["odometry", "rear_sensors"] = Field(
        "odometry", description="end by odometry, or when the two rear rays read equal"
    )
    speed: AngularSpeed = Field(1.0, gt=0, le=4.3, description="fastest turn rate")
    tolerance: Angle = Field(
        0.0005,
        gt=0,
        le=0.2,
        description="odometry: done within this angle; rear_sensors: "
        "done when the rear rays differ by less than spacing*tan(tolerance)",
    )
    snap: Angle = Field(
        0.0,
        ge=0,
        le=math.pi,
        description="if > 0, round the target heading to a multiple "
        "of this (e.g. 90deg) so errors do not add up turn after turn",
    )
    pivot: Length = Field(
        0.0,
        ge=0,
        le=0.05,
        description="turn about the point of the axle line this far "
        "outside the turn, not the axle's centre: the axle backs away along an arc, so the "
        "front sweeps this much further from the walls ahead and on the turning side "
        "(a tight cell)",
    )
    keep_moving: bool = Field(False, description="do not stop the robot when done")


class TurnAngle(Motion):
    """Turn in place about the wheel axle by ``angle`` (left positive).

    ``mode: rear_sensors`` turns by odometry to within 10° and then squares the robot to the wall
    behind it until the two rear rays read the same; it fails with NO_WALL when no wall is behind.

    With ``pivot`` it turns about a point of the axle line that far outside the turn (backing as
    it turns): a 90° turn ends with the axle ``pivot`` back from where it was along both the old
    and the new heading, so the front passes that much further from the walls it sweeps.

    Example (YAML)::

        - TurnAngle: {angle: 90deg}
        - TurnAngle: {angle: bb:turn_angle}     # written by ChooseTurn
        - TurnAngle: {angle: bb:move_turn, pivot: 3mm}
    """

    Params = TurnAngleParams
    moves = True
    reports = "turn"
    FINE_WINDOW = math.radians(10.0)

    def start(self) -> None:
        """The angle to turn (to the snapped heading, if any)."""
        p = self.params
        self.turn = Turn.begin(self, p.angle, p.speed, p.tolerance, p.snap)
        self.values = plain_values(p)  # step() reads two a tick

    def step(self) -> Status:
        """Turn on towards the angle (by odometry, or squared by the rear sensors near the end)."""
        turn = self.turn
        error = turn.error()
        self.extra = self._end_fields
        if self.values.mode == "rear_sensors" and abs(error) < self.FINE_WINDOW:
            scan = self.robot.proximity()
            assert scan is not None
            left, right = scan["rear_left"], scan["rear_right"]
            if math.isinf(left) or math.isinf(right):
                return self.fail(FailureCode.NO_WALL, "the rear sensors see no wall behind the robot")
            # the rear-left sensor reads farther when the robot must still turn left to be square
            error = math.atan2(left - right, REAR_SENSOR_SPACING)
        if turn.drive(error, self.values.pivot):
            self.say("turned {:.2f} deg", math.degrees(turn.turned))
            return SUCCESS
        self.say("{:.2f} deg to go", math.degrees(error))
        return RUNNING

    def _end_fields(self) -> dict[str, float]:
        """The behaviour_end fields: the angle turned."""
        return {"angle": round(self.turn.turned, 6)}


@dataclass(slots=True)
class Turn:
    """An in-place turn by odometry, driven a tick at a time: TurnAngle's controller, which other
    behaviours that turn as one of their steps (LookAround) use too.

    ``error()`` reads the heading and says how much is left to turn (what a late robot will still
    turn from what was sent is counted as turned); ``drive(error)`` commands the turn rate for that
    error, or stops the robot and says True once it is within the tolerance.
    """

    robot: Robot
    goal: float  # the signed angle to turn, unwrapped (may exceed pi)
    speed: float
    tolerance: float
    gain: float
    period: float
    latency: float
    last_yaw: float
    turned: float = 0.0
    rate: float = 0.0  # the turn rate last commanded

    @classmethod
    def begin(cls, behaviour: RobotBehaviour, angle: float, speed: float, tolerance: float, snap: float = 0.0) -> Turn:
        """A turn by ``angle`` (left positive) from the robot's heading now; with ``snap``, to the
        nearest multiple of it. A late robot cannot stop finer than its slowest turn covers in a tick
        and its latency, so its tolerance is at least that."""
        robot, period = behaviour.robot, behaviour.ctx.tick_period
        yaw = current_pose(robot).yaw
        target = yaw + angle
        if snap:
            target = round(target / snap) * snap
        latency = robot.latency
        if latency:
            tolerance = max(tolerance, MIN_TURN_RATE * (period + latency))
        return cls(robot, target - yaw, speed, tolerance, late_gain(5.0, latency, period), period, latency, yaw)

    def error(self) -> float:
        """The angle still to turn, after what a late robot turns before a command sent now acts."""
        yaw = current_pose(self.robot).yaw
        self.turned += wrap_angle(yaw - self.last_yaw)
        self.last_yaw = yaw
        return self.goal - self.turned - self.rate * self.latency

    def drive(self, error: float, pivot: float = 0.0) -> bool:
        """Stop and say True within the tolerance; else command the turn rate for ``error`` about a
        point ``pivot`` outside the turn (the axle backs away as the robot turns)."""
        if abs(error) <= self.tolerance:
            self.robot.drive(0.0, 0.0)
            return True
        rate = approach_speed(abs(error), self.speed, self.gain, MIN_TURN_RATE, self.period)
        self.rate = math.copysign(rate, error)
        self.robot.drive(-rate * pivot, self.rate)
        return False


class StopParams(BehaviourParams):
    """No parameters besides the time limit."""


class Stop(RobotBehaviour):
    """Stop the robot at once (SUCCESS).

    Example (YAML)::

        - Stop: {}
    """

    Params = StopParams
    moves = True
    always, instant = "S", True  # it fails only without a robot

    def step(self) -> Status:
        """Stop the motors."""
        self.robot.drive(0.0, 0.0)
        return SUCCESS


class WaitParams(BehaviourParams):
    """Wait in simulated time."""

    seconds: Duration = Field(description="how long to wait", ge=0, le=3600)
    timeout: Duration = Field(3600.0, gt=0, le=3600, description="time limit in simulated seconds")


class Wait(RobotBehaviour):
    """RUNNING for ``seconds`` of simulated time, then SUCCESS; the robot keeps its command.

    Example (YAML)::

        - Wait: {seconds: 2}
    """

    Params = WaitParams
    needs_robot = False
    fails_on_collision = False

    def step(self) -> Status:
        """SUCCESS once the time has passed."""
        if self.elapsed() >= self.params.seconds - 1e-9:
            return SUCCESS
        self.say("{:.1f} s left", self.params.seconds - self.elapsed())
        return RUNNING
