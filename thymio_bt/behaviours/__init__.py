"""The built-in nodes: robot behaviours, one family per module (motion, maze, entities, navigation, mapping),
and the composites and decorators that arrange them (:mod:`.flow`), re-exported here."""

from thymio_bt.behaviours.base import Context, EventLog, FailureCode, RobotBehaviour
from thymio_bt.behaviours.entities import DeleteEntity, SpawnEntity
from thymio_bt.behaviours.flow.composites import COMPOSITES
from thymio_bt.behaviours.flow.decorators import DECORATORS
from thymio_bt.behaviours.flow.node import ControlNode
from thymio_bt.behaviours.flow.primitives import RepeatUntil, ScriptedStub, SimTimeout
from thymio_bt.behaviours.mapping import AtTarget, MapWalls, MoveCells, PlanMove, WallMapped
from thymio_bt.behaviours.maze import ChooseTurn, IsDeadEnd, LookAround, SideOpen, WallAhead, WallFollow
from thymio_bt.behaviours.motion import MoveDistance, MoveUntilWall, Stop, TurnAngle, Wait
from thymio_bt.behaviours.navigation import (
    FollowWaypoints,
    GoToPose,
    ObstacleAhead,
    SetBlackboard,
    TurnBack,
    TurnUntilClear,
    WaypointsDone,
)
from thymio_bt.behaviours.places import InRegion, OutsideMaze

#: Every built-in robot behaviour, in the order ``thymio-bt behaviours`` lists them.
BUILTIN: tuple[type[RobotBehaviour], ...] = (
    MoveUntilWall,
    MoveDistance,
    TurnAngle,
    Stop,
    Wait,
    DeleteEntity,
    SpawnEntity,
    ChooseTurn,
    LookAround,
    WallAhead,
    SideOpen,
    IsDeadEnd,
    WallFollow,
    GoToPose,
    FollowWaypoints,
    WaypointsDone,
    ObstacleAhead,
    TurnUntilClear,
    TurnBack,
    SetBlackboard,
    MapWalls,
    PlanMove,
    MoveCells,
    WallMapped,
    AtTarget,
    OutsideMaze,
    InRegion,
)

#: Every built-in composite and decorator.
CONTROL: tuple[type[ControlNode], ...] = (*COMPOSITES, *DECORATORS)

__all__ = [
    "BUILTIN",
    "CONTROL",
    "ControlNode",
    "Context",
    "EventLog",
    "FailureCode",
    "RobotBehaviour",
    "RepeatUntil",
    "ScriptedStub",
    "SimTimeout",
    *(cls.__name__ for cls in BUILTIN),
]
