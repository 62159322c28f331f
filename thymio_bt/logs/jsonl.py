"""thymio-bt's own log format: JSON lines, flushed line by line so a crash still leaves a readable log.

Line 1 is the ``header`` (mission, maze, rates, the tree), then one ``tick`` per tick (time, pose,
command, velocity, proximity, running nodes, the status of every node, blackboard values that
changed), then an ``end`` with the outcome and the events.

Example (a log damaged at line 101: an error naming the line, or the 99 ticks before it):

>>> import tempfile
>>> from thymio_bt.logs.recording import Recorder
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> folder = tempfile.TemporaryDirectory()
>>> path = Path(folder.name) / "run.jsonl"
>>> recorder = Recorder(log_path=path)
>>> _ = recorder.finish(Run(load_mission("square")).run(on_tick=recorder))
>>> lines = path.read_text().splitlines()
>>> lines[0][:60]
'{"kind":"header","version":2,"mission":"square","tick_hz":10'
>>> lines[100] = '{"kind": "tick"}'  # no time, no pose...
>>> _ = path.write_text("\\n".join(lines))
>>> read_jsonl(path)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: .../run.jsonl:101:1: damaged log line: tick line: missing key 't' (hint: ...)
>>> partial = read_jsonl(path, partial=True)
>>> len(partial.samples), partial.header["damaged_at"], partial.end["status"]
(99, 101, 'INCOMPLETE')
>>> folder.cleanup()
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import IO, Annotated, Any, Literal, cast

from pydantic import BaseModel, ConfigDict, Field, FiniteFloat, ValidationError, model_validator

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import read_text
from thymio_bt.inputs.validation import Wording, problems_from, validate
from thymio_bt.logs.entries import STATUS_LETTER, LogEnd, LogHeader, TickRecord
from thymio_bt.logs.recording import Recording
from thymio_bt.maze import Maze


class JsonlWriter:
    """Writes a run as JSON lines (see the module docstring)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._owned = str(path) != "-"  # "-": standard output, left open
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
        """Write line 1, ``{"kind": "header", ...}``."""
        self._write({"kind": "header", **header})

    def tick(self, record: TickRecord) -> None:
        """Write a ``{"kind": "tick", ...}`` line (flushed: the file is line-buffered)."""
        self._write({"kind": "tick", **record})

    def end(self, end: LogEnd) -> None:
        """Write the last line, ``{"kind": "end", ...}``."""
        self._write({"kind": "end", **end})

    def close(self) -> None:
        """Close the file (standard output is flushed, left open); idempotent."""
        if self._file is not None:
            if self._owned:
                self._file.close()
            else:
                self._file.flush()
            self._file = None


#: the longest run a log may describe, in simulated seconds (a year): past it a time is damage
MAX_TIME = 3.2e7
#: node uids are BT.CPP's (16 bits: the Groot2 log stores them so)
MAX_UID = 65535

_Time = Annotated[float, Field(ge=0, le=MAX_TIME, allow_inf_nan=False)]
_Uid = Annotated[int, Field(ge=1, le=MAX_UID)]


class _Pose(BaseModel):
    x: FiniteFloat
    y: FiniteFloat
    yaw: FiniteFloat


class _Tick(BaseModel):
    """What a replay or an export needs of a tick line; other keys are kept as they are."""

    model_config = ConfigDict(extra="allow")
    t: _Time
    tick: Annotated[int, Field(ge=0)]
    pose: _Pose | None
    cmd: tuple[FiniteFloat, FiniteFloat]
    vel: tuple[FiniteFloat, FiniteFloat]
    prox: dict[str, FiniteFloat | None] | None
    running: list[str] = []
    nodes: dict[str, Literal[tuple(STATUS_LETTER.values())]] = {}  # type: ignore[valid-type]  # the letters


class _TreeNode(BaseModel):
    model_config = ConfigDict(extra="allow")
    uid: _Uid
    path: str
    name: str
    kind: str
    parent: _Uid | None


class _Header(BaseModel):
    model_config = ConfigDict(extra="allow")
    mission: str = ""
    maze: dict[str, Any]
    tree: list[_TreeNode] = []

    @model_validator(mode="after")
    def _parents_come_first(self) -> _Header:
        """Each node's parent is a node listed before it (pre-order), and no uid is used twice."""
        seen: set[int] = set()
        for node in self.tree:
            if node.uid in seen:
                raise ValueError(f"uid {node.uid} is used twice")
            if node.parent is not None and node.parent not in seen:
                raise ValueError(f"node {node.uid}'s parent {node.parent} is not listed before it")
            seen.add(node.uid)
        return self


class _End(BaseModel):
    model_config = ConfigDict(extra="allow")
    status: str
    sim_time: _Time | None = None
    collisions: Annotated[int, Field(ge=0)] | None = None
    events: list[dict[str, Any]] = []


_LINES: dict[str, type[BaseModel]] = {"header": _Header, "tick": _Tick, "end": _End}
#: how a line's first problem reads after "tick line: " (a log has no marks: its line number is the place)
_LINE_WORDING = Wording(unknown="unknown key '{path}'", missing="missing key '{path}'", invalid="{path}: {msg}")


def read_jsonl(path: Path, partial: bool = False) -> Recording:
    """Read a JSON-lines log. A log cut short (a crashed run) is read up to its last whole line; a
    damaged line (not JSON, a wrong type, a missing field) is an error naming it, or with
    ``partial``, where the reading stops, keeping what came before."""
    lines = read_text(path, "log").splitlines()
    if not lines:
        raise UserError(
            Problem("the log is empty", str(path), hint="logs are written by thymio-bt run --log FILE.jsonl")
        )
    recording: Recording | None = None
    last_t = 0.0
    for number, line in enumerate(lines, 1):
        try:
            kind, obj = _line(line, number == 1)
            last_t = _tick_time(kind, obj, last_t)
        except ValueError as exc:
            if _damaged(path, exc, number, len(lines), partial):
                assert recording is not None
                recording.header["damaged_at"] = number
            break
        recording = _added(recording, kind, obj, path)
    assert recording is not None
    if not recording.end:
        last = recording.samples[-1] if recording.samples else {"pose": None, "t": 0.0}
        recording.end = {"status": "INCOMPLETE", "final_pose": last["pose"], "sim_time": last["t"]}
    return recording


def _tick_time(kind: str, obj: dict[str, Any], last_t: float) -> float:
    """The time of the last tick read, once this line is; ValueError for a tick before the previous one."""
    if kind != "tick":
        return last_t
    if obj["t"] < last_t:
        raise ValueError(f"tick line: t: {obj['t']} is before the previous tick's {last_t}")
    return obj["t"]


def _damaged(path: Path, exc: ValueError, number: int, count: int, partial: bool) -> bool:
    """Where the reading stops at line ``number`` (of ``count``), which ``exc`` says is wrong: a
    UserError, unless the run crashed mid-line (the last line's JSON cut short: False) or the log
    is read ``partial`` (True: the recording says where it is damaged)."""
    if number == 1:
        raise UserError(
            Problem(
                f"not a thymio-bt log: {exc}",
                str(path),
                1,
                1,
                hint="logs are written by thymio-bt run --log FILE.jsonl",
            )
        ) from None
    if number == count and "invalid JSON" in str(exc):
        return False  # the run crashed mid-line: keep what came before
    if partial:
        return True
    raise UserError(
        Problem(
            f"damaged log line: {exc}",
            str(path),
            number,
            1,
            hint=f"replay the {_ticks(number - 2)} before it with --partial",
        )
    ) from None


def _added(recording: Recording | None, kind: str, obj: dict[str, Any], path: Path) -> Recording:
    """The recording with one more line read: a header starts it, a tick adds a sample, the end
    line its events and ending."""
    # each line as written, JSON checked by its line model (_LINES): the log's shapes from here on
    if kind == "header":
        header = cast(LogHeader, {k: v for k, v in obj.items() if k != "kind"})
        return Recording(maze=validate(Maze, obj["maze"], str(path)), mission=obj.get("mission", ""), header=header)
    assert recording is not None
    if kind == "tick":
        recording.samples.append(cast(TickRecord, {k: v for k, v in obj.items() if k != "kind"}))
    else:
        recording.events = obj.get("events", [])
        recording.end = cast(LogEnd, {k: v for k, v in obj.items() if k not in ("kind", "events")})
    return recording


def _line(line: str, first: bool) -> tuple[str, dict[str, Any]]:
    """The kind and content of one log line, checked; ValueError says what is wrong with it."""
    try:
        obj = json.loads(line)
    except json.JSONDecodeError:
        raise ValueError("invalid JSON") from None
    kind = obj.get("kind") if isinstance(obj, dict) else None
    if first and kind != "header":
        raise ValueError("the first line must be its header")
    if not first and kind == "header":
        raise ValueError("a second header")
    if kind not in _LINES:
        raise ValueError(f"unknown line kind {kind!r} (expected header, tick or end)")
    try:
        _LINES[kind].model_validate(obj)
    except ValidationError as exc:
        problem = problems_from(exc, obj, "", _LINES[kind], wording=_LINE_WORDING)[0]
        raise ValueError(f"{kind} line: {problem.message}") from None
    return kind, obj


def _ticks(count: int) -> str:
    """``count`` ticks in words: "1 tick", "3 ticks"."""
    return f"{count} tick" if count == 1 else f"{count} ticks"
