"""Run untrusted submissions, each in a process of its own with CPU and memory limits.

A submission's code (its plugins, its tree) runs only in a child process forked for it: the child
sets its limits (address space, CPU seconds, file size), runs the submission's runs one after the
other, and sends each run's summary to the grader through a pipe, one JSON line at a time. A run
that loops for ever is stopped by a timer (:class:`RunLimit`) and fails with a reason; a child that
dies (``os._exit``, a crash, the kernel's CPU limit, a hang the timer could not break) fails the
run it was in, and a new child goes on with the submission's next runs. No child ever writes the
results: only the grader does, from what the pipes said.

What this does not isolate: the file system and the network (a child runs as the grader's user),
and the grader process itself from signals. Grade in a container or as a user of its own for that.

Example (the work function runs in the child; here it just echoes)::

    >>> def work(task, send, skip):
    ...     for x in task[1][skip:]:
    ...         if x == 0:
    ...             os._exit(3)               # a submission that ends its process
    ...         send({"kind": "run", "x": x})
    >>> done = ForkPool(workers=2).run([("a", [1, 0, 2]), ("b", [3])], work, lambda task: len(task[1]))
    >>> [(task[0], [m.get("x", m.get("reason")) for m in messages]) for task, messages in done]
    [('a', [1, 'the run ended its process (exit code 3: os._exit or a crash)', 2]), ('b', [3])]
"""

from __future__ import annotations

import contextlib
import json
import os
import resource
import select
import signal
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar

from thymio_bt.grade.reaping import mapped_bytes

T = TypeVar("T")
#: how a child sends the grader a message (a JSON object)
Send = Callable[[dict[str, Any]], None]


class RunLimit(BaseException):  # noqa: N818 - raised into a student's code: not an Exception it can catch
    """A run went over its CPU or wall-clock time: raised in the child by its timer."""


@dataclass
class Limits:
    """What one run may use (CPU seconds, wall seconds) and its process (MiB of memory)."""

    cpu: float = 20.0
    memory_mib: int = 1024
    #: a run's wall-clock limit: the timer's, then the grader's own (this plus a margin)
    wall: float = 60.0


def run_limited(limits: Limits, run: Callable[[], T]) -> T:
    """``run()`` with its CPU and wall-clock timers set (in a child process): :class:`RunLimit` when
    one fires."""

    fired: list[str] = []

    def expired(signum: int, _frame: Any) -> None:
        what = "CPU" if signum == signal.SIGPROF else "wall-clock"
        fired.append(f"the run used more than its {what} time limit")
        raise RunLimit(fired[0])

    signal.signal(signal.SIGPROF, expired)
    signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_PROF, limits.cpu)
    signal.setitimer(signal.ITIMER_REAL, limits.wall)
    try:
        result = run()
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.setitimer(signal.ITIMER_REAL, 0)
    if fired:  # the run's own fault handling caught it (a node that raised): still a stopped run
        raise RunLimit(fired[0])
    return result


@dataclass
class _Child(Generic[T]):
    """A child process at work on a task: its pipe, what it has said, since when it is silent."""

    task: T
    pid: int
    fd: int
    runs: int
    messages: list[dict[str, Any]]
    heard: float
    buffer: bytes = b""
    done: int = 0  # runs it (and the children before it) finished
    current: int | None = None  # the run it started and has not finished


@dataclass
class ForkPool(Generic[T]):
    """At most ``workers`` children at once, one task each, each child under ``limits``."""

    workers: int = 2
    limits: Limits = field(default_factory=Limits)
    #: called in the grader with (task, message) as each message arrives
    progress: Callable[[T, dict[str, Any]], None] | None = None
    #: set from a signal handler to stop: children are killed, the results so far returned
    stop: Callable[[], bool] = lambda: False

    def run(
        self, tasks: Sequence[T], work: Callable[..., Any], runs_of: Callable[[T], int]
    ) -> list[tuple[T, list[dict[str, Any]]]]:
        """``work(task, send, skip=n)`` in a child per task: it runs the task's runs but the first
        ``n``, announcing each with ``{"kind": "start", "index": i}`` and ending it with a message of
        kind ``run``. Each task's messages, in task order. A child that dies mid-way is followed by
        another for the remaining runs, the run it died in reported as ``{"kind": "died", ...}``."""
        results: dict[int, list[dict[str, Any]]] = {i: [] for i in range(len(tasks))}
        waiting: list[tuple[int, int]] = [(i, 0) for i in range(len(tasks))][::-1]  # (task, runs done)
        children: dict[int, tuple[int, _Child[T]]] = {}
        try:
            while (waiting or children) and not self.stop():
                while waiting and len(children) < self.workers:
                    index, skip = waiting.pop()
                    child = self._fork(tasks[index], work, skip, runs_of(tasks[index]))
                    child.done = skip
                    children[child.fd] = (index, child)
                ready, _, _ = select.select(list(children), [], [], 0.1)
                for fd in ready:
                    index, child = children[fd]
                    if self._read(child, results[index]):
                        continue
                    del children[fd]
                    self._reap(child, results[index], waiting, index)
                for fd, (index, child) in list(children.items()):
                    if time.monotonic() - child.heard > self.limits.wall + 10:
                        _kill(child.pid)
                        del children[fd]
                        self._reap(child, results[index], waiting, index, hung=True)
        finally:
            for _, child in children.values():
                _kill(child.pid)
                os.waitpid(child.pid, 0)
                os.close(child.fd)
        return [(task, results[i]) for i, task in enumerate(tasks)]

    def _fork(self, task: T, work: Callable[..., Any], skip: int, runs: int) -> _Child[T]:
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: never returns
            code = 0
            try:
                os.close(read)
                _child_setup(self.limits, runs - skip)

                def send(message: dict[str, Any]) -> None:
                    data = (json.dumps(message, allow_nan=False) + "\n").encode()
                    while data:
                        data = data[os.write(write, data) :]

                work(task, send, skip=skip)
            except BaseException:
                code = 70
            finally:
                os._exit(code)
        os.close(write)
        with contextlib.suppress(OSError):  # the child does it too: whichever runs first
            os.setpgid(pid, pid)
        return _Child(task, pid, read, runs, [], time.monotonic())

    def _read(self, child: _Child[T], messages: list[dict[str, Any]]) -> bool:
        """Read what the child sent; False at the end of its pipe."""
        data = os.read(child.fd, 1 << 16)
        if not data:
            return False
        child.heard = time.monotonic()
        child.buffer += data
        *lines, child.buffer = child.buffer.split(b"\n")
        for line in lines:
            message = _message(line)
            if message is None:  # not a message: the run it is in counts as died, if it never ends
                continue
            if message.get("kind") == "start":
                child.current = message.get("index")
                continue
            if message.get("kind") == "run":
                child.done += 1
                child.current = None
            messages.append(message)
            if self.progress is not None:
                self.progress(child.task, message)
        return True

    def _reap(
        self,
        child: _Child[T],
        messages: list[dict[str, Any]],
        waiting: list[tuple[int, int]],
        index: int,
        hung: bool = False,
    ) -> None:
        """The child ended: if it left runs undone, report the one it died in and queue the rest."""
        os.close(child.fd)
        _, status = os.waitpid(child.pid, 0)
        _kill(child.pid)  # what it started and left behind, in its process group
        if child.done >= child.runs:
            return
        died = {
            "kind": "died",
            "index": child.current if child.current is not None else child.done,
            "reason": _death(status, hung, self.limits),
        }
        messages.append(died)
        if self.progress is not None:
            self.progress(child.task, died)
        if child.done + 1 < child.runs:
            waiting.append((index, child.done + 1))


def _message(line: bytes) -> dict[str, Any] | None:
    """A line of a child's pipe as a JSON object; None if it is not one.

    >>> _message(b'{"kind": "start", "index": 0}'), _message(b"[1, 2]"), _message(b"\\xff{")
    ({'kind': 'start', 'index': 0}, None, None)
    """
    try:
        message = json.loads(line)
    except ValueError:
        return None
    return message if isinstance(message, dict) else None


def _kill(pid: int) -> None:
    """Kill the process group of the child ``pid``: the child and whatever it started."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pid, signal.SIGKILL)


def _child_setup(limits: Limits, runs: int) -> None:
    """In a new child: a process group of its own (killed whole), its limits, no terminal output,
    the grader's signals left to the grader."""
    os.setpgid(0, 0)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    # on top of what the process maps already (a Dask worker's threads and arenas map gigabytes
    # of address space they never touch): the limit is what the submission may add
    memory = mapped_bytes() + (limits.memory_mib << 20)
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    cpu = int(limits.cpu * runs + 30)  # the kernel's backstop, should the timers not fire
    resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 5))
    resource.setrlimit(resource.RLIMIT_FSIZE, (64 << 20, 64 << 20))
    devnull = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(devnull, fd)


def _death(status: int, hung: bool, limits: Limits) -> str:
    """Why a child ended before its runs did, in a student's terms."""
    if hung:
        return f"the run stopped answering (no progress for {limits.wall + 10:g} s): stopped"
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        if sig == signal.SIGXCPU:
            return "the run used more than its CPU time limit (killed)"
        if sig == signal.SIGKILL:
            return f"the run was killed (SIGKILL: out of memory, more than {limits.memory_mib} MiB?)"
        return f"the run crashed ({signal.Signals(sig).name})"
    code = os.WEXITSTATUS(status)
    return f"the run ended its process (exit code {code}: os._exit or a crash)"
