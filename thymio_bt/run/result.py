"""What a run produced: its :class:`RunResult` (the run report of DESIGN.md, a contract), how its
tick loop ended (:class:`EndKind`, :class:`Ending`) and the report's verdict on it (:class:`RunOutcome`),
the failing node of a tree that failed (:func:`failing_branch`) and the map it learnt (:func:`learnt_map`).

Example:

>>> import py_trees
>>> root = py_trees.composites.Sequence("course", memory=True, children=[
...     py_trees.behaviours.Success("part 1"), py_trees.behaviours.Failure("part 2")])
>>> root.tick_once()
>>> failing_branch(root)
('course/part 2', <FailureCode.FAILED: 'FAILED'>, 'failure')
>>> learnt_map(root) is None  # no mapping behaviour in this tree
True
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Any

from py_trees.behaviour import Behaviour
from py_trees.blackboard import Blackboard
from py_trees.common import Status

from thymio_bt.behaviours.base import Explains, RobotBehaviour, node_path
from thymio_bt.enums import FailureCode, TextEnum
from thymio_bt.geometry import Pose
from thymio_bt.run.phases import Phase

if TYPE_CHECKING:
    from thymio_bt.maze.cellmap import CellMap


class RunStatus(TextEnum):
    """How a run ended, the report's ``status``: a ``str`` enum, so it is written, compared and
    printed as its text (``result.status == "SUCCESS"`` holds).

    >>> RunStatus.SUCCESS == "SUCCESS", f"{RunStatus.TIMEOUT}", RunStatus("FAILURE")
    (True, 'TIMEOUT', <RunStatus.FAILURE: 'FAILURE'>)
    """

    SUCCESS = "SUCCESS"
    FAILURE = "FAILURE"
    TIMEOUT = "TIMEOUT"


@dataclass(frozen=True)
class GoalReached:
    """Whether base_link entered the maze's goal region during the run, and when (s; None if never)."""

    reached: bool
    t: float | None

    def as_dict(self) -> dict[str, bool | float | None]:
        """As the report writes it: ``{"reached": ..., "t": ...}``."""
        return {"reached": self.reached, "t": self.t}


@dataclass
class RunResult:
    """What a run produced; :meth:`report` gives the run report JSON of DESIGN.md."""

    mission: str
    maze: str
    status: RunStatus
    reason: str | None
    #: a :class:`FailureCode`, or a plugin behaviour's own code (a string)
    code: FailureCode | str | None
    failed_path: str | None
    sim_time: float
    ticks: int
    wall_time: float
    seed: int
    #: the robot's true pose at the end, to the µm and µrad the report writes (None: no robot)
    final_pose: Pose | None
    final_proximity: dict[str, float | None] | None
    events: list[dict[str, Any]]
    collisions: int
    min_clearance: float | None
    trajectory: list[tuple[float, float, float, float]] = field(default_factory=list)
    #: per node path: ticks, successes, failures, running_time (only with ``node_stats=True``)
    node_stats: dict[str, dict[str, float]] | None = None
    #: the mission's ``expect:`` criteria that failed ([] all held); None when it declares none
    expectations: list[str] | None = None
    #: for a maze with a goal region: whether base_link entered it, and when (s); else None
    goal: GoalReached | None = None
    #: each subtree use that ran: when, how long, cells seen (:mod:`thymio_bt.run.phases`)
    phases: list[Phase] = field(default_factory=list)
    #: the maze map the mapping behaviours learnt (:meth:`CellMap.summary`), if a run made one
    maze_map: dict[str, Any] | None = None

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second (inf for a run too quick to time)."""
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf

    @property
    def final_pose_json(self) -> dict[str, float] | None:
        """:attr:`final_pose` as reports and logs write it: ``{x, y, yaw}``, or None."""
        return None if self.final_pose is None else self.final_pose.as_dict()

    def report(self) -> dict[str, Any]:
        """The run report as JSON data: a contract (key order included) that ``--report`` writes as it is."""
        expectations = (
            {}
            if self.expectations is None
            else {"expectations": {"met": not self.expectations, "failed": self.expectations}}
        )
        return {
            "mission": self.mission,
            "maze": self.maze,
            "status": self.status,
            "reason": self.reason,
            "code": self.code,
            "failed_path": self.failed_path,
            "sim_time": round(self.sim_time, 6),
            "ticks": self.ticks,
            "wall_time": round(self.wall_time, 6),
            "real_time_factor": round(self.real_time_factor, 1) if math.isfinite(self.real_time_factor) else None,
            "seed": self.seed,
            "final_pose": self.final_pose_json,
            "final_proximity": self.final_proximity,
            "collisions": self.collisions,
            "min_clearance": None if self.min_clearance is None else round(self.min_clearance, 6),
            "events": self.events,
            **expectations,
            **({} if self.goal is None else {"goal": self.goal.as_dict()}),
            **({"phases": [phase.as_dict() for phase in self.phases]} if self.phases else {}),
            **({"map": self.maze_map} if self.maze_map else {}),
            "trajectory": [[round(v, 6) for v in sample] for sample in self.trajectory],
        }


class EndKind(Enum):
    """What ended a run's tick loop; the report's status follows from it
    (:meth:`thymio_bt.run.runner.Run._end_of_run`)."""

    #: the tree returned SUCCESS or FAILURE
    FINISHED = "finished"
    #: the mission's time limit came first
    TIMEOUT = "timeout"
    #: a signal (Ctrl-C, SIGTERM) noted in the run's :class:`~thymio_bt.run.interrupts.Interrupts`
    INTERRUPTED = "interrupted"
    #: a tick hook raised :class:`~thymio_bt.errors.StopRun`
    STOPPED = "stopped"
    #: the robot could not start, was lost, or the backend raised
    CRASHED = "crashed"

    @property
    def report_status(self) -> RunStatus:
        """The report's status of a run cut short this way: one of the report contract's three, so a
        stopped, crashed or interrupted run is a FAILURE (its ``code`` says which).

        >>> EndKind.TIMEOUT.report_status, EndKind.CRASHED.report_status, EndKind.INTERRUPTED.report_status
        (<RunStatus.TIMEOUT: 'TIMEOUT'>, <RunStatus.FAILURE: 'FAILURE'>, <RunStatus.FAILURE: 'FAILURE'>)
        """
        return RunStatus.TIMEOUT if self is EndKind.TIMEOUT else RunStatus.FAILURE


@dataclass(frozen=True)
class Ending:
    """How the tick loop ended: its kind, and for a run cut short the report's code (``TIMEOUT``,
    ``ROBOT_LOST``...) and, where known then, the reason and the node it ended in; ``forced`` when
    a second signal broke into a tick (the robot is then stopped whatever the tree did)."""

    kind: EndKind
    code: FailureCode | None = None
    reason: str | None = None
    failed_path: str | None = None
    forced: bool = False


@dataclass(frozen=True)
class RunOutcome:
    """The report's status, reason, code and failing node's path (all None but the status on SUCCESS)."""

    status: RunStatus
    reason: str | None = None
    code: FailureCode | str | None = None
    failed_path: str | None = None


def learnt_map(root: Behaviour) -> CellMap | None:
    """The maze map the tree's mapping behaviours keep on the blackboard, at the ``key`` of their
    parameters (:class:`~thymio_bt.behaviours.mapping.MazeMapParams`); None when none made one.
    A tree without them never imported their module (the registry imports a node's module when a
    mission names it), and the run does not import it either."""
    if "thymio_bt.behaviours.mapping" not in sys.modules:
        return None
    from thymio_bt.behaviours.mapping import MazeMapParams
    from thymio_bt.maze.cellmap import CellMap

    for node in root.iterate():
        params = node.params if isinstance(node, RobotBehaviour) else None
        if isinstance(params, MazeMapParams) and Blackboard.exists(params.key):
            found = Blackboard.get(params.key)
            if isinstance(found, CellMap):
                return found
    return None


def _failure(node: Behaviour) -> tuple[FailureCode | str, str] | None:
    """The (code, reason) a node recorded when it failed (:class:`~thymio_bt.behaviours.base.Explains`)."""
    return node.failure if isinstance(node, Explains) else None


def failing_branch(root: Behaviour) -> tuple[str, FailureCode | str, str]:
    """Follow FAILURE down from the root to the node that caused it: (path, code, reason)."""
    node = root
    while True:
        failed = [c for c in node.children if c.status == Status.FAILURE]
        if not failed or _failure(node):
            break
        # prefer the child whose subtree recorded a reason (a condition may hold a stale FAILURE)
        explained = [c for c in failed if any(_failure(n) and n.status == Status.FAILURE for n in c.iterate())]
        node = (explained or failed)[-1]
    failure = _failure(node)
    if failure:
        code, reason = failure
        return node_path(node), code, reason
    return node_path(node), FailureCode.FAILED, node.feedback_message or f"'{node.name}' returned FAILURE"
