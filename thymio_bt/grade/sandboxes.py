"""The grader's side of submissions' confined processes (:mod:`.sandbox` is theirs): the zygote
that starts them, and a :class:`Sandbox` per submission with its private folder and its link.

The zygote is spawned once per grade, fresh (``python -I``, an empty environment, its own session:
Ctrl-C at the terminal reaches the grader only), before the grader forks its workers, which inherit
the socket to it. A worker asks for a process by passing it one end of a new socket pair; the
process's first message (sent before it reads any of the submission) says its process id and what
confinement held.

Each submission works on a copy of its files in a private folder (its plugins cannot change the
original, nor see the folder next door), with the world's spawns and goal in a maze file of its own
(never the world's file: the walls of a hidden world stay with the grader). When the grader runs as
root, the process joins a ``pids`` cgroup of its own (at most :data:`~.confine.NPROC_MARGIN`
processes, each found there and killed when a run ends).
"""

from __future__ import annotations

import atexit
import contextlib
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from thymio_bt.grade.confine import NPROC_MARGIN, Confinement
from thymio_bt.grade.reaping import kill_tree, new_pids_cgroup, remove_cgroup
from thymio_bt.grade.wire import Link, WireError

#: how long a new submission process may take to say hello (the zygote may still be importing)
HELLO_WAIT = 60.0


class Zygote:
    """The process that forks submissions' processes (started by :meth:`start`, ended by :meth:`close`)."""

    def __init__(self) -> None:
        self.control: socket.socket | None = None
        self.process: subprocess.Popen[bytes] | None = None
        self._lock = threading.Lock()

    def ensure(self) -> Zygote:
        """Started, if it is not yet (for a process that grades many tasks, a Dask worker: it then
        lives as long as that process)."""
        with self._lock:
            if self.control is None:
                self.start()
                atexit.register(self.close)
        return self

    def start(self) -> Zygote:
        """Spawn it (fresh, not forked from this process)."""
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.process = subprocess.Popen(  # noqa: S603 - this Python, this package's module
            [sys.executable, "-I", "-m", "thymio_bt.grade.sandbox", str(theirs.fileno())],
            pass_fds=[theirs.fileno()],
            env={"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"},
            cwd="/",
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        theirs.close()
        self.control = ours
        return self

    def connect(self) -> Link:
        """A link to a new process of the zygote's."""
        assert self.control is not None, "the zygote was not started"
        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            socket.send_fds(self.control, [b"go"], [theirs.fileno()])
        except OSError as exc:
            mine.close()
            raise WireError(f"the sandbox's zygote is gone ({exc.strerror or exc})") from None
        finally:
            theirs.close()
        return Link(mine)

    def close(self) -> None:
        """End it and every process it started (closing its socket ends it; a kill makes sure)."""
        if self.control is not None:
            self.control.close()
            self.control = None
        if self.process is not None:
            try:
                self.process.wait(5)
            except subprocess.TimeoutExpired:
                kill_tree(self.process.pid)
                self.process.wait()
            self.process = None

    def __enter__(self) -> Zygote:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()


#: the zygote of this grade, set by the grader before it forks its workers
ZYGOTE = Zygote()


@dataclass
class Sandbox:
    """One submission's confined process, seen from the grader's worker."""

    link: Link
    pid: int
    cgroup: Path | None
    folder: Path
    confinement: Confinement
    #: why it could not be confined (its runs fail with this), None when it was
    error: str | None = None
    mazes: dict[str, str] = field(default_factory=dict)

    @classmethod
    def open(cls, mission: Path, home: Path | None, sources: list[Path], memory: int, cpu: int) -> Sandbox:
        """A new process for the mission file ``mission``: a copy of ``home`` (a student's folder)
        or, without one, of the file and the sources beside or below it (its plugins)."""
        folder = Path(tempfile.mkdtemp(prefix="thymio-bt-submission-"))
        _copy(mission, home, sources, folder / "submission")
        # (this runs in a worker of the grade: its parent is the grading process)
        cgroup = new_pids_cgroup(NPROC_MARGIN, os.getppid()) if os.geteuid() == 0 else None
        link = ZYGOTE.connect()
        try:
            link.send({"folder": str(folder), "memory": memory, "cpu": cpu, "cgroup": cgroup and str(cgroup)})
            hello = link.receive(time.monotonic() + HELLO_WAIT)
        except WireError:
            link.close()
            shutil.rmtree(folder, ignore_errors=True)
            remove_cgroup(cgroup)
            raise
        pid = hello.get("hello")
        if not isinstance(pid, int) or pid <= 1:
            raise WireError("the sandbox did not say hello")
        confinement = Confinement(list(hello.get("held", [])), dict(hello.get("missing", {})))
        return cls(link, pid, cgroup, folder, confinement, hello.get("error"))

    def copy_of(self, mission: Path, home: Path | None) -> Path:
        """Where the copy of the mission file is."""
        return self.folder / "submission" / mission.resolve().relative_to((home or mission.parent).resolve())

    def maze_file(self, maze: Any) -> str:
        """A maze file holding only ``maze``'s spawns and goal, unrounded (written once per maze)."""
        import json

        if maze.name not in self.mazes:
            blind = {
                "name": maze.name,
                "walls": [],
                "spawns": {k: {"x": s.x, "y": s.y, "yaw": s.yaw} for k, s in maze.spawns.items()},
                "goal": [{"from": list(a.start), "to": list(a.end)} for a in maze.goal],
            }
            path = self.folder / "worlds" / f"maze_{len(self.mazes)}.yaml"
            path.parent.mkdir(exist_ok=True)
            path.write_text(json.dumps(blind))  # YAML reads JSON, floats exactly
            self.mazes[maze.name] = str(path)
        return self.mazes[maze.name]

    def end_run(self) -> None:
        """Kill every process the submission started during a run (its own stays, for the next)."""
        kill_tree(self.pid, self.cgroup, spare=True)

    def close(self) -> None:
        """End the process and everything it started; remove its folder."""
        with contextlib.suppress(OSError, WireError):
            self.link.send({"bye": True})
        self.link.close()
        kill_tree(self.pid, self.cgroup)
        remove_cgroup(self.cgroup)
        shutil.rmtree(self.folder, ignore_errors=True)


def _special(folder: str, names: list[str]) -> list[str]:
    """The entries of ``folder`` that are neither folders, files nor links (a FIFO would block the copy)."""
    import stat

    def kind(name: str) -> int:
        try:
            return os.lstat(os.path.join(folder, name)).st_mode
        except OSError:
            return 0

    return [n for n in names if not (stat.S_ISDIR(kind(n)) or stat.S_ISREG(kind(n)) or stat.S_ISLNK(kind(n)))]


def _copy(mission: Path, home: Path | None, sources: list[Path], into: Path) -> None:
    """The submission's files, links kept as links (their targets stay out of reach)."""
    if home is not None:
        shutil.copytree(home, into, symlinks=True, ignore=_special)
        return
    parent = mission.parent.resolve()
    into.mkdir(parents=True)
    for source in [mission, *sources]:
        try:
            relative = source.resolve().relative_to(parent)
        except ValueError:
            continue  # a shipped file (an included library, a maze): read from the package
        (into / relative).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, into / relative, follow_symlinks=False)
