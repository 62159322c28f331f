"""What a run log holds, whatever its file format: a header, one record per tick, an end.

The header carries the mission, the maze and the tree itself (each node with a BT.CPP-style
pre-order uid, 1 = the root), so a log is self-contained: a replay, a Groot2 log or a rosbag2
export needs nothing else. Times are simulated seconds, poses base_link in the world frame.

Example:

>>> import py_trees
>>> a, b = py_trees.behaviours.Success("a"), py_trees.behaviours.Failure("b")
>>> root = py_trees.composites.Sequence("course", memory=True, children=[a, b])
>>> [(n["uid"], n["path"], n["kind"], n["parent"]) for n in tree_nodes(root)]
[(1, 'course', 'Sequence', None), (2, 'course/a', 'Success', 1), (3, 'course/b', 'Failure', 1)]
>>> number(0.1234567), number(float("inf")), jsonable({"turn": ("left", 1.5707963), "at": object})
(0.123457, None, {'turn': ['left', 1.570796], 'at': "<class 'object'>"})
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

from py_trees.behaviour import Behaviour

from thymio_bt.behaviours.base import node_path
from thymio_bt.behaviours.flow.node import node_kind
from thymio_bt.enums import STATUS_LETTER as STATUS_LETTER  # a node status as logs store it

if TYPE_CHECKING:
    from thymio_bt.maze import Maze


class TreeNode(TypedDict):
    """One node of the logged tree: ``kind`` is its YAML type (``MoveUntilWall``, ``sequence``...)."""

    uid: int
    path: str
    name: str
    kind: str
    parent: int | None


class LogHeader(TypedDict, total=False):
    """A log's first record: what the run was (mission, rates, seed, start, the maze and the tree),
    and since this field, the ``backend`` kind that ran it (``sim``, ``playground``...), which says
    whether its ``pose`` is the ground truth (older logs lack it). A run writes every key up to
    ``robot``; a log read back may lack any (a Groot2 log has no maze, no seed; a file is outside
    input): readers ``get`` what its reader did not check."""

    version: int
    mission: str
    tick_hz: float
    seed: int
    start: dict[str, float]
    maze: dict[str, Any]
    tree: list[TreeNode]
    backend: str
    #: the backend's latency in seconds (:attr:`thymio_bt.robot.interface.Robot.latency`)
    latency: float
    #: the robot model that ran: name, outline, sensors and range (:func:`thymio_bt.logs.recording.robot_shape`)
    robot: dict[str, Any]
    # --- what a reader adds -------------------------------------------------------------------
    #: where a log read ``--partial`` is damaged: its line (JSON lines), its byte (a Groot2 log)
    damaged_at: int
    #: False: the numbers are not the tree's own (a bag's float32 scans), a what-if replay cannot re-tick them
    exact: bool
    #: what a log without poses lacks, shown with its pictures (a Groot2 log)
    note: str


class TickRecord(TypedDict, total=False):
    """The robot and the tree after one tick (``nodes`` and ``bb`` only where the format keeps them)."""

    t: float
    tick: int
    pose: dict[str, float] | None
    cmd: list[float]
    vel: list[float]
    prox: dict[str, float | None] | None
    running: list[str]
    #: the odometry pose, where it is not ``pose`` (a backend with ground truth and drifting odometry)
    odom: dict[str, float]
    nodes: dict[str, str]
    bb: dict[str, Any]


class LogEnd(TypedDict, total=False):
    """A log's last record: the run's outcome as its report gives it, and its events."""

    status: str
    reason: str | None
    code: str | None
    failed_path: str | None
    sim_time: float
    final_pose: dict[str, float] | None
    collisions: int
    #: what the events were, in the log's file only (a :class:`Recording` keeps them apart)
    events: list[dict[str, Any]]
    #: the map its mapping behaviours learnt (a run's recording, not its log)
    map: dict[str, Any]
    #: a Groot2 log's: the tick of its last record and how many status records it holds
    ticks: int
    records: int


@dataclass
class Recording:
    """What a run (or a log) holds for plots and replays: ``header`` is the log header (mission,
    rates, the tree), ``samples`` one :class:`~thymio_bt.logs.entries.TickRecord` per tick."""

    maze: Maze
    mission: str = ""
    samples: list[TickRecord] = field(default_factory=list)
    events: list[dict[str, Any]] = field(default_factory=list)
    end: LogEnd = field(default_factory=lambda: LogEnd())
    header: LogHeader = field(default_factory=lambda: LogHeader())

    @property
    def final_pose_json(self) -> dict[str, float] | None:
        """base_link's pose when the run ended (None: no robot then, or a log without an end)."""
        return self.end.get("final_pose")


def walk(root: Behaviour) -> Iterator[Behaviour]:
    """The nodes of a py_trees tree in pre-order (BT.CPP's uid order)."""
    yield root
    for child in root.children:
        yield from walk(child)


def tree_nodes(root: Behaviour) -> list[TreeNode]:
    """The tree as the header stores it: pre-order, uids from 1, each with its parent's uid."""
    uids: dict[int, int] = {}
    nodes: list[TreeNode] = []
    for uid, node in enumerate(walk(root), 1):
        uids[id(node)] = uid
        parent = uids.get(id(node.parent)) if node.parent is not None else None
        nodes.append(TreeNode(uid=uid, path=node_path(node), name=node.name, kind=node_kind(node), parent=parent))
    return nodes


def finite(value: Any) -> float | None:
    """``value`` if it is a finite number (not a bool), else None: a log's events are not checked
    when it is read, and a hostile or damaged one may hold anything.

    >>> finite(0.05), finite("north"), finite(float("nan")), finite(True)
    (0.05, None, None, None)
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return None


def checked_events(events: list[Any]) -> list[dict[str, Any]]:
    """The events of a log that can be used: dicts with a finite time ``t``, their ``pose`` kept
    only if it is a pose (finite ``x``, ``y``, ``yaw``), their ``range``, ``angle``, ``x`` and ``y``
    only if finite numbers.

    >>> checked_events([{"t": 1, "pose": {"x": 0, "y": 0, "yaw": "up"}, "range": 0.05}, {"kind": "x"}, 3])
    [{'t': 1.0, 'pose': None, 'range': 0.05}]
    """
    out = []
    for event in events:
        if not isinstance(event, dict) or finite(event.get("t")) is None:
            continue
        event = {**event, "t": finite(event["t"])}
        if "pose" in event:
            pose = event["pose"]
            ok = isinstance(pose, dict) and all(finite(pose.get(k)) is not None for k in ("x", "y", "yaw"))
            event["pose"] = {k: float(pose[k]) for k in ("x", "y", "yaw")} if ok else None
        for key in ("range", "angle", "x", "y"):
            if key in event:
                event[key] = finite(event[key])
        out.append(event)
    return out


def number(value: float | None) -> float | None:
    """A float as logs store it: 6 decimals, None for infinity or no value."""
    if value is None or (isinstance(value, float) and math.isinf(value)):
        return None
    return round(value, 6)


def jsonable(value: Any) -> Any:
    """A blackboard value as JSON: numbers rounded, containers converted, anything else its repr."""
    if isinstance(value, float):
        return number(value)
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    return repr(value)
