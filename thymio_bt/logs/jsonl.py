"""thymio-bt's own log format: JSON lines, flushed line by line so a crash still leaves a readable log.

Line 1 is the ``header`` (mission, maze, rates, the tree), then one ``tick`` per tick (time, pose,
command, velocity, proximity, running nodes, the status of every node, blackboard values that
changed), then an ``end`` with the outcome and the events.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import IO, Any

from ..errors import Problem, UserError
from ..reading import read_text
from ..maze import Maze
from ..recording import Recording
from .records import LogEnd, LogHeader, TickRecord


class JsonlWriter:
    """Writes a run as JSON lines (see the module docstring)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._owned = str(path) != "-"                      # "-": standard output, left open
        self._file: IO[str] | None = sys.stdout
        if not self._owned:
            return
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file = path.open("w", encoding="utf-8", buffering=1)
        except OSError as exc:
            raise UserError(f"cannot write the log {path}: {exc}") from None

    def _write(self, obj: dict[str, Any]) -> None:
        if self._file is not None:
            self._file.write(json.dumps(obj, allow_nan=False, separators=(",", ":")) + "\n")

    def header(self, header: LogHeader) -> None:
        self._write({"kind": "header", **header})

    def tick(self, record: TickRecord) -> None:
        self._write({"kind": "tick", **record})

    def end(self, end: LogEnd) -> None:
        self._write({"kind": "end", **end})

    def close(self) -> None:
        if self._file is not None:
            if self._owned:
                self._file.close()
            else:
                self._file.flush()
            self._file = None


def read_jsonl(path: Path) -> Recording:
    """Read a JSON-lines log; a truncated log (a crashed run) is read up to its last whole line."""
    lines = read_text(path, "log").splitlines()
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
            from ..validation import validate
            header = {k: v for k, v in obj.items() if k != "kind"}
            recording = Recording(maze=validate(Maze, obj["maze"], str(path)), mission=obj.get("mission", ""),
                                  header=header)
            continue
        assert recording is not None
        if kind == "tick":
            recording.samples.append({k: v for k, v in obj.items() if k != "kind"})
        elif kind == "end":
            recording.events = obj.get("events", [])
            recording.end = {k: v for k, v in obj.items() if k not in ("kind", "events")}
    if recording is None:
        raise UserError(Problem("empty log", str(path)))
    if not recording.end and recording.samples:
        last = recording.samples[-1]
        recording.end = {"status": "INCOMPLETE", "final_pose": last["pose"], "sim_time": last["t"]}
    return recording
