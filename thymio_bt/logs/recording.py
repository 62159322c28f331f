"""Record a run tick by tick: in memory for plots and replays, and in a log of any format.

The :class:`Recorder` is an ``on_tick`` hook: each tick it makes one
:class:`~thymio_bt.logs.entries.TickRecord` (time, pose, command, velocity, proximity, running
nodes, the status of every node, blackboard values that changed), keeps it for plots, and hands it
to the log writer that ``--log FILE``'s suffix picks (:mod:`thymio_bt.logs`). ``thymio-bt replay``
redraws plots from a log without re-running.

Example (a log written, then read back as it was recorded):

>>> import tempfile
>>> from thymio_bt.logs import read_log
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> with tempfile.TemporaryDirectory() as folder:
...     recorder = Recorder(log_path=f"{folder}/run.jsonl")
...     recording = recorder.finish(Run(load_mission("square")).run(on_tick=recorder))
...     logged = read_log(f"{folder}/run.jsonl")
>>> len(recording.samples), recording.end["status"], recording.final_pose_json
(228, <RunStatus.SUCCESS: 'SUCCESS'>, {'x': 0.45, 'y': 0.45, 'yaw': 0.0})
>>> logged.samples == recording.samples, logged.end == recording.end
(True, True)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import py_trees

from thymio_bt.behaviours.base import node_path
from thymio_bt.errors import UserError
from thymio_bt.logs.entries import LogHeader, Recording
from thymio_bt.maze import Maze

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from thymio_bt.logs import LogWriter
    from thymio_bt.logs.entries import LogEnd, TickRecord
    from thymio_bt.plan.model import Mission
    from thymio_bt.robot.interface import Backend
    from thymio_bt.robot.model import RobotModel


class WatchedRun(Protocol):
    """What a tick hook (the :class:`Recorder`, Groot2's monitor) reads of the run it watches. A
    :class:`~thymio_bt.run.runner.Run` is one; the hooks, below the run in the layers, name only these."""

    @property
    def mission(self) -> Mission:
        """The mission run."""
        ...

    @property
    def seed(self) -> int:
        """The run's seed."""
        ...

    @property
    def backend(self) -> Backend:
        """The robot it drives."""
        ...

    @property
    def ticks(self) -> int:
        """The ticks done."""
        ...

    @property
    def root(self) -> Behaviour:
        """The tree ticked."""
        ...

    def shown_tree(self) -> Behaviour:
        """The tree as the mission wrote it (the tree ticked, or the one it wraps)."""
        ...


class EndedRun(Protocol):
    """What :meth:`Recorder.finish` reads of a run's result. A :class:`~thymio_bt.run.result.RunResult`
    is one."""

    @property
    def mission(self) -> str:
        """The mission's name."""
        ...

    @property
    def status(self) -> str:
        """How the run ended (SUCCESS, FAILURE, ...)."""
        ...

    @property
    def reason(self) -> str | None:
        """Why, in words."""
        ...

    @property
    def code(self) -> str | None:
        """Why, as a failure code."""
        ...

    @property
    def failed_path(self) -> str | None:
        """The node that failed."""
        ...

    @property
    def sim_time(self) -> float:
        """Its simulated seconds."""
        ...

    @property
    def collisions(self) -> int:
        """Its collisions."""
        ...

    @property
    def events(self) -> list[dict[str, Any]]:
        """Its events."""
        ...

    @property
    def maze_map(self) -> dict[str, Any] | None:
        """The map its mapping behaviours learnt, if any."""
        ...

    @property
    def final_pose_json(self) -> dict[str, float] | None:
        """base_link's pose at the end, as a log writes it."""
        ...


class Recorder:
    """An ``on_tick`` hook for :meth:`thymio_bt.run.runner.Run.run` that records every tick."""

    def __init__(self, log_path: str | Path | None = None, keep: bool = True, statuses: bool = False) -> None:
        """``log_path``: the log to write; ``keep``: keep the records in memory too; ``statuses``:
        with every node's status and the blackboard's changes even without a log (a log has them), for
        comparing runs and for the run's page."""
        self.keep = keep
        self.statuses = statuses
        self.samples: list[TickRecord] = []
        self._path = Path(log_path) if log_path else None
        self._writer: LogWriter | None = None
        self._blackboard: dict[str, Any] = {}
        self._run: WatchedRun | None = None
        self._header = LogHeader()

    def begin(self, run: WatchedRun) -> None:
        """Open the log and write its header for ``run`` before its first tick, so that a run whose
        first tick never ends (a plugin stuck in it, then Ctrl-C) still leaves a whole log; the
        first tick does it otherwise. Once only."""
        if self._run is None:
            self._open(run)

    def _open(self, run: WatchedRun) -> None:
        from thymio_bt.logs.entries import tree_nodes

        self._run = run
        mission = run.mission
        header = LogHeader(
            version=2,
            mission=mission.name,
            tick_hz=mission.tick_hz,
            seed=run.seed,
            start=mission.start.as_dict(),
            maze=mission.maze.to_yaml_dict(),
            tree=tree_nodes(run.shown_tree()),
            backend=backend_name(run.backend, mission.backend),
            latency=run.backend.latency,
            robot=robot_shape(run.backend.model),
        )
        self._header = header.copy()
        if self._path is not None:
            from thymio_bt.logs import open_writer

            self._writer = open_writer(self._path)
            self._writer.header(header)

    def __call__(self, run: WatchedRun) -> None:
        """Record the tick ``run`` just made (the first call writes the log's header); a log that cannot
        be written any more ends the run with :class:`~thymio_bt.errors.StopRun`."""
        from thymio_bt.logs.entries import STATUS_LETTER, jsonable

        if self._run is None:
            self._open(run)
        backend = run.backend
        pose = backend.true_pose()
        scan = backend.proximity()
        cmd, vel = backend.command(), backend.velocity()
        # the robot's numbers exactly as the tree had them: a what-if replay (run.whatif) feeds them back
        record: TickRecord = {
            "t": round(backend.time(), 6),
            "tick": run.ticks,
            "pose": None if pose is None else pose.as_dict(),
            "cmd": [float(cmd.linear), float(cmd.angular)],
            "vel": [float(vel.linear), float(vel.angular)],
            "prox": None if scan is None else {k: None if math.isinf(v) else float(v) for k, v in scan.items()},
            "running": [n.name for n in _running_leaves(run.shown_tree())],
        }
        odom = backend.pose()
        if odom is not None and odom != pose:  # odometry that is not the pose logged: what the tree read
            record["odom"] = odom.as_dict()
        if self._writer is not None or self.statuses:
            record["nodes"] = {node_path(n): STATUS_LETTER[n.status.name] for n in run.shown_tree().iterate()}
            storage = py_trees.blackboard.Blackboard.storage
            changed = {k: jsonable(v) for k, v in storage.items() if self._blackboard.get(k, object()) != v}
            self._blackboard = dict(storage)
            if changed:
                record["bb"] = changed
        if self._writer is not None:
            try:
                self._writer.tick(record)
            except OSError as exc:  # a full disk, a file size limit: end the run, keep the report
                from thymio_bt.errors import StopRun

                self._abandon()
                raise StopRun(f"cannot write the log {self._path}: {exc.strerror or exc}") from None
        if self.keep:
            self.samples.append(record.copy())

    def finish(self, result: EndedRun) -> Recording:
        """Write the log's end and close it; return the in-memory recording."""
        end: LogEnd = {
            "status": result.status,
            "reason": result.reason,
            "code": result.code,
            "failed_path": result.failed_path,
            "sim_time": round(result.sim_time, 6),
            "final_pose": result.final_pose_json,
            "collisions": result.collisions,
        }
        if self._writer is not None:
            try:
                self._writer.end({**end, "events": result.events})
                self._writer.close()
            except OSError as exc:
                self._abandon()
                raise UserError(f"cannot write the end of the log {self._path}: {exc.strerror or exc}") from None
            self._writer = None
        maze = self._run.mission.maze if self._run is not None else Maze()
        return Recording(
            maze=maze,
            mission=result.mission,
            samples=self.samples,
            events=result.events,
            end={**end, "map": result.maze_map} if result.maze_map else end,
            header=self._header,
        )

    def _abandon(self) -> None:
        """Close a log that can no longer be written (what reached the disk stays readable)."""
        writer, self._writer = self._writer, None
        try:
            if writer is not None:
                writer.close()
        except OSError:
            pass


def robot_shape(model: RobotModel) -> dict[str, Any]:
    """The robot model that ran, as the log header keeps it for the run's page: its ``name``, its
    ``hull`` outline and its ``sensors`` (``[name, x, y, yaw]``, base_link metres and radians), and
    the sensors' ``range`` (m)."""
    return {
        "name": model.name,
        "hull": [[x, y] for x, y in model.hull],
        "sensors": [[s.name, s.x, s.y, s.yaw] for s in model.sensors],
        "range": model.range_max,
    }


def backend_name(backend: object, default: str) -> str:
    """The backend kind (``sim``, ``playground``, ``ros2``...) whose package made ``backend``, else
    ``default`` (the mission's): ``run --backend`` does not change the mission's."""
    from thymio_bt.backends import backend_kinds

    module = type(backend).__module__
    kinds = [(k.name, k.factory.partition(":")[0]) for k in backend_kinds().values() if isinstance(k.factory, str)]
    for name, factory in kinds:
        if module == factory:
            return name
    for name, factory in kinds:
        if module.startswith(factory.rpartition(".")[0] + "."):
            return name
    return default


def _running_leaves(root: Behaviour) -> list[Behaviour]:
    """The leaves RUNNING after the tick (a tree's running behaviours)."""
    return [n for n in root.iterate() if not n.children and n.status.name == "RUNNING"]
