"""Run logs in several file formats, chosen by the file's suffix, through one writer/reader protocol.

``thymio-bt run --log FILE`` picks the writer of FILE's format, ``replay`` and ``export`` the reader.
Built in: JSON lines (``.jsonl``, thymio-bt's own) and rosbag2 with MCAP storage (``.mcap``, or a
folder: what Foxglove, PlotJuggler and ``ros2 bag`` open; needs ``thymio-bt[rosbag]``), plus
BT.CPP's Groot2 log (``.btlog``: node statuses only, no robot). Plugins add formats through the
``thymio_bt.log_formats`` entry-point group, whose entries point to a :class:`LogFormat`.

A :class:`LogWriter` gets ``header()``, then ``tick()`` per tick, ``end()`` and ``close()``;
:func:`read_log` gives a :class:`~thymio_bt.logs.entries.Recording` back, for plots and replays
(:mod:`thymio_bt.logs.recording` writes and reads one).

Example:

>>> [format_for(name).name for name in ("run.jsonl", "run.mcap", "run_bag", "run.btlog")]
['jsonl', 'rosbag2', 'rosbag2', 'btlog']
>>> format_for("run.txt", reading=True)
Traceback (most recent call last):
...
thymio_bt.errors.UserError: run.txt: no log format reads '.txt' files (hint: use .jsonl, .mcap, .btlog)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import check_regular
from thymio_bt.named import named

if TYPE_CHECKING:
    from thymio_bt.logs.entries import LogEnd, LogHeader, Recording, TickRecord

ENTRY_POINT_GROUP = "thymio_bt.log_formats"


class LogWriter(Protocol):
    """Writes one run: the header first, a record per tick, the end; ``close`` however the run ends."""

    def header(self, header: LogHeader) -> None:
        """Write the log's header: the mission, its rates and the tree, before the first tick."""

    def tick(self, record: TickRecord) -> None:
        """Write one tick's record."""

    def end(self, end: LogEnd) -> None:
        """Write how the run ended, with its events."""

    def close(self) -> None:
        """Close the file; what was written stays readable however the run ended."""


@dataclass(frozen=True)
class LogFormat:
    """A log file format: ``writer`` and ``reader`` are ``"module:attr"`` (imported when used), or
    None when the format is only written or only read. ``writer`` is called with the path."""

    name: str
    summary: str
    suffixes: tuple[str, ...]
    writer: str | None = None
    reader: str | None = None
    #: whether a path without a suffix (a folder) is this format
    folder: bool = False
    #: whether the reader takes ``partial=True``: stop at a damaged record, keeping those before it
    partial: bool = False

    def load(self, attr: str) -> Any:
        """The object ``attr`` (``"module:name"``, :attr:`writer` or :attr:`reader`) names, imported now."""
        return named(attr)


BUILTIN: tuple[LogFormat, ...] = (
    LogFormat(
        "jsonl",
        "JSON lines: thymio-bt's own log, every field of every tick",
        (".jsonl",),
        "thymio_bt.logs.jsonl:JsonlWriter",
        "thymio_bt.logs.jsonl:read_jsonl",
        partial=True,
    ),
    LogFormat(
        "rosbag2",
        "rosbag2 with MCAP storage: /cmd_vel, /odom, /tf, the 7 proximity scans, /clock, "
        "tree state and events (Foxglove, PlotJuggler, ros2 bag; needs thymio-bt[rosbag])",
        (".mcap",),
        "thymio_bt.logs.rosbag:RosbagWriter",
        "thymio_bt.logs.rosbag:read_rosbag",
        folder=True,
    ),
)


def formats() -> list[LogFormat]:
    """Every log format: the built-in ones, then those of installed plugins."""
    from importlib.metadata import entry_points

    found = list(BUILTIN)
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        fmt = ep.load()
        if not isinstance(fmt, LogFormat):
            raise UserError(
                f"log format plugin '{ep.name}' ({ep.value}) is not a LogFormat "
                f"(hint: point the entry point at a thymio_bt.logs.LogFormat)"
            )
        found.append(fmt)
    return found


def format_for(path: str | Path, *, reading: bool = False) -> LogFormat:
    """The format of ``path`` by its suffix (a folder, or a path without suffix, is a rosbag2 bag;
    ``-``, standard output, is written as JSON lines)."""
    if str(path) == "-" and not reading:
        return BUILTIN[0]
    path = Path(path)
    suffix = path.suffix.lower()
    available = formats()
    for fmt in available:
        if suffix in fmt.suffixes or (fmt.folder and (not suffix or (reading and path.is_dir()))):
            if (fmt.reader if reading else fmt.writer) is None:
                break
            return fmt
    usable = [s for f in available if (f.reader if reading else f.writer) for s in f.suffixes]
    raise UserError(
        Problem(
            f"no log format {'reads' if reading else 'writes'} '{suffix or path.name}' files",
            str(path),
            hint=f"use {', '.join(usable)}{' or a folder' if not reading else ''}",
        )
    )


def open_writer(path: str | Path) -> LogWriter:
    """A writer for ``path`` in the format its suffix names; the file is created now."""
    fmt = format_for(path)
    assert fmt.writer is not None
    return fmt.load(fmt.writer)(Path(path))


def read_log(path: str | Path, partial: bool = False) -> Recording:
    """Read a log of any format that has a reader; ``partial``: what is readable of a damaged one."""
    path = Path(path)
    if not path.exists():
        raise UserError(Problem(f"log not found: {path}", str(path), hint="write one with run --log FILE.jsonl"))
    check_regular(path, "log", folder_ok=True)  # a rosbag2 bag may be a folder
    fmt = format_for(path, reading=True)
    assert fmt.reader is not None
    if partial and not fmt.partial:
        raise UserError(Problem(f"--partial is not available for {fmt.name} logs", str(path)))
    return fmt.load(fmt.reader)(path, **({"partial": True} if partial else {}))
