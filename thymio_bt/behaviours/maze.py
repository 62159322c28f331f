"""Maze behaviours: sensing walls and openings, choosing a turn, and following a wall.

They rely on the geometry of the course's sensors: the ±38° front rays cross a corridor side
0.12 m ahead of the axle, so they see the side walls of the cell ahead but never a wall exactly
beside the robot. A decision is therefore taken when the wall ahead first comes into range, and
an opening is found by its edge and then reached by odometry.

This module holds the conditions (``WallAhead``, ``SideOpen``, ``IsDeadEnd``) and ``ChooseTurn``;
``WallFollow`` lives in :mod:`thymio_bt.behaviours.wall_follow` (its name still imports from here)
and the corridor's geometry in :mod:`thymio_bt.behaviours.corridor`.

Example::

    >>> from thymio_bt.testing import run_tree, world
    >>> tree = {"parallel": {"policy": "success_on_all", "children": [
    ...     {"MoveUntilWall": {"distance": "1.5cm"}}, {"ChooseTurn": {}}]}}
    >>> result = run_tree(tree, world("L"), seconds=20)
    >>> result.status, [e["decision"] for e in result.events if e["kind"] == "behaviour_end" and "decision" in e]
    ('SUCCESS', ['right'])
"""

from __future__ import annotations

import math
from typing import Literal

from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.base import BehaviourParams, ConditionBehaviour, Context, RobotBehaviour
from thymio_bt.behaviours.corridor import RANGE_MAX, Side, side_ray
from thymio_bt.behaviours.wall_follow import WallFollow, WallFollowParams
from thymio_bt.inputs.fields import SensedLength
from thymio_bt.robot.model import WIDEST_RANGE

__all__ = [
    "RANGE_MAX",
    "ChooseTurn",
    "ChooseTurnParams",
    "IsDeadEnd",
    "IsDeadEndParams",
    "Side",
    "SideOpen",
    "SideOpenParams",
    "WallAhead",
    "WallAheadParams",
    "WallFollow",
    "WallFollowParams",
    "side_ray",
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

    def step(self) -> Status:
        """Compare the sensor's reading with ``distance``."""
        scan = self.robot.proximity()
        assert scan is not None
        reading = scan[self.params.sensor]
        self.say("{} reads {:.4f}", self.params.sensor, reading)
        return Status.SUCCESS if reading <= self.params.distance else Status.FAILURE


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
        """Whether the side ray reads nothing."""
        scan = self.robot.proximity()
        assert scan is not None
        return Status.SUCCESS if math.isinf(scan[side_ray(self.params.side)]) else Status.FAILURE


class IsDeadEndParams(BehaviourParams):
    """Read ChooseTurn's decision."""

    key: str = Field("turn", description="the blackboard key ChooseTurn wrote")


class IsDeadEnd(ConditionBehaviour):
    """SUCCESS when the last ChooseTurn decided ``dead_end``.

    Example (YAML)::

        - IsDeadEnd: {}
    """

    Params = IsDeadEndParams
    needs_robot = False

    def __init__(
        self, name: str, params: IsDeadEndParams, ctx: Context, blackboard_refs: dict[str, str] | None = None
    ) -> None:
        super().__init__(name, params, ctx, blackboard_refs)
        self.board = self.blackboard("decision", read=(params.key,))

    def step(self) -> Status:
        """Read the decision (FAILURE while there is none)."""
        if not self.board.exists(self.params.key):
            self.feedback_message = "no decision yet"
            return Status.FAILURE
        decision = self.board.get(self.params.key)
        self.feedback_message = f"decision: {decision}"
        return Status.SUCCESS if decision == "dead_end" else Status.FAILURE


# ---------------------------------------------------------------- ChooseTurn
class ChooseTurnParams(BehaviourParams):
    """Decide the turn at the next wall."""

    key: str = Field("turn", description="blackboard key for the decision; the angle goes to KEY_angle")
    prefer: Side = Field("left", description="the side chosen when both sides are open")


class ChooseTurn(RobotBehaviour):
    """Decide left / right / dead end the moment the wall ahead first comes into range.

    Run it beside MoveUntilWall (in a parallel): it waits until ``front_center`` first reads a
    finite range, then reads the ±38° rays, which at that moment cross the sides of the last cell.
    It writes ``turn`` (``left``, ``right`` or ``dead_end``) and ``turn_angle`` (+pi/2, -pi/2, 0).

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

    def __init__(
        self, name: str, params: ChooseTurnParams, ctx: Context, blackboard_refs: dict[str, str] | None = None
    ) -> None:
        super().__init__(name, params, ctx, blackboard_refs)
        self.board = self.blackboard("decision", write=(params.key, f"{params.key}_angle"))

    def step(self) -> Status:
        """Wait for the wall ahead, then decide from the outer rays and write the decision."""
        scan = self.robot.proximity()
        assert scan is not None
        if math.isinf(scan["front_center"]):
            self.feedback_message = "waiting for the wall ahead to come into range"
            return Status.RUNNING
        left_open, right_open = math.isinf(scan["front_left"]), math.isinf(scan["front_right"])
        if left_open and right_open:
            decision = self.params.prefer
        elif left_open:
            decision = "left"
        elif right_open:
            decision = "right"
        else:
            decision = "dead_end"
        angle = {"left": math.pi / 2, "right": -math.pi / 2, "dead_end": 0.0}[decision]
        self.board.set(self.params.key, decision)
        self.board.set(f"{self.params.key}_angle", angle)
        self.extra = {"decision": decision}
        self.feedback_message = f"decided {decision}"
        return Status.SUCCESS
