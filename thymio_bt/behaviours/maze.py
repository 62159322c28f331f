"""Maze behaviours: sensing walls and openings, choosing a turn, and following a wall.

They rely on the geometry of the course's sensors: the ±38° front rays cross a corridor side
0.12 m ahead of the axle, so they see the side walls of the cell ahead but never a wall exactly
beside the robot. A decision is therefore taken when the wall ahead first comes into range, and
an opening is found by its edge and then reached by odometry.

This module holds the conditions (``WallAhead``, ``SideOpen``, ``IsDeadEnd``) and ``ChooseTurn``;
``WallFollow`` lives in :mod:`thymio_bt.behaviours.wall_follow` (its name still imports from here)
and the corridor's geometry in :mod:`thymio_bt.robot.corridor`.

Example::

    >>> from thymio_bt.testing import run_tree, world
    >>> tree = {"parallel": {"policy": "success_on_all", "children": [
    ...     {"MoveUntilWall": {"distance": "1.5cm"}}, {"ChooseTurn": {}}]}}
    >>> result = run_tree(tree, world("L"), seconds=20)
    >>> result.status, [e["decision"] for e in result.events if e["kind"] == "behaviour_end" and "decision" in e]
    (<RunStatus.SUCCESS: 'SUCCESS'>, ['right'])
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any, Literal

from py_trees.blackboard import Client
from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.base import (
    FAILURE,
    RUNNING,
    SUCCESS,
    BehaviourParams,
    ConditionBehaviour,
    Reading,
    RobotBehaviour,
    current_pose,
)
from thymio_bt.behaviours.motion import Turn
from thymio_bt.behaviours.wall_follow import WallFollow, WallFollowParams
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import wrap_angle
from thymio_bt.inputs.fields import AngularSpeed, BlackboardKey, SensedLength
from thymio_bt.robot.corridor import FRONT_SENSORS, RANGE_MAX, Side, side_ray
from thymio_bt.robot.model import WIDEST_RANGE, RobotModel

__all__ = [
    "RANGE_MAX",
    "ChooseTurn",
    "ChooseTurnParams",
    "IsDeadEnd",
    "IsDeadEndParams",
    "LookAround",
    "LookAroundParams",
    "Side",
    "SideOpen",
    "SideOpenParams",
    "WallAhead",
    "WallAheadParams",
    "WallFollow",
    "WallFollowParams",
    "side_ray",
    "turns_decided",
]


class WallAheadParams(BehaviourParams):
    """Is a wall ahead?"""

    distance: SensedLength = Field(RANGE_MAX, gt=0, le=WIDEST_RANGE, description="closer than this counts")
    sensor: Literal["front_center", "front_center_left", "front_center_right"] = "front_center"


class WallAhead(ConditionBehaviour):
    """SUCCESS when the front sensor reads at most ``distance``, FAILURE otherwise.

    Example (YAML)::

        - guard: {condition: {invert: WallAhead}, do: {MoveDistance: {distance: 1}}}
    """

    Params = WallAheadParams

    @classmethod
    def clear_ahead(cls, params: WallAheadParams) -> float:
        """Inverted, it says nothing is within ``distance`` ahead."""
        return params.distance

    def step(self) -> Status:
        """Compare the sensor's reading with ``distance``."""
        scan = self.robot.proximity()
        assert scan is not None
        reading = scan[self.params.sensor]
        self.say(
            "{} reads {} (a wall counts at {:.3f} m or less)",
            self.params.sensor,
            Reading(reading),
            self.params.distance,
        )
        return SUCCESS if reading <= self.params.distance else FAILURE


class SideOpenParams(BehaviourParams):
    """Is there an opening on one side ahead?"""

    side: Side = Field(description="left or right")


class SideOpen(ConditionBehaviour):
    """SUCCESS when the ±38° ray on ``side`` sees nothing (the side of the cell ahead is open).

    Example (YAML)::

        - SideOpen: {side: left}
    """

    Params = SideOpenParams

    def step(self) -> Status:
        """Whether the side ray reads nothing; the feedback (a failure's reason) says what it read."""
        scan = self.robot.proximity()
        assert scan is not None
        ray = side_ray(self.params.side)
        self.say("{} reads {}", ray, Reading(scan[ray]))
        return SUCCESS if math.isinf(scan[ray]) else FAILURE


class IsDeadEndParams(BehaviourParams):
    """Read ChooseTurn's decision."""

    key: BlackboardKey = Field("turn", description="the blackboard key ChooseTurn wrote")


class IsDeadEnd(ConditionBehaviour):
    """SUCCESS when the last ChooseTurn decided ``dead_end``.

    Example (YAML)::

        - IsDeadEnd: {}
    """

    Params = IsDeadEndParams
    needs_robot = False

    def prepare(self) -> None:
        """The decision's key."""
        self.board = self.blackboard("decision", read=(self.params.key,))

    def step(self) -> Status:
        """Read the decision (FAILURE while there is none)."""
        if not self.board.exists(self.params.key):
            self.feedback_message = "no decision yet"
            return FAILURE
        decision = self.board.get(self.params.key)
        self.feedback_message = f"decision: {decision}"
        return SUCCESS if decision == "dead_end" else FAILURE


# ---------------------------------------------------------------- ChooseTurn
#: a side wall must be this much nearer the centre line than its sensor's reach for ChooseTurn to
#: trust that sensor's empty reading as an opening (a robot a few mm off the line still sees it)
REACH_MARGIN = 0.005
#: a reading this near the sensor's range says a wall is there, not how far: the weakest signal a
#: calibration table converts, which a wall further out gives too (Enki's cone, a side wall at a slant)
SATURATED = 0.001
#: stationary front readings LookAround takes of each side (their median counts: one glint does not)
LOOK_READINGS = 3
#: a front reading under this while LookAround turns to a side: a wall there, too near to turn on (m)
LOOK_CLEARANCE = 0.01
SIDES: tuple[Side, Side] = ("left", "right")


def _other(side: Side) -> Side:
    """The side opposite ``side``."""
    return "right" if side == "left" else "left"


def _quarter(side: Side) -> float:
    """A quarter turn towards ``side`` (rad, left positive): the angle TurnAngle turns, and the
    heading LookAround faces from ahead."""
    return math.pi / 2 if side == "left" else -math.pi / 2


def turns_decided(events: Iterable[dict[str, Any]]) -> str:
    """The turns a run's tree decided, as ``LRL...``: ChooseTurn's sure decisions and LookAround's
    corrections of the others, from the run's ``behaviour_end`` events.

    >>> turns_decided([{"kind": "behaviour_end", "name": "ChooseTurn", "decision": "left", "certain": False},
    ...                {"kind": "behaviour_end", "name": "LookAround", "decision": "right"},
    ...                {"kind": "behaviour_end", "name": "ChooseTurn", "decision": "left", "certain": True}])
    'RL'
    """
    return "".join(
        e["decision"][0].upper()
        for e in events
        if e["kind"] == "behaviour_end"
        and e.get("decision") in SIDES
        and (e["name"] == "LookAround" or (e["name"] == "ChooseTurn" and e.get("certain", True)))
    )


def write_decision(board: Client, key: str, decision: Side | Literal["dead_end"], certain: bool) -> None:
    """Write a turn decision as ChooseTurn does: ``key``, ``key_angle`` (the turn TurnAngle makes:
    +pi/2 left, -pi/2 right, 0 at a dead end) and ``key_certain``."""
    board.set(key, decision)
    board.set(f"{key}_angle", 0.0 if decision == "dead_end" else _quarter(decision))
    board.set(f"{key}_certain", certain)


def lateral_reach(model: RobotModel, side: Side) -> float:
    """How far from the centre line ``side``'s outer sensor sees a wall parallel to the heading.

    >>> from thymio_bt.robot.model import COURSE, ENKI
    >>> round(lateral_reach(COURSE, "left"), 4), round(lateral_reach(ENKI, "right"), 4)
    (0.1093, 0.1385)
    """
    sensor = model.sensor(side_ray(side))
    return abs(sensor.y) + model.range_max * abs(math.sin(sensor.yaw))


class ChooseTurnParams(BehaviourParams):
    """Decide the turn at the next wall."""

    key: BlackboardKey = Field(
        "turn",
        description="blackboard key for the decision; the angle goes to KEY_angle, whether it is sure to KEY_certain",
    )
    prefer: Side = Field("left", description="the side chosen when both sides are open")


class ChooseTurn(RobotBehaviour):
    """Decide left / right / dead end the moment the wall ahead first comes into range.

    Run it beside MoveUntilWall (in a parallel): it waits until ``front_center`` first reads a
    finite range, then reads the outer rays, which at that moment cross the sides of the last cell.
    It writes ``turn`` (``left``, ``right`` or ``dead_end``), ``turn_angle`` (+pi/2, -pi/2, 0) and
    ``turn_certain``. A side whose ray meets a side wall is closed; an empty reading is an opening
    only where a wall there would be within the ray's reach: the ray met that side's wall on the
    way, or the other side's wall, seen now, is nearer than the corridor's width measured earlier
    minus that reach (a reading within 1 mm of the sensor's range measures no width: a wall further
    out reads so too). Where not (a corridor wider than the rays reach, a leg that starts with the wall
    ahead close, so the rays meet it) the decision is the side that may be open, and
    ``turn_certain`` is false: LookAround, after the robot stops, turns to look.

    Example (YAML)::

        - parallel:
            policy: success_on_all
            children:
              - MoveUntilWall: {distance: 1.5cm}
              - ChooseTurn: {}
        - TurnAngle: {angle: bb:turn_angle}
    """

    Params = ChooseTurnParams
    fails_on_collision = False

    def prepare(self) -> None:
        """The decision's keys; no width measured yet."""
        key = self.params.key
        self.board = self.blackboard("decision", write=(key, f"{key}_angle", f"{key}_certain"))
        #: the corridor's width between its side walls, last measured with both in view (kept from leg to leg)
        self.width: float | None = None

    def start(self) -> None:
        """A new leg: the side walls are not seen yet. The robot's sensor poses and reach."""
        model = self.robot.model
        self.reach = {side: lateral_reach(model, side) for side in SIDES}
        front = model.sensor("front_center").x
        #: per side: the ray's x + reading * cos(yaw) beyond front.x + ahead - 1 cm met the wall ahead;
        #: |y| + reading * |sin(yaw)| is how far from the centre line it met a side wall
        self.rays = {
            side: (ray.x, math.cos(ray.yaw), front, abs(ray.y), abs(math.sin(ray.yaw)))
            for side, ray in ((side, model.sensor(side_ray(side))) for side in SIDES)
        }
        self.edge = model.range_max - SATURATED
        self.beside: dict[str, float | None] = {side: None for side in SIDES}

    def step(self) -> Status:
        """Wait for the wall ahead, watching the side walls, then decide and write the decision."""
        scan = self.robot.proximity()
        assert scan is not None
        ahead, left, right = scan["front_center"], scan["front_left"], scan["front_right"]
        # each side in locals while waiting (a tick's two dicts cost more than the rays' offsets)
        off_left, off_right = self._offset(left, "left", ahead), self._offset(right, "right", ahead)
        # how far the side walls are, where the readings say it (not at the edge of the range)
        edge = self.edge
        seen_left = off_left if left < edge else None
        seen_right = off_right if right < edge else None
        if seen_left is not None and seen_right is not None:
            self.width = seen_left + seen_right
        if math.isinf(ahead):
            if off_left is not None:
                self.beside["left"] = off_left
            if off_right is not None:
                self.beside["right"] = off_right
            self.feedback_message = "waiting for the wall ahead to come into range"
            return RUNNING
        offsets: dict[Side, float | None] = {"left": off_left, "right": off_right}
        measured: dict[Side, float | None] = {"left": seen_left, "right": seen_right}
        prefer: Side = self.params.prefer
        # a side is closed where its ray met a side wall; a ray that met the wall ahead tells nothing
        candidates = [s for s in (prefer, _other(prefer)) if offsets[s] is None]
        chosen = candidates[0] if candidates else None
        decision = chosen or "dead_end"
        certain = chosen is None or (math.isinf(scan[side_ray(chosen)]) and self._surely_open(chosen, measured))
        write_decision(self.board, self.params.key, decision, certain)
        self.extra = {"decision": decision, "certain": certain}
        self.feedback_message = f"decided {decision}" + ("" if certain else " (not sure: look)")
        return SUCCESS

    def _offset(self, reading: float, side: Side, ahead: float) -> float | None:
        """How far from the centre line the ray on ``side`` met a side wall; None when it met none
        (or met the wall ahead: within 1 cm of where ``front_center`` meets it)."""
        if math.isinf(reading):
            return None
        x, cos, front, y, sin = self.rays[side]
        if x + reading * cos >= front + ahead - 0.01:
            return None
        return y + reading * sin

    def _surely_open(self, side: Side, measured: dict[Side, float | None]) -> bool:
        """Whether ``side``'s empty reading is an opening: a wall there would be within its ray's
        reach. Where that side's wall was, the ray met it on the way; else the other side's wall,
        measured now, and the corridor's width measured earlier (one maze, one grid) say it."""
        seen, other = self.beside[side], measured[_other(side)]
        if seen is None and other is not None and self.width is not None:
            seen = self.width - other
        return seen is not None and seen <= self.reach[side] - REACH_MARGIN


# ---------------------------------------------------------------- LookAround
class LookAroundParams(BehaviourParams):
    """Make sure of ChooseTurn's decision by looking."""

    key: BlackboardKey = Field("turn", description="the blackboard key ChooseTurn wrote (and KEY_angle, KEY_certain)")
    speed: AngularSpeed = Field(1.0, gt=0, le=4.3, description="fastest turn rate")


class LookAround(RobotBehaviour):
    """Where ChooseTurn was not sure, turn to look at each side and correct its decision.

    Run it after the approach, stopped before the wall ahead. When ``turn_certain`` is true it
    succeeds at once without moving. Otherwise it turns a quarter towards the side ChooseTurn
    chose and reads ``front_center`` (the median of three stationary readings: a wall there reads,
    an opening does not); if that side is closed it turns to look at the other one; it ends facing
    the way it came, having rewritten ``turn``, ``turn_angle`` and ``turn_certain``. A robot off
    its corridor's centre line may meet a side wall before it faces it: a front reading under 1 cm
    as it turns to a side stops the turn, that side closed.

    Example (YAML)::

        - parallel: {policy: success_on_all, children: [{MoveUntilWall: {distance: 5cm}}, ChooseTurn]}
        - LookAround
        - TurnAngle: {angle: bb:turn_angle}
    """

    Params = LookAroundParams
    #: it stops the robot itself if halted mid-turn: a sure decision must send no command at all
    #: (a noisy wheel errs anew with every command, so one more would change the rest of the run)
    moves = False

    def prepare(self) -> None:
        """The decision's keys."""
        key = self.params.key
        self.keys = (key, f"{key}_angle", f"{key}_certain")
        self.board = self.blackboard("decision", write=self.keys)

    def start(self) -> None:
        """Read the decision: which side to look at first, if any; the heading that is ahead."""
        self.turn: Turn | None = None
        self.target: Side | None = None  # what the turn under way faces
        self.facing: Side | None = None  # the side being read, the turn to it done
        self.readings: list[float] = []
        self.open: dict[str, bool] = {}
        self.ahead = current_pose(self.robot).yaw if self.robot.exists() else 0.0
        key, _, certain_key = self.keys
        self.first: Side | None = None
        if self.board.exists(key):
            certain = self.board.get(certain_key) if self.board.exists(certain_key) else True
            decision = self.board.get(key)
            self.first = decision if decision in SIDES and not certain else None
        #: the headings still to face: a side, or ahead (None)
        self.looks: list[Side | None] = [self.first] if self.first else []

    def step(self) -> Status:
        """Turn, look, and decide once back facing the way the robot came."""
        if not self.board.exists(self.keys[0]):
            return self.fail(FailureCode.INVALID_INPUT, f"no decision '{self.keys[0]}' to check: run ChooseTurn first")
        if self.first is None:
            self.feedback_message = "ChooseTurn was sure: nothing to look at"
            return SUCCESS
        scan = self.robot.proximity()
        assert scan is not None
        ahead = scan["front_center"]
        if self.facing is not None:  # stopped, facing a side: read it
            self.readings.append(ahead)
            if len(self.readings) < LOOK_READINGS:
                return RUNNING
            self._seen(self.facing, sorted(self.readings)[LOOK_READINGS // 2])
        if self.turn is None:
            if not self.looks:
                return self._decide()
            self.target = self.looks.pop(0)
            turned = wrap_angle(current_pose(self.robot).yaw - self.ahead)
            facing = 0.0 if self.target is None else _quarter(self.target)
            self.turn = Turn.begin(self, facing - turned, self.params.speed, 0.0005)
        elif self.target is not None and min(scan[name] for name in FRONT_SENSORS) < LOOK_CLEARANCE:
            self.robot.drive(0.0, 0.0)  # turning on would touch that side's wall
            self.turn = None
            self._seen(self.target, 0.0)
            return RUNNING
        if not self.turn.drive(self.turn.error()):
            self.say("turning to look {}", self.target or "ahead")
            return RUNNING
        self.turn, self.facing = None, self.target
        return RUNNING if self.facing is not None or self.looks else self._decide()

    def terminate(self, new_status: Status) -> None:
        """Stop the robot if it ends (or is halted) mid-turn, then log the end."""
        if self.status == RUNNING and self.turn is not None and self.robot.exists():
            self.robot.drive(0.0, 0.0)
        super().terminate(new_status)

    def _seen(self, side: Side, reading: float) -> None:
        """Record what ``side`` looks like and plan the next turns: to the other side if the first
        is closed, then back to face ahead."""
        self.open[side], self.readings, self.facing = math.isinf(reading), [], None
        self.looks = [_other(side), None] if side == self.first and not self.open[side] else [None]

    def _decide(self) -> Status:
        """Write the corrected decision."""
        assert self.first is not None
        other = _other(self.first)
        decision = self.first if self.open.get(self.first) else other if self.open.get(other) else "dead_end"
        write_decision(self.board, self.params.key, decision, True)
        self.extra = {"decision": decision, "looked": sorted(self.open)}
        self.feedback_message = f"looked: {decision}"
        return SUCCESS
