"""The student report's navigation: PID waypoint following (Algorithm 2) and the Pledge-style
left-wall obstacle avoidance (Algorithm 3), split into behaviours so the state machine is a tree:

- ``turning_left``  → :class:`TurnUntilClear` (adds the angle turned to a counter),
- ``going_forward`` → ``MoveDistance``,
- ``turning_right`` → :class:`TurnBack` (turns the counter back to zero; fails if blocked).

``missions/lib/navigation.yaml`` composes them; see ``missions/waypoints_obstacles.yaml``.
"""

from __future__ import annotations

import math
from typing import Literal

from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.base import BehaviourParams, ConditionBehaviour, Reading, RobotBehaviour, current_pose
from thymio_bt.behaviours.motion import approach_speed
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import Pose, wrap_angle
from thymio_bt.inputs.fields import Angle, AngularSpeed, BlackboardKey, Duration, Length, Point, Speed
from thymio_bt.robot.interface import Scan
from thymio_bt.robot.pid import PID

FRONT = ("front_left", "front_center_left", "front_center", "front_center_right", "front_right")
#: The report's simulation thresholds for the 5 front sensors (Table 2), metres.
REPORT_THRESHOLDS = (0.025, 0.03, 0.03, 0.03, 0.025)

Thresholds = tuple[Length, Length, Length, Length, Length]


class PIDGains(BehaviourParams):
    """Gains and limits of the two controllers (the report's Table 2 by default)."""

    heading_kp: float = Field(3.0, ge=0, le=100, description="heading PID: proportional gain")
    heading_ki: float = Field(0.0, ge=0, le=100, description="heading PID: integral gain")
    heading_kd: float = Field(0.0, ge=0, le=100, description="heading PID: derivative gain")
    distance_kp: float = Field(2.0, ge=0, le=100, description="distance PID: proportional gain")
    distance_ki: float = Field(0.0, ge=0, le=100, description="distance PID: integral gain")
    distance_kd: float = Field(0.0, ge=0, le=100, description="distance PID: derivative gain")
    max_speed: Speed = Field(0.05, gt=0, le=0.2, description="forward speed limit")
    max_turn: AngularSpeed = Field(math.pi, gt=0, le=4.3, description="turn rate limit")
    turn_in_place_above: Angle = Field(
        math.pi / 90, gt=0, le=math.pi, description="turn in place while the heading error exceeds this"
    )
    tolerance: Length = Field(0.01, gt=0, le=0.5, description="a goal counts as reached within this distance")
    timeout: Duration = Field(300.0, gt=0, le=36000, description="time limit in simulated seconds")


class _Navigator:
    """Algorithm 2 for one goal: heading PID and distance PID; turn in place on large heading errors.

    A goal the controller cannot settle on (a tolerance tighter than it holds at this tick rate:
    base_link, off the axle, circles the goal or spins beside it) would keep it turning until the
    time limit. So :attr:`stalled` says why, once the robot has turned a full circle since it last
    got closer to the goal by half the tolerance; no normal approach turns that much.
    """

    def __init__(self, p: PIDGains) -> None:
        self.p = p
        self.heading = PID(p.heading_kp, p.heading_ki, p.heading_kd, p.max_turn)
        self.distance = PID(p.distance_kp, p.distance_ki, p.distance_kd, p.max_speed)
        self.stalled: str | None = None
        self._best = math.inf  # the closest to the goal so far
        self._turned = 0.0  # how far the robot turned since then (rad)
        self._yaw: float | None = None

    def command(self, pose: Pose, goal: tuple[float, float], dt: float) -> tuple[float, float] | None:
        """(v, ω) towards ``goal``, or None when it is reached (the PIDs are then reset) or when
        the robot makes no progress (:attr:`stalled` then says why)."""
        dx, dy = goal[0] - pose.x, goal[1] - pose.y
        distance = math.hypot(dx, dy)
        if distance <= self.p.tolerance:
            self.heading.reset()
            self.distance.reset()
            self._best, self._turned, self._yaw = math.inf, 0.0, None
            return None
        if distance < self._best - self.p.tolerance / 2:
            self._best, self._turned = distance, 0.0
        elif self._yaw is not None:
            self._turned += abs(wrap_angle(pose.yaw - self._yaw))
            if self._turned > math.tau:
                self.stalled = (
                    f"turned a full circle without getting closer to ({goal[0]:g}, {goal[1]:g}) than "
                    f"{1000 * self._best:.1f} mm: a tolerance of {1000 * self.p.tolerance:g} mm is "
                    f"tighter than the controller can hold (try tolerance: "
                    f"{max(5.0, math.ceil(2000 * self._best)):g}mm)"
                )
                return None
        self._yaw = pose.yaw
        error = wrap_angle(math.atan2(dy, dx) - pose.yaw)
        omega = self.heading(error, dt)
        if abs(error) > self.p.turn_in_place_above:
            return 0.0, omega
        return max(0.0, self.distance(distance, dt)), omega


class GoToPoseParams(PIDGains):
    """Drive to a point with the report's two PID controllers."""

    goal: Point = Field(description="the point [x, y] to reach")


class GoToPose(RobotBehaviour):
    """Drive base_link to ``goal`` (Algorithm 2): turn in place while the heading error is large,
    else heading PID and distance PID together; SUCCESS within ``tolerance``.

    Example (YAML)::

        - GoToPose: {goal: [0.5, 0.3], max_speed: 5cm/s}
    """

    Params = GoToPoseParams
    moves = True

    @classmethod
    def drives_forward(cls, params: GoToPoseParams) -> float:
        """It drives to its goal, as far as that is, without looking ahead."""
        return math.inf

    def start(self) -> None:
        """A fresh controller (its PIDs start from zero)."""
        self.nav = _Navigator(self.params)

    def step(self) -> Status:
        """One control step towards the goal: SUCCESS there, FAILURE (NO_PROGRESS) when stalled."""
        command = self.nav.command(current_pose(self.robot), self.params.goal, self.ctx.tick_period)
        if command is None:
            self.robot.drive(0.0, 0.0)
            return self.fail(FailureCode.NO_PROGRESS, self.nav.stalled) if self.nav.stalled else Status.SUCCESS
        self.robot.drive(*command)
        return Status.RUNNING


class FollowWaypointsParams(PIDGains):
    """Visit waypoints in order with the report's PID controllers."""

    waypoints: list[Point] = Field(min_length=1, description="the points [[x, y], ...] to visit")
    key: BlackboardKey = Field(
        "waypoint",
        description="blackboard key holding the index of the next waypoint, so the "
        "behaviour resumes where it was after an interruption (e.g. by obstacle avoidance)",
    )


class FollowWaypoints(RobotBehaviour):
    """Visit ``waypoints`` in order (Algorithm 2 for each); SUCCESS after the last one.

    Progress is kept on the blackboard (``waypoint``: index of the next one, ``waypoint_left``:
    how many remain), so when obstacle avoidance interrupts it, it resumes at the same waypoint.
    Emits a ``waypoint_reached`` event with the pose for each.

    Example (YAML)::

        - FollowWaypoints: {waypoints: [[0.5, -0.4], [0.5, 0.4]]}
    """

    Params = FollowWaypointsParams
    moves = True

    @classmethod
    def drives_forward(cls, params: FollowWaypointsParams) -> float:
        """It drives to its goal, as far as that is, without looking ahead."""
        return math.inf

    def prepare(self) -> None:
        """The progress keys."""
        key = self.params.key
        self.board = self.blackboard("progress", write=(key, f"{key}_left"))

    def start(self) -> None:
        """A fresh controller; resume at the waypoint the blackboard says is next."""
        self.nav = _Navigator(self.params)
        self.index = self.board.get(self.params.key) if self.board.exists(self.params.key) else 0
        self._publish()

    def _publish(self) -> None:
        """Write the progress (next index, how many left) on the blackboard."""
        self.board.set(self.params.key, self.index)
        self.board.set(f"{self.params.key}_left", len(self.params.waypoints) - self.index)

    def step(self) -> Status:
        """Drive towards the next waypoint, moving on (and logging it) as each is reached."""
        waypoints = self.params.waypoints
        while self.index < len(waypoints):
            pose = current_pose(self.robot)
            command = self.nav.command(pose, waypoints[self.index], self.ctx.tick_period)
            if self.nav.stalled:
                self.robot.drive(0.0, 0.0)
                return self.fail(FailureCode.NO_PROGRESS, f"waypoint {self.index + 1}: {self.nav.stalled}")
            if command is not None:
                self.robot.drive(*command)
                self.feedback_message = f"to waypoint {self.index + 1}/{len(waypoints)} {waypoints[self.index]}"
                self.extra = {"waypoint": self.index}
                return Status.RUNNING
            self.ctx.events.emit(
                self.ctx.now(),
                "waypoint_reached",
                index=self.index,
                target=list(waypoints[self.index]),
                pose={k: round(v, 6) for k, v in pose.as_dict().items()},
            )
            self.index += 1
            self._publish()
        self.robot.drive(0.0, 0.0)
        self.extra = {"waypoint": self.index}
        return Status.SUCCESS


class WaypointsDoneParams(BehaviourParams):
    """Have all waypoints been visited?"""

    key: BlackboardKey = Field("waypoint", description="the FollowWaypoints progress key")


class WaypointsDone(ConditionBehaviour):
    """SUCCESS once FollowWaypoints has no waypoint left.

    Example (YAML)::

        - repeat: {until: WaypointsDone, do: ...}
    """

    Params = WaypointsDoneParams
    needs_robot = False

    def prepare(self) -> None:
        """The key of how many waypoints are left."""
        self.board = self.blackboard("progress", read=(f"{self.params.key}_left",))

    def step(self) -> Status:
        """Whether the blackboard says no waypoint is left."""
        key = f"{self.params.key}_left"
        left = self.board.get(key) if self.board.exists(key) else None
        self.feedback_message = "not started" if left is None else f"{left} left"
        return Status.SUCCESS if left == 0 else Status.FAILURE


# ------------------------------------------------------------ avoidance
def _blocked(scan: Scan, thresholds: Thresholds) -> bool:
    """Whether a front sensor reads less than its threshold (one threshold per front sensor)."""
    return any(scan[name] < limit for name, limit in zip(FRONT, thresholds, strict=True))


class ObstacleAheadParams(BehaviourParams):
    """Is an obstacle closer than a threshold to any front sensor?"""

    thresholds: Thresholds = Field(REPORT_THRESHOLDS, description="per front sensor, left to right")


class ObstacleAhead(ConditionBehaviour):
    """SUCCESS when any front sensor reads less than its threshold (the report's 0.025/0.03 m).

    Example (YAML)::

        - ObstacleAhead: {thresholds: [0.025, 0.03, 0.03, 0.03, 0.025]}
    """

    Params = ObstacleAheadParams

    @classmethod
    def clear_ahead(cls, params: ObstacleAheadParams) -> float:
        """Inverted, it says nothing is within its largest threshold ahead."""
        return max(params.thresholds)

    def step(self) -> Status:
        """Compare the front readings with the thresholds; the feedback says the nearest one."""
        scan = self.robot.proximity()
        assert scan is not None
        nearest = min(FRONT, key=lambda name: scan[name])
        self.say("nearest: {} reads {}", nearest, Reading(scan[nearest]))
        return Status.SUCCESS if _blocked(scan, self.params.thresholds) else Status.FAILURE


class _CounterParams(BehaviourParams):
    """What the Pledge counter's turns share: the obstacle thresholds, the counter key, the rate."""

    thresholds: Thresholds = Field(REPORT_THRESHOLDS, description="per front sensor, left to right")
    counter: BlackboardKey = Field("avoid_turn", description="blackboard key of the angle turned since avoidance began")
    speed: AngularSpeed = Field(1.0, gt=0, le=4.3, description="turn rate")


class _CountingTurn(RobotBehaviour):
    """A turn in place that adds what it turns to a blackboard counter (the Pledge counter)."""

    moves = True

    def prepare(self) -> None:
        """The counter's key."""
        self.board = self.blackboard("counter", write=(self.params.counter,))

    def start(self) -> None:
        """Count from the current heading; start the counter at zero if nothing wrote it yet."""
        self.last_yaw = current_pose(self.robot).yaw
        if not self.board.exists(self.params.counter):
            self.board.set(self.params.counter, 0.0)

    def count(self) -> float:
        """Add the turn since the last call to the counter; the counter's new value (rad)."""
        yaw = current_pose(self.robot).yaw
        total = self.board.get(self.params.counter) + wrap_angle(yaw - self.last_yaw)
        self.last_yaw = yaw
        self.board.set(self.params.counter, total)
        self.extra = {"counter": round(total, 6)}
        return total


class TurnUntilClearParams(_CounterParams):
    """turning_left: turn until no front sensor is below its threshold."""

    direction: Literal["left", "right"] = Field("left", description="which way to turn")
    margin: Angle = Field(
        0.0,
        ge=0,
        le=math.pi / 2,
        description="keep turning this much more once clear, so "
        "the body (which the angled sensors do not see) clears a corner too",
    )


class TurnUntilClear(_CountingTurn):
    """Turn (left by default) until the way ahead is clear; the angle goes to the Pledge counter.

    Example (YAML)::

        - TurnUntilClear: {direction: left}
    """

    Params = TurnUntilClearParams

    def start(self) -> None:
        """Count from here; not clear yet."""
        super().start()
        self.clear_at: float | None = None

    def step(self) -> Status:
        """Turn while blocked, then the margin more once clear."""
        counter = self.count()
        scan = self.robot.proximity()
        assert scan is not None
        sign = 1.0 if self.params.direction == "left" else -1.0
        if self.clear_at is None and not _blocked(scan, self.params.thresholds):
            self.clear_at = counter
        if self.clear_at is not None:
            remaining = self.params.margin - abs(counter - self.clear_at)
            if remaining <= 0.002:
                self.robot.drive(0.0, 0.0)
                return Status.SUCCESS
            rate = approach_speed(remaining, self.params.speed, 5.0, 0.02, self.ctx.tick_period)
            self.robot.drive(0.0, sign * rate)
            self.feedback_message = "clear: turning the margin"
            return Status.RUNNING
        self.robot.drive(0.0, sign * self.params.speed)
        self.feedback_message = "blocked ahead: turning"
        return Status.RUNNING


class TurnBackParams(_CounterParams):
    """turning_right: turn the Pledge counter back to zero."""

    tolerance: Angle = Field(0.01, gt=0, le=0.5, description="back on course within this angle")


class TurnBack(_CountingTurn):
    """Turn back towards the heading avoidance started from (the counter back to zero): SUCCESS
    there; FAILURE as soon as an obstacle is ahead (so the avoidance turns left again).

    Example (YAML)::

        - TurnBack: {}
    """

    Params = TurnBackParams

    def step(self) -> Status:
        """Turn the counter back towards zero; FAILURE (BLOCKED) as soon as an obstacle is ahead."""
        counter = self.count()
        if abs(counter) <= self.params.tolerance:
            self.robot.drive(0.0, 0.0)
            self.board.set(self.params.counter, 0.0)
            self.feedback_message = "back on course"
            return Status.SUCCESS
        scan = self.robot.proximity()
        assert scan is not None
        if _blocked(scan, self.params.thresholds):
            self.robot.drive(0.0, 0.0)
            return self.fail(FailureCode.BLOCKED, "obstacle ahead: turn away again")
        rate = approach_speed(abs(counter), self.params.speed, 5.0, 0.02, self.ctx.tick_period)
        self.robot.drive(0.0, -math.copysign(rate, counter))
        self.say("{:.1f} deg to turn back", math.degrees(counter))
        return Status.RUNNING


class SetBlackboardParams(BehaviourParams):
    """Write a value on the blackboard."""

    key: BlackboardKey = Field(description="the key")
    value: float | str | bool = Field(description="the value")


class SetBlackboard(RobotBehaviour):
    """Write ``value`` under ``key`` (e.g. reset a counter) and succeed.

    Example (YAML)::

        - SetBlackboard: {key: avoid_turn, value: 0}
    """

    Params = SetBlackboardParams
    needs_robot = False
    always, instant = "S", True
    emits_events = False
    fails_on_collision = False

    def prepare(self) -> None:
        """The key written."""
        self.board = self.blackboard("writer", write=(self.params.key,))

    def step(self) -> Status:
        """Write the value."""
        self.board.set(self.params.key, self.params.value)
        return Status.SUCCESS
