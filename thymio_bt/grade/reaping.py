"""Every process a submission started ends with its run: found in ``/proc`` by parentage (the
processes that start submissions are child subreapers, so a ``setsid`` or a double fork stays
beneath them) and, as root, in the submission's ``pids`` cgroup (which also bounds how many it may
start: ``RLIMIT_NPROC`` does not bind root); then killed.

Example (a process that forks a sleeper)::

    >>> import subprocess, sys, time
    >>> code = "import os, time\\nos.fork()\\ntime.sleep(60)"  # realtime: a child that waits to be killed
    >>> parent = subprocess.Popen([sys.executable, "-c", code]); time.sleep(0.5)  # realtime: it forks
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
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path

_PR_SET_CHILD_SUBREAPER = 36


def set_subreaper() -> bool:
    """Make this process a child subreaper (orphans of its descendants become its children)."""
    if not sys.platform.startswith("linux"):
        return False
    return bool(ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)


def _table() -> dict[int, int]:
    """Every live process: pid -> parent pid."""
    found: dict[int, int] = {}
    if not os.path.isdir("/proc"):  # not Linux: nothing can be found (nor is any confinement claimed)
        return found
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as stat:
                fields = stat.read().rsplit(b")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if fields[0] != b"Z":  # a zombie is already dead: its parent reaps it
            found[int(name)] = int(fields[1])
    return found


def has_children(pid: int) -> bool:
    """Whether ``pid`` has a child now (read from its threads' ``children`` lists, without a scan
    of every process); True when that cannot be read."""
    try:
        return any(
            Path(f"/proc/{pid}/task/{task}/children").read_text().strip() for task in os.listdir(f"/proc/{pid}/task")
        )
    except OSError:
        return True


def descendants(pid: int, table: dict[int, int] | None = None) -> list[int]:
    """The live descendants of ``pid`` (children, theirs...)."""
    table = _table() if table is None else table
    children: dict[int, list[int]] = {}
    for child, parent in table.items():
        children.setdefault(parent, []).append(child)
    out, todo = [], list(children.get(pid, []))
    while todo:
        child = todo.pop()
        out.append(child)
        todo += children.get(child, [])
    return sorted(out)


def kill_tree(pid: int, cgroup: Path | None = None, spare: bool = False) -> int:
    """SIGKILL ``pid`` (unless ``spare``), its descendants and (with ``cgroup``) every process in
    that cgroup, until none is left; how many were killed. Each round stops them first, so a fork
    bomb cannot outrun it."""
    killed: set[int] = set()
    if spare and not has_children(pid) and (cgroup is None or _members(cgroup) == [pid]):
        return 0  # the common case at a run's end: nothing was started
    for _ in range(100):
        table = _table()
        targets = {p for p in [pid, *descendants(pid, table)] if p in table}
        if cgroup is not None:
            targets |= {p for p in _members(cgroup) if p in table}
        targets -= {os.getpid(), *([pid] if spare else [])}
        if not targets:
            break
        _signal(targets, signal.SIGSTOP)
        _signal(targets, signal.SIGKILL)
        killed |= targets
        time.sleep(0.005)  # realtime: the kernel ends them (and reparents their children) meanwhile
    return len(killed)


def reap_orphans(parent: int, keep: set[int]) -> int:
    """Kill the children of ``parent`` (a subreaper) that are not in ``keep``, with their trees:
    orphans of a submission whose process already ended. Reaps them when ``parent`` is this process."""
    table = _table()
    orphans = [p for p, pp in table.items() if pp == parent and p not in keep]
    for orphan in orphans:
        kill_tree(orphan)
    if parent == os.getpid():
        with contextlib.suppress(ChildProcessError):
            while os.waitpid(-1, os.WNOHANG)[0]:
                pass
    return len(orphans)


#: where a pids cgroup may be made (cgroup v1's pids hierarchy, or a v2 root that delegates pids)
CGROUP_ROOTS = (Path("/sys/fs/cgroup/pids"), Path("/sys/fs/cgroup"))


def pids_cgroups() -> Path | None:
    """The folder new pids cgroups go in, if this process may make them (as root, usually)."""
    for root in CGROUP_ROOTS:
        if (root / "cgroup.procs").exists() and os.access(root, os.W_OK) and _has_pids(root):
            return root
    return None


def _has_pids(root: Path) -> bool:
    controllers = root / "cgroup.subtree_control"
    if not controllers.exists():  # cgroup v1: a hierarchy of its own
        return root.name == "pids"
    return "pids" in controllers.read_text().split()


def new_pids_cgroup(limit: int, grade: int) -> Path | None:
    """A new cgroup that holds at most ``limit`` processes (None where none can be made), named for
    the ``grade`` (the grading process's id: ``thymio-bt-GRADE-...``)."""
    root = pids_cgroups()
    if root is None:
        return None
    folder = Path(tempfile.mkdtemp(prefix=f"thymio-bt-{grade}-", dir=root))
    (folder / "pids.max").write_text(str(limit))
    return folder


def remove_cgroup(folder: Path | None) -> None:
    """Remove a cgroup of :func:`new_pids_cgroup`, killing what is still in it (5 s at most)."""
    for _ in range(500):
        if folder is None:
            return
        try:
            folder.rmdir()
            return
        except FileNotFoundError:
            return
        except OSError:
            _signal(_members(folder), signal.SIGKILL)
            time.sleep(0.01)  # realtime: the kernel empties the cgroup; no run is ticking


def remove_cgroups_of(grade: int) -> None:
    """Remove every pids cgroup of the grade ``grade`` (those of workers a signal ended early)."""
    root = pids_cgroups()
    for folder in root.glob(f"thymio-bt-{grade}-*") if root is not None else ():
        remove_cgroup(folder)


def _members(cgroup: Path) -> list[int]:
    try:
        return [int(p) for p in (cgroup / "cgroup.procs").read_text().split()]
    except (OSError, ValueError):
        return []


def _signal(pids: Iterable[int], sig: int) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, sig)


def mapped_bytes() -> int:
    """The bytes of address space this process maps now (its VmSize): a memory limit is set on top
    of it, so a process that has mapped its interpreter still has the limit's room to work in."""
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0
