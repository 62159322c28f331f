"""WallFollow: the hand-on-wall rule through a maze of square cells, on the robot's own geometry.

The robot drives along a corridor holding its heading (re-taken from the side walls and from walls
squarely ahead or behind, since odometry's heading drifts), turns into an opening once it has driven
to its middle, and turns away from its side at a wall ahead. Where it is in the maze is kept from
the distance covered along each corridor, in quarter turns from the start heading. The corridor's
geometry (sensor pairs, glints, the wall-line fit) is in :mod:`thymio_bt.robot.corridor`.

Example::

    >>> from thymio_bt.testing import run_tree, world
    >>> bend = world('''
    ... +--+--+--+
    ... |>       |
    ... +--+--+  +
    ...       |  |
    ...       +  +
    ... ''')
    >>> result = run_tree({"WallFollow": {"side": "left"}}, bend, seconds=60)
    >>> result.status, result.collisions, [e["turns"] for e in result.events if e["kind"] == "behaviour_end"]
    (<RunStatus.SUCCESS: 'SUCCESS'>, 0, ['R'])
"""

from __future__ import annotations

import math
from collections import deque
from typing import Literal

from py_trees.common import Status
from pydantic import Field, model_validator

from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour, current_pose
from thymio_bt.behaviours.motion import MIN_TURN_RATE, approach_speed, late_gain
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import Pose, wrap_angle
from thymio_bt.inputs.fields import AngularSpeed, Duration, Length, Speed
from thymio_bt.robot.corridor import (
    FRONT_PAIR,
    FRONT_SENSORS,
    GLINT_BELOW,
    GLINT_JUMP,
    QUARTERS,
    REAR_PAIR,
    RETAKE_ANGLE,
    RETAKE_MAX,
    SQUARING_READINGS,
    WALL_RESIDUAL,
    WALL_SPAN,
    Side,
    line_direction,
    side_ray,
)


class WallFollowParams(BehaviourParams):
    """Follow one wall through a maze of square cells."""

    side: Side = Field("left", description="the wall to keep on the robot's side")
    speed: Speed = Field(0.1, gt=0, le=0.2, description="cruise speed")
    turn_speed: AngularSpeed = Field(1.0, gt=0, le=4.0, description="fastest turn rate")
    cell: Length = Field(0.2, ge=0.17, le=1.0, description="the maze's grid pitch (wall centre to centre)")
    wall_thickness: Length = Field(0.01, gt=0, le=0.05, description="the maze's wall thickness")
    until: Literal["exit", "goal"] = Field(
        "exit", description="stop when leaving the maze's bounding box, or on reaching the goal"
    )
    exit_margin: Length = Field(
        0.03,
        ge=0,
        le=0.2,
        description="with until: exit, how far beyond the maze's bounding box base_link must believe itself "
        "(the distances it goes by are off by a centimetre or two after a long maze)",
    )
    goal: tuple[float, float] | None = Field(None, description="goal position [x, y] for until: goal")
    goal_radius: Length = Field(0.05, gt=0, le=1.0, description="how close to the goal counts")
    timeout: Duration = Field(600.0, gt=0, le=36000, description="time limit in simulated seconds")

    @model_validator(mode="after")
    def _goal_given(self) -> WallFollowParams:
        if self.until == "goal" and self.goal is None:
            raise ValueError("until: goal needs a goal: [x, y]")
        return self


class WallFollow(RobotBehaviour):
    """Follow the wall on ``side`` until leaving the maze (or reaching a goal): the hand-on-wall rule.

    In a simply-connected maze of square cells this reaches every exit. The robot drives along
    the corridor holding its heading; when the side ray loses the wall it locates the wall's end
    (between the last hit and the ray's current crossing point), drives on by odometry to the
    middle of the opening and turns into it. At a wall ahead it stops with the axle in the cell
    centre and turns away from its side; if a wall is still ahead (a dead end) it turns again.

    Example (YAML)::

        - WallFollow: {side: left}
    """

    Params = WallFollowParams
    moves = True

    def start(self) -> None:
        """Take the robot's own geometry, and the start pose as the maze frame's origin."""
        p = self.params
        self.model = self.robot.model  # this robot's own sensor poses and axle, throughout
        self.sensors = {s.name: (s.x, s.y, s.yaw) for s in self.model.sensors}
        sx, sy, syaw = self.sensors[side_ray(p.side)]
        self.sign = 1.0 if p.side == "left" else -1.0
        self.corridor = p.cell - p.wall_thickness
        ahead, lateral = sx - self.model.axle_x, abs(sy)
        # where the side ray meets a side wall, measured ahead of the axle
        self.probe = ahead + (self.corridor / 2 - lateral) / math.tan(abs(syaw))
        self.ray_ahead, self.ray_cos = ahead, math.cos(syaw)
        self.stop_distance = self.corridor / 2 - (self.sensors["front_center"][0] - self.model.axle_x)
        start = current_pose(self.robot)
        self.heading = start.yaw
        # the maze frame's origin (axle) and x axis (not ``self.start``: that is the start hook)
        self.maze_origin = (*self._axle(start), start.yaw)
        self.turns: list[str] = []
        self.mode = "forward"
        self.aligned = False
        # where the axle is in the maze's frame (start heading = +x), from the distance covered along
        # each corridor: unlike 2D odometry, it gains no sideways error when the heading drifts
        self.quarter = 0  # the corridor's direction, in quarter turns
        self.position = (0.0, 0.0)
        self.anchor: tuple[float, float] | None = None  # a cell centre (axle, maze frame)
        # a late robot (see Backend.latency) stops early by what its last command still covers,
        # approaches with a damped gain and settles a turn within what its slowest turn covers
        self.latency = self.robot.latency
        self.gain = late_gain(5.0, self.latency, self.ctx.tick_period)
        self.turn_tolerance = math.radians(0.1)
        if self.latency:
            self.turn_tolerance = max(self.turn_tolerance, MIN_TURN_RATE * (self.ctx.tick_period + self.latency))
        self.speed = self.rate = 0.0  # the speed and turn rate last commanded
        self.squaring: list[tuple[float, float, float]] = []  # readings while squaring to a wall
        self.square_pair, self.square_then_turn = FRONT_PAIR, True
        self.turn_reason = ""  # why the current turn: "wall" or "opening"
        self._new_segment()
        self._bad_input: str | None = None
        if p.until == "exit" and self.ctx.bounds is None:
            self._bad_input = "until: exit needs the maze's bounds, and this backend has none"

    def _new_segment(self) -> None:
        self.origin = self._axle(current_pose(self.robot))
        self.segment_start = self.position
        self.last_front = math.inf  # the front sensor's reading last tick
        # where each side ray met its wall (odometry frame), while it reads one straight wall
        self.wall_points: dict[str, deque[tuple[float, float]]] = {
            name: deque(maxlen=12) for name in ("front_left", "front_right")
        }
        self.wall_seen = False
        self.last_hit = 0.0
        self.target: float | None = None

    def _axle(self, pose: Pose) -> tuple[float, float]:
        x, y, _ = self.model.axle_of(pose)
        return x, y

    def _scan(self) -> dict[str, float] | None:
        """The robot's readings, a reading nearer than GLINT_BELOW taken for nothing: the robot never
        comes that close to a wall on purpose, and Enki's cones at a wall's end read 0 m for seconds
        while the robot stands still or turns (one made WallFollow square and turn twice in the open)."""
        scan = self.robot.proximity()
        if scan is None:
            return None
        return {name: math.inf if value < GLINT_BELOW else value for name, value in scan.items()}

    def _where(self) -> tuple[float, float]:
        """Where base_link is by the distances covered along the corridors (world frame), which
        unlike 2D odometry does not wander off with a drifted heading (odometry's heading was 30-45°
        off after 200 s on a loaded Playground, and its position with it)."""
        x0, y0, yaw0 = self.maze_origin
        (mx, my), c, s = self.position, math.cos(yaw0), math.sin(yaw0)
        heading, axle_x = yaw0 + self.quarter * math.pi / 2, self.model.axle_x
        return (x0 + c * mx - s * my - axle_x * math.cos(heading), y0 + s * mx + c * my - axle_x * math.sin(heading))

    def _done(self) -> bool:
        p = self.params
        x, y = self._where()
        if p.until == "goal":
            assert p.goal is not None
            return math.hypot(x - p.goal[0], y - p.goal[1]) <= p.goal_radius
        assert self.ctx.bounds is not None
        xmin, ymin, xmax, ymax = self.ctx.bounds
        margin = p.exit_margin
        if xmin - margin <= x <= xmax + margin and ymin - margin <= y <= ymax + margin:
            return False
        # out of the maze's box, and no wall in front: a robot whose distances are off by a few
        # centimetres believes it is out while still beside a wall
        scan = self._scan()
        return scan is None or all(math.isinf(scan[name]) for name in FRONT_SENSORS)

    def step(self) -> Status:
        """Stop once out of the maze (or at the goal); else one tick of driving, squaring or turning."""
        if self._bad_input:
            return self.fail(FailureCode.INVALID_INPUT, self._bad_input)
        pose = current_pose(self.robot)
        self.extra = {"turns": "".join(self.turns)}
        if self._done():
            self.robot.drive(0.0, 0.0)
            self.feedback_message = "left the maze" if self.params.until == "exit" else "reached the goal"
            return Status.SUCCESS
        if self.mode == "turn":
            return self._turn(pose)
        if self.mode == "square":
            return self._square(pose)
        return self._forward(pose)

    def _forward(self, pose: Pose) -> Status:
        p = self.params
        scan = self._scan()
        assert scan is not None
        ax, ay = self._axle(pose)
        s = (ax - self.origin[0]) * math.cos(self.heading) + (ay - self.origin[1]) * math.sin(self.heading)
        ux, uy = QUARTERS[self.quarter]
        self.position = (self.segment_start[0] + s * ux, self.segment_start[1] + s * uy)
        side = scan[side_ray(p.side)]
        if self.target is None:
            if math.isfinite(side):
                self.wall_seen = True
                self.last_hit = s + self.ray_ahead + side * self.ray_cos
            elif self.wall_seen:  # the side wall just ended: the opening starts in between
                edge = (self.last_hit + s + self.probe) / 2
                self.target = self._on_grid(edge + self.corridor / 2, s)
            elif self.aligned:  # open from the cell centre on: the opening is the next cell
                self.target = p.cell
        front = scan["front_center"]
        lead = self.speed * self.latency
        front_left = front - self.stop_distance - lead
        tol = 0.0005
        if front_left <= tol and self.last_front - front > GLINT_JUMP:
            # far or nothing ahead a tick ago and now a wall at the stop: a glint (Enki's cones at a
            # wall's end read 0), as in MoveUntilWall: hold still for a tick and let the next reading say
            self.last_front = front
            self.robot.drive(0.0, 0.0)
            self.speed = 0.0
            return Status.RUNNING
        self.last_front = front
        if self.target is not None and (
            self.target - s - lead <= tol or (front_left <= tol and self.target - s < p.cell / 2)
        ):
            return self._begin_turn(self.sign, "opening")
        if front_left <= tol:
            self.robot.drive(0.0, 0.0)
            self.speed = 0.0
            return self._begin_square(FRONT_PAIR, then_turn=True)
        limit = p.speed
        if math.isfinite(front):
            limit = approach_speed(front_left, limit, self.gain, 0.005, self.ctx.tick_period)
        if self.target is not None:
            limit = min(limit, approach_speed(self.target - s - lead, p.speed, self.gain, 0.005, self.ctx.tick_period))
        self._retake_heading(pose, scan)
        self.robot.drive(limit, self._steer(pose, scan))
        self.speed = limit
        self.feedback_message = (
            f"following the {p.side} wall"
            if self.target is None
            else f"opening on the {p.side} in {self.target - s:.3f} m"
        )
        return Status.RUNNING

    def _on_grid(self, estimate: float, s: float) -> float:
        """``estimate`` (a distance along the corridor from the segment's origin) moved to the
        nearest cell centre of the grid anchored at the last stop before a wall, never behind the robot.

        Where a sensor loses a wall's end depends on the sensor (one ray or a cone) and on its
        calibration by centimetres; the maze's cells do not. A stop facing a wall puts the axle in a
        cell centre, measured by the front sensor square to the wall (the most reliable reading), and
        every other cell centre is a whole number of cells from it along x and y: rounding the
        estimate to one absorbs errors of up to half a cell, and an opening turn that came out a
        little off does not carry its error into the next one.
        """
        if self.anchor is None:
            return estimate
        axis = self.quarter % 2  # 0: along x, 1: along y
        origin, anchor = self.segment_start[axis], self.anchor[axis]
        direction = QUARTERS[self.quarter][axis]
        world = origin + estimate * direction
        snapped = anchor + round((world - anchor) / self.params.cell) * self.params.cell
        return max((snapped - origin) / direction, s)

    def _steer(self, pose: Pose, scan: dict[str, float]) -> float:
        """Hold the corridor's heading, nudged towards the centre line when a side wall is seen."""
        heading = self.heading
        offset = self._offset(scan) if math.isinf(scan["front_center"]) else None
        if offset is not None:
            heading -= max(-0.1, min(0.1, 5.0 * offset))
        error = wrap_angle(heading - pose.yaw)
        return max(-0.5, min(0.5, 3.0 * error))

    def _offset(self, scan: dict[str, float]) -> float | None:
        """The axle's offset from the corridor's centre line (> 0: left of it) by the outer front rays
        (each at its own pose), from both side walls when both are seen, else from the one seen; None
        when neither reads a side wall (a reading more than 2 cm off the centre line is a wall's end
        or a wall across, not one)."""
        half = self.corridor / 2
        found = []
        for name, sign in (("front_left", 1.0), ("front_right", -1.0)):
            reading = scan[name]
            if math.isfinite(reading):
                _, y, yaw = self.sensors[name]
                offset = sign * (half - (abs(y) + reading * abs(math.sin(yaw))))
                if abs(offset) < 0.02:
                    found.append(offset)
        return sum(found) / len(found) if found else None

    def _retake_heading(self, pose: Pose, scan: dict[str, float]) -> None:
        """Re-take the corridor's heading from the side walls: where a side ray meets a straight wall
        traces that wall in the odometry frame, whatever the robot's own heading, so the line through
        the points is the corridor's direction as odometry sees it. Odometry's heading drifts (on the
        Playground 2-5° a turn, and more when its simulated time falls behind the wall clock); the
        walls do not. A wall's end, a glint or a wall across breaks the line and starts it again."""
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        for name, points in self.wall_points.items():
            reading = scan[name]
            if math.isinf(reading):
                points.clear()
                continue
            x, y, yaw = self.sensors[name]
            angle = pose.yaw + yaw
            points.append(
                (pose.x + c * x - s * y + reading * math.cos(angle), pose.y + s * x + c * y + reading * math.sin(angle))
            )
            if math.dist(points[0], points[-1]) < WALL_SPAN:
                continue
            direction, residual = line_direction(points)
            if residual > WALL_RESIDUAL:
                last = points[-1]
                points.clear()
                points.append(last)
                continue
            error = wrap_angle(direction - self.heading)
            error = wrap_angle(error - math.pi) if abs(error) > math.pi / 2 else error  # the line has two directions
            if RETAKE_ANGLE < abs(error) < RETAKE_MAX:
                self.heading = wrap_angle(self.heading + error)
                for other in self.wall_points.values():
                    other.clear()
                return

    def _begin_square(self, pair: tuple[str, str], then_turn: bool) -> Status:
        self.robot.drive(0.0, 0.0)
        self.mode, self.squaring, self.square_pair, self.square_then_turn = "square", [], pair, then_turn
        return Status.RUNNING

    def _square(self, pose: Pose) -> Status:
        """Stopped square to a wall (ahead, or behind): read a pair of sensors that both see it for a
        few ticks, re-take the corridor's heading from where they see the wall, then turn away from
        the side (a wall ahead) or drive on (a wall behind).

        Odometry's heading drifts at every turn (on the Playground up to 5°: it samples wheel speeds
        that change in steps); a wall across the corridor is square to it, so where the two sensors
        hit it gives the robot's true angle to it. A few stationary readings are averaged (a real
        sensor's noise), and corrections beyond RETAKE_MAX are not believed.
        """
        scan = self._scan()
        assert scan is not None
        self.squaring.append((scan[self.square_pair[0]], scan[self.square_pair[1]], scan["front_center"]))
        if len(self.squaring) < SQUARING_READINGS:
            self.robot.drive(0.0, 0.0)
            return Status.RUNNING
        readings = [sum(r[i] for r in self.squaring) / len(self.squaring) for i in (0, 1, 2)]
        near = self.params.cell / 2
        if self.square_then_turn and not readings[2] < near:
            self.mode = "forward"  # no wall ahead after all (a glint stopped the robot): go on
            return Status.RUNNING
        if readings[0] < near and readings[1] < near:  # both on the wall across, in this cell
            self._square_to_wall(pose, readings[:2])
        if self.square_then_turn:
            return self._begin_turn(-self.sign, "wall")
        return self._drive_on()

    def _square_to_wall(self, pose: Pose, readings: list[float]) -> None:
        """Set the corridor's heading square to the wall the squaring pair reads at ``readings``."""
        hits = []
        for name, reading in zip(self.square_pair, readings, strict=True):
            x, y, yaw = self.sensors[name]
            hits.append((x + reading * math.cos(yaw), y + reading * math.sin(yaw)))
        (lx, ly), (rx, ry) = hits
        error = math.atan2(lx - rx, ly - ry)  # > 0: the robot is turned left of the wall's normal
        if abs(error) < RETAKE_MAX:
            self.heading = wrap_angle(pose.yaw - error)

    def _begin_turn(self, direction: float, why: str) -> Status:
        self.robot.drive(0.0, 0.0)
        self.speed = 0.0
        self.mode = "turn"
        self.heading = wrap_angle(self.heading + direction * math.pi / 2)
        self.quarter = (self.quarter + (1 if direction > 0 else -1)) % 4
        self.turn_reason = why
        self.turns.append("L" if direction > 0 else "R")
        return Status.RUNNING

    def _turn(self, pose: Pose) -> Status:
        error = wrap_angle(self.heading - pose.yaw) - self.rate * self.latency
        if abs(error) > self.turn_tolerance:
            rate = approach_speed(abs(error), self.params.turn_speed, self.gain, MIN_TURN_RATE, self.ctx.tick_period)
            self.rate = math.copysign(rate, error)
            self.robot.drive(0.0, self.rate)
            self.say("turning, {:.1f} deg to go", math.degrees(error))
            return Status.RUNNING
        self.robot.drive(0.0, 0.0)
        self.rate = 0.0
        scan = self._scan()
        assert scan is not None
        if self.turn_reason == "wall" and scan["front_center"] < self.params.cell / 2:
            # still a wall ahead, in this cell: a dead end; square to that wall, and turn again
            return self._begin_square(FRONT_PAIR, then_turn=True)
        if self.turn_reason == "wall":
            self.anchor = self.position  # stopped by a wall: the axle is in a cell centre
        if all(scan[name] < self.params.cell / 2 for name in REAR_PAIR):
            return self._begin_square(REAR_PAIR, then_turn=False)  # a wall behind, across the corridor
        return self._drive_on()

    def _drive_on(self) -> Status:
        self.mode = "forward"
        self.aligned = True
        self._new_segment()
        return Status.RUNNING
