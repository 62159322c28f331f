"""The built-in behaviours, one family per module (motion, maze, entities, control)."""

from .base import Context, EventLog, FailureCode, RobotBehaviour
from .control import RepeatUntil, ScriptedStub, SimTimeout
from .entities import DeleteEntity, SpawnEntity
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
)

__all__ = ["BUILTIN", "Context", "EventLog", "FailureCode", "RobotBehaviour", "RepeatUntil",
           "ScriptedStub", "SimTimeout", *(cls.__name__ for cls in BUILTIN)]
