"""The built-in nodes: robot behaviours, one family per module (motion, maze, entities, navigation, mapping),
and the composites and decorators that arrange them."""

from .base import Context, EventLog, FailureCode, RobotBehaviour
from .composites import COMPOSITES
from .control import RepeatUntil, ScriptedStub, SimTimeout
from .control_node import ControlNode
from .decorators import DECORATORS
from .entities import DeleteEntity, SpawnEntity
from .mapping import AtTarget, MapWalls, MoveCells, PlanMove, WallMapped
from .maze import ChooseTurn, IsDeadEnd, SideOpen, WallAhead, WallFollow
from .motion import MoveDistance, MoveUntilWall, Stop, TurnAngle, Wait
from .navigation import (FollowWaypoints, GoToPose, ObstacleAhead, SetBlackboard, TurnBack, TurnUntilClear,
                         WaypointsDone)

#: Every built-in robot behaviour, in the order ``thymio-bt behaviours`` lists them.
BUILTIN: tuple[type[RobotBehaviour], ...] = (
    MoveUntilWall, MoveDistance, TurnAngle, Stop, Wait,
    DeleteEntity, SpawnEntity,
    ChooseTurn, WallAhead, SideOpen, IsDeadEnd, WallFollow,
    GoToPose, FollowWaypoints, WaypointsDone, ObstacleAhead, TurnUntilClear, TurnBack, SetBlackboard,
    MapWalls, PlanMove, MoveCells, WallMapped, AtTarget,
)

#: Every built-in composite and decorator.
CONTROL: tuple[type[ControlNode], ...] = (*COMPOSITES, *DECORATORS)

__all__ = ["BUILTIN", "CONTROL", "ControlNode", "Context", "EventLog", "FailureCode", "RobotBehaviour", "RepeatUntil",
           "ScriptedStub", "SimTimeout", *(cls.__name__ for cls in BUILTIN)]
