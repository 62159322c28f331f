"""Record a run tick by tick, in memory and optionally as a JSON-lines log, and read logs back.

Each log line is one JSON object: a ``header`` (mission, maze walls, rates), then one ``tick`` per
tick (time, pose, command, velocity, proximity, the status of every tree node, blackboard values
that changed), then an ``end`` with the outcome and events. Lines are flushed as the run goes, so a
crash still leaves a readable log. ``thymio-bt replay`` redraws plots from a log without re-running.

Example::

    recorder = Recorder(log_path="run.jsonl")
    result = run.run(on_tick=recorder)
    recorder.finish(result)
    recording = read_log("run.jsonl")
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import py_trees

from .errors import Problem, UserError
from .behaviours.base import node_path
from .maze import Maze

_STATUS = {"SUCCESS": "S", "FAILURE": "F", "RUNNING": "R", "INVALID": "-"}


def _num(value: float | None) -> float | None:
    if value is None or (isinstance(value, float) and math.isinf(value)):
        return None
    return round(value, 6)


def _jsonable(value: Any) -> Any:
    if isinstance(value, float):
        return _num(value)
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    return repr(value)


@dataclass
class Recording:
    """What a run (or a log) holds for plots and replays."""

    maze: Maze
    mission: str = ""
    samples: list[dict[str, Any]] = field(default_factory=list)
    events: list[dict[str, Any]] = field(default_factory=list)
    end: dict[str, Any] = field(default_factory=dict)

    @property
    def final_pose(self) -> dict[str, float] | None:
        return self.end.get("final_pose")


class Recorder:
    """An ``on_tick`` hook for :meth:`thymio_bt.runner.Run.run` that samples every tick."""

    def __init__(self, log_path: str | Path | None = None, keep: bool = True) -> None:
        self.keep = keep
        self.samples: list[dict[str, Any]] = []
        self._file: IO[str] | None = None
        self._path = Path(log_path) if log_path else None
        self._blackboard: dict[str, Any] = {}
        self._run: Any = None

    def _open(self, run: Any) -> None:
        self._run = run
        if self._path is None:
            return
        try:
            self._path.parent.mkdir(parents=True, exist_ok=True)
            self._file = self._path.open("w", encoding="utf-8", buffering=1)
        except OSError as exc:
            raise UserError(f"cannot write the log {self._path}: {exc}") from None
        mission = run.mission
        self._write({"kind": "header", "version": 1, "mission": mission.name, "tick_hz": mission.tick_hz,
                     "seed": run.seed, "start": mission.start.as_dict(), "maze": mission.maze.to_yaml_dict()})

    def _write(self, obj: dict[str, Any]) -> None:
        if self._file is not None:
            self._file.write(json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n")

    def __call__(self, run: Any) -> None:
        if self._run is None:
            self._open(run)
        sim = run.backend
        pose = sim.true_pose()
        scan = sim.proximity()
        cmd, vel = sim.command(), sim.velocity()
        sample: dict[str, Any] = {
            "t": round(sim.time(), 6), "tick": run.ticks,
            "pose": None if pose is None else {k: round(v, 6) for k, v in pose.as_dict().items()},
            "cmd": [round(cmd.linear, 6), round(cmd.angular, 6)],
            "vel": [round(vel.linear, 6), round(vel.angular, 6)],
            "prox": None if scan is None else {k: _num(v) for k, v in scan.items()},
            "running": [n.name for n in _running_leaves(run.root)],
        }
        if self.keep:
            self.samples.append(sample)
        if self._file is not None:
            nodes = {node_path(n): _STATUS[n.status.name] for n in run.root.iterate()}
            storage = py_trees.blackboard.Blackboard.storage
            changed = {k: _jsonable(v) for k, v in storage.items() if self._blackboard.get(k, object()) != v}
            self._blackboard = dict(storage)
            self._write({"kind": "tick", **sample, "nodes": nodes, **({"bb": changed} if changed else {})})

    def finish(self, result: Any) -> Recording:
        """Write the ``end`` line and close the log; return the in-memory recording."""
        end = {"status": result.status, "reason": result.reason, "code": result.code,
               "failed_path": result.failed_path, "sim_time": round(result.sim_time, 6),
               "final_pose": result.final_pose, "collisions": result.collisions}
        self._write({"kind": "end", **end, "events": result.events})
        if self._file is not None:
            self._file.close()
            self._file = None
        maze = self._run.mission.maze if self._run is not None else Maze()
        return Recording(maze=maze, mission=result.mission, samples=self.samples, events=result.events, end=end)


def _running_leaves(root: Any) -> list[Any]:
    return [n for n in root.iterate() if not getattr(n, "children", None) and n.status.name == "RUNNING"]


def read_log(path: str | Path) -> Recording:
    """Read a JSON-lines log; a truncated log (a crashed run) is read up to its last whole line."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        raise UserError(Problem(f"log not found: {path}", str(path), hint="write one with run --log FILE.jsonl")) from None
    header: dict[str, Any] | None = None
    recording: Recording | None = None
    for number, line in enumerate(lines, 1):
        try:
            obj = json.loads(line)
        except json.JSONDecodeError:
            if number == len(lines):
                break                      # the run crashed mid-line: keep what came before
            raise UserError(Problem("not a thymio-bt log line (invalid JSON)", str(path), number, 1)) from None
        kind = obj.get("kind") if isinstance(obj, dict) else None
        if number == 1:
            if kind != "header":
                raise UserError(Problem("not a thymio-bt log: the first line must be its header", str(path), 1, 1,
                                        hint="logs are written by thymio-bt run --log FILE.jsonl"))
            header = obj
            from .validation import validate
            recording = Recording(maze=validate(Maze, obj["maze"], str(path)), mission=obj.get("mission", ""))
            continue
        assert recording is not None
        if kind == "tick":
            recording.samples.append({k: v for k, v in obj.items() if k not in ("kind", "nodes", "bb")})
        elif kind == "end":
            recording.events = obj.get("events", [])
            recording.end = {k: v for k, v in obj.items() if k not in ("kind", "events")}
    if recording is None or header is None:
        raise UserError(Problem("empty log", str(path)))
    if not recording.end and recording.samples:
        last = recording.samples[-1]
        recording.end = {"status": "INCOMPLETE", "final_pose": last["pose"], "sim_time": last["t"]}
    return recording
