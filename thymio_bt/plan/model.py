"""The validated form of a mission: plain data, no py_trees objects, no robot.

Loading a mission produces a :class:`Mission` whose ``tree`` is a :class:`NodePlan`; only
:func:`thymio_bt.mission.build.build_tree` turns it into py_trees behaviours bound to a robot.
So validating a file never leaves state behind (py_trees' blackboard is global).

Example::

    >>> from thymio_bt.mission.loader import load_mission
    >>> mission = load_mission("square")
    >>> mission.tree.kind, len(list(mission.tree.walk())), mission.start
    ('repeat', 4, Pose(x=0.45, y=0.45, yaw=0.0))
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze
from thymio_bt.plan.expect import Expect
from thymio_bt.robot.model import SimSensorModel
from thymio_bt.robot.noise import NoiseConfig

if TYPE_CHECKING:  # the registry imports every behaviour, which a plan never needs to
    from thymio_bt.plan.registry import Registry

MAX_DEPTH = 64
#: Most nodes one mission may expand to (subtrees calling subtrees twice each multiply).
MAX_NODES = 20_000


@dataclass
class NodePlan:
    """One node of the tree to build.

    ``kind`` is ``behaviour``, a composite (``sequence``, ``reactive_sequence``, ``selector``,
    ``reactive_selector``, ``parallel``) or a decorator (``repeat``, ``retry``, ``timeout``, ...).
    """

    kind: str
    name: str
    path: str
    behaviour: str | None = None
    params: BaseModel | None = None
    blackboard_refs: dict[str, str] = field(default_factory=dict)
    children: list[NodePlan] = field(default_factory=list)
    where: tuple[str, int, int] = ("", 0, 0)
    #: the subtree (``subtrees:``) this node is the root of an instance of, or None
    subtree: str | None = None

    def walk(self) -> Iterator[NodePlan]:
        """This node and every node below it, in pre-order (the order py_trees ticks them)."""
        yield self
        for child in self.children:
            yield from child.walk()


@dataclass
class Mission:
    """A loaded, validated mission."""

    name: str
    description: str
    file: Path
    maze: Maze
    maze_file: Path | None
    start: Pose
    tick_hz: float
    time_limit: float
    seed: int
    noise: NoiseConfig
    parameters: dict[str, Any]
    #: how the simulator makes the readings: "metres" (the course's exact rays), "raw" (a real
    #: Thymio's readings, see thymio_bt.sensor_tables) or "cone" (Enki's three-ray cones)
    sensor_model: SimSensorModel
    tree: NodePlan
    #: the node kinds the mission was planned with (its plugins' included)
    registry: Registry
    #: the robot model's name (:data:`thymio_bt.robot.model.ROBOTS`) or profile file, None when the
    #: mission names none (then :func:`thymio_bt.backends.robot_for` picks the backend's own)
    robot: str | None = None
    #: the backend kind's name (:mod:`thymio_bt.backends`) and its settings, as written
    backend: str = "sim"
    backend_options: dict[str, Any] = field(default_factory=dict)
    #: where the start pose was given (file, line, column), for error messages
    start_where: tuple[str, int, int] = ("", 0, 0)
    #: every file the mission was read from: itself, its includes, its maze and its .py plugins
    sources: tuple[Path, ...] = ()
    #: each included file and where it was included (file, line, column)
    included_at: dict[Path, tuple[str, int, int]] = field(default_factory=dict)
    #: what counts as success besides the tree's status (:mod:`thymio_bt.plan.expect`), or None
    expect: Expect | None = None
