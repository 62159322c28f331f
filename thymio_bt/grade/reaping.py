"""Every process a submission started ends with its run: found in ``/proc`` by parentage (the
processes that start submissions are child subreapers, so a ``setsid`` or a double fork stays
beneath them) and, when the submission has a user id of its own, by that user; then killed.

Example (a process that forks a sleeper)::

    >>> import subprocess, sys, time
    >>> code = "import os, time\\nos.fork()\\ntime.sleep(60)"
    >>> parent = subprocess.Popen([sys.executable, "-c", code]); time.sleep(0.5)
    >>> len(descendants(parent.pid))
    1
    >>> kill_tree(parent.pid), parent.wait()
    (2, -9)
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import time
from collections.abc import Iterable

_PR_SET_CHILD_SUBREAPER = 36


def set_subreaper() -> bool:
    """Make this process a child subreaper (orphans of its descendants become its children)."""
    if not sys.platform.startswith("linux"):
        return False
    return bool(ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)


def _table() -> dict[int, tuple[int, int]]:
    """Every process: pid -> (parent pid, real user id)."""
    found = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as stat:
                fields = stat.read().rsplit(b")", 1)[1].split()
            uid = os.stat(f"/proc/{name}").st_uid
        except (OSError, IndexError):
            continue
        if fields[0] != b"Z":  # a zombie is already dead: its parent reaps it
            found[int(name)] = (int(fields[1]), uid)
    return found


def descendants(pid: int, table: dict[int, tuple[int, int]] | None = None) -> list[int]:
    """The live descendants of ``pid`` (children, theirs...)."""
    table = _table() if table is None else table
    children: dict[int, list[int]] = {}
    for child, (parent, _) in table.items():
        children.setdefault(parent, []).append(child)
    out, todo = [], list(children.get(pid, []))
    while todo:
        child = todo.pop()
        out.append(child)
        todo += children.get(child, [])
    return sorted(out)


def kill_tree(pid: int, uid: int | None = None) -> int:
    """SIGKILL ``pid``, its descendants and (with ``uid``) every process of that user, until none
    is left; how many were killed. Each round stops them first, so a fork bomb cannot outrun it."""
    killed: set[int] = set()
    for _ in range(100):
        table = _table()
        targets = {p for p in [pid, *descendants(pid, table)] if p in table}
        if uid is not None:
            targets |= {p for p, (_, owner) in table.items() if owner == uid}
        targets -= {os.getpid()}
        if not targets:
            break
        _signal(targets, signal.SIGSTOP)
        _signal(targets, signal.SIGKILL)
        killed |= targets
        time.sleep(0.005)  # the kernel ends them (and reparents their children) meanwhile
    return len(killed)


def reap_orphans(parent: int, keep: set[int]) -> int:
    """Kill the children of ``parent`` (a subreaper) that are not in ``keep``, with their trees:
    orphans of a submission whose process already ended. Reaps them when ``parent`` is this process."""
    table = _table()
    orphans = [p for p, (pp, _) in table.items() if pp == parent and p not in keep]
    for orphan in orphans:
        kill_tree(orphan)
    if parent == os.getpid():
        with contextlib.suppress(ChildProcessError):
            while os.waitpid(-1, os.WNOHANG)[0]:
                pass
    return len(orphans)


def _signal(pids: Iterable[int], sig: int) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, sig)
