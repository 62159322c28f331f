"""The built-in nodes: robot behaviours, one family per module (motion, maze, entities, navigation, mapping),
and the composites and decorators that arrange them (:mod:`.flow`).

The families are imported when first asked for: ``from thymio_bt.behaviours import WallFollow`` still
works, but importing this package (as the base of every node does) loads none of them, so a run
creates only its own nodes' classes (the registry finds each in :mod:`thymio_bt.plan.builtin_nodes`).

    >>> from thymio_bt.behaviours import WallFollow
    >>> WallFollow.__module__
    'thymio_bt.behaviours.wall_follow'
"""

from __future__ import annotations

import importlib
from typing import Any

from thymio_bt.behaviours.base import Context, EventLog, RobotBehaviour
from thymio_bt.behaviours.flow.node import ControlNode
from thymio_bt.behaviours.flow.primitives import RepeatUntil, ScriptedStub, SimTimeout
from thymio_bt.enums import FailureCode

#: the robot behaviours' family modules, where :func:`__getattr__` looks for a name
FAMILIES = ("motion", "entities", "maze", "wall_follow", "navigation", "mapping", "move_cells", "places")


def __getattr__(name: str) -> Any:
    """A robot behaviour class of one of the families, its module imported now (PEP 562)."""
    for family in FAMILIES:
        module = importlib.import_module(f"{__name__}.{family}")
        cls = getattr(module, name, None)
        if isinstance(cls, type) and issubclass(cls, RobotBehaviour) and cls.__module__ == module.__name__:
            return cls
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ControlNode",
    "Context",
    "EventLog",
    "FailureCode",
    "RobotBehaviour",
    "RepeatUntil",
    "ScriptedStub",
    "SimTimeout",
    "MoveUntilWall",
    "MoveDistance",
    "TurnAngle",
    "Stop",
    "Wait",
    "DeleteEntity",
    "SpawnEntity",
    "ChooseTurn",
    "LookAround",
    "WallAhead",
    "SideOpen",
    "IsDeadEnd",
    "WallFollow",
    "GoToPose",
    "FollowWaypoints",
    "WaypointsDone",
    "ObstacleAhead",
    "TurnUntilClear",
    "TurnBack",
    "SetBlackboard",
    "MapWalls",
    "PlanMove",
    "MoveCells",
    "WallMapped",
    "AtTarget",
    "OutsideMaze",
    "InRegion",
]
