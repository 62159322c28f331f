"""Where a submission's tree and plugins run: a process of their own, confined (:mod:`.confine`),
that drives the grader's robot only through the :class:`~thymio_bt.grade.remote_robot.RemoteRobot`
(:mod:`.remote_robot` lists the messages). The simulation, its ground truth and every judgement
stay in the grader (:mod:`.remote_run`).

``python -I -m thymio_bt.grade.sandbox FD`` is the *zygote*: started fresh by the grader (never
forked from it, so it holds no other student's data, no assignment, no hidden world), with an empty
environment and nothing but a socket (FD) to the grader. It imports what runs need once, then forks
a process per connection the grader passes it: that process reads its orders (its folder, its limits),
confines itself for good, and only then reads the submission and imports its plugins. The zygote is
a child subreaper: the orphans of a submission whose process ended become its children, and it
kills them.

Per run: ``{"run": {...}}`` (the mission file, its settings, a maze holding only the world's spawns
and goal, the clock's period) is answered ``{"ready": ...}`` or ``{"error": ...}``; then each
observation by a reply (binary frames, :mod:`.wire`), until ``{"end": true}``, answered with the
node statistics.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import socket
import sys
from pathlib import Path
from typing import Any

from thymio_bt.grade.confine import confine, python_paths
from thymio_bt.grade.reaping import has_children, kill_tree, mapped_bytes, reap_orphans, set_subreaper
from thymio_bt.grade.remote_robot import RemoteRobot
from thymio_bt.grade.wire import MAX_DRIVES, Link, WireError, is_json, read_json, read_observation, reply_frame


def zygote(fd: int) -> None:
    """Serve the grader's connections on the SOCK_SEQPACKET socket ``fd`` until it closes."""
    _warm()
    set_subreaper()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    control = socket.socket(fileno=fd)
    kids: set[int] = set()
    try:
        while True:
            ready = select.select([control], [], [], 0.2)[0]
            if _reap(kids) or has_children(os.getpid()) and len(kids) == 0:
                reap_orphans(os.getpid(), kids)  # a submission's process ended: its orphans are ours
            if not ready:
                continue
            data, fds, _, _ = socket.recv_fds(control, 16, 1)
            if not data:
                break
            pid = os.fork()
            if pid == 0:
                code = 0
                try:
                    control.close()
                    serve(fds[0])
                except BaseException:
                    code = 70
                finally:
                    os._exit(code)
            for passed in fds:
                os.close(passed)
            kids.add(pid)
    finally:
        _end_all(kids)


def _end_all(kids: set[int]) -> None:
    """Kill every process the zygote started and every orphan handed to it, until it has no child."""
    for kid in kids:
        kill_tree(kid)
    for _ in range(1000):
        reap_orphans(os.getpid(), set())
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            return


def _reap(kids: set[int]) -> bool:
    """Reap the submissions' processes that ended; whether one did."""
    ended = False
    for kid in list(kids):
        with contextlib.suppress(ChildProcessError):
            if os.waitpid(kid, os.WNOHANG)[0]:
                kids.discard(kid)
                ended = True
    return ended


def _warm() -> None:
    """Import what every run needs, before any connection: each forked process starts warm."""
    import py_trees  # noqa: F401

    from thymio_bt.behaviours.flow.ticking import tick  # noqa: F401
    from thymio_bt.mission import build_tree, default_registry, load_mission  # noqa: F401
    from thymio_bt.run.coverage import NodeStats  # noqa: F401
    from thymio_bt.run.result import failing_branch  # noqa: F401

    load_mission("maze_part1_2")
    default_registry().import_all()  # a submission's mission may name any node


def serve(fd: int) -> None:
    """One submission's process: its orders, its confinement, then its runs."""
    link = Link(socket.socket(fileno=fd))
    orders = link.receive(None)
    folder = Path(orders["folder"])
    devnull = os.open(os.devnull, os.O_RDWR)
    for std in (0, 1, 2):
        os.dup2(devnull, std)
    os.chdir(folder)
    os.environ.clear()
    os.environ.update({"HOME": str(folder), "TMPDIR": str(folder), "PATH": "/usr/bin:/bin"})
    sys.argv = ["thymio-bt-submission"]
    os.setsid()  # a group of its own: killpg(0) reaches none of the zygote's other processes
    set_subreaper()
    try:
        if orders.get("cgroup"):  # as root: a pids cgroup of its own, joined while it may
            Path(orders["cgroup"], "cgroup.procs").write_text(str(os.getpid()))
        held = confine(python_paths(), folder, mapped_bytes() + orders["memory"], orders["cpu"])
    except Exception as exc:  # the grader says so in the summary, and fails the runs
        link.send({"hello": os.getpid(), "error": f"confinement failed: {exc}"})
        return
    link.send({"hello": os.getpid(), "held": held.held, "missing": held.missing})
    missions: dict[str, Any] = {}
    watch = _Watch(link)
    while True:
        message = link.receive(None)
        if "run" not in message:
            return
        _reap_children()  # those the last run started, killed by the grader: zombies count as processes
        _run(link, message["run"], missions, watch)


def _reap_children() -> None:
    with contextlib.suppress(ChildProcessError):
        while os.waitpid(-1, os.WNOHANG)[0]:
            pass


def _run(link: Link, spec: dict[str, Any], missions: dict[str, Any], watch: _Watch) -> None:
    """One run: load (once per world) and build the tree, then answer each observation."""
    import py_trees

    from thymio_bt.behaviours import Context, EventLog
    from thymio_bt.behaviours.base import describe, node_path
    from thymio_bt.errors import UserError
    from thymio_bt.maze.model import Area
    from thymio_bt.mission import build_tree, load_mission
    from thymio_bt.robot.model import robot_model
    from thymio_bt.run.coverage import NodeStats

    key = repr(sorted(spec["mission"].items()))
    try:
        if key not in missions:
            missions[key] = load_mission(run_plugins=True, **spec["mission"])
        mission = missions[key]
        robot = RemoteRobot(robot_model(mission.robot))
        events = EventLog()
        bounds = tuple(spec["bounds"]) if spec["bounds"] else None
        goal = tuple(Area.model_validate(area) for area in spec["goal"])  # {"from": [x, y], "to": [x, y]}
        context = Context(robot, robot, events, spec["period"], bounds, goal)
        context.collision_count = lambda: robot.collisions
        py_trees.blackboard.Blackboard.clear()
        root = build_tree(mission.tree, context, mission.registry)
    except UserError as exc:
        link.send({"error": f"the mission cannot run in this world: {exc}"})
        return
    except BaseException as exc:
        link.send({"error": f"the tree could not be built: {describe(exc)}"})
        return
    stats = NodeStats(spec["period"])
    stats.attach(root, mission.tree)
    link.send({"ready": True})
    sent, tip = 0, None
    shown = _Statuses(root)
    while True:
        frame = link.receive_frame(None)
        if is_json(frame):  # the run's end: running behaviours end then
            robot.observe_time(read_json(frame)["t"])
            break
        robot.observe(*read_observation(frame))
        with watch:
            status, rest = _tick(root)
        drives, requests = robot.outbox()
        if requests:
            rest["q"] = requests
        if len(events) > sent:
            rest["ev"] = events[sent:]
            sent = len(events)
        running = root.tip()
        path = node_path(running) if running is not None and status == "RUNNING" else None
        if path != tip:
            rest["tip"] = tip = path
        if changed := shown.changed():
            rest["n"] = changed
        link.send_frame(reply_frame(status, drives[:MAX_DRIVES], rest))
    with contextlib.suppress(Exception):
        root.stop(py_trees.common.Status.INVALID)
    link.send({"stats": stats.table.rows(), "ev": events[sent:]})


class _Statuses:
    """What the grader's copy of the tree shows: each node's status, sent when it changed."""

    def __init__(self, root: Any) -> None:
        from thymio_bt.behaviours.base import node_path

        self.nodes = [(node_path(node), node) for node in root.iterate()]
        self.last: dict[str, str] = {}

    def changed(self) -> dict[str, str]:
        """The nodes whose status changed since the last call: path -> status letter (as logs write it)."""
        from thymio_bt.logs.entries import STATUS_LETTER

        now = {path: STATUS_LETTER[node.status.name] for path, node in self.nodes}
        changed = {path: letter for path, letter in now.items() if self.last.get(path) != letter}
        self.last = now
        return changed


class _Watch:
    """Tells the grader which node a tick is in once it has taken :data:`SLOW` s (``{"slow": path}``):
    the node a run that goes over its time limit is stopped in. A timer signal, armed for each tick
    (a thread woken every tick would cost the tick loop its GIL)."""

    def __init__(self, link: Link) -> None:
        self.link = link
        signal.signal(signal.SIGALRM, self._slow)

    def __enter__(self) -> None:
        signal.setitimer(signal.ITIMER_REAL, SLOW)

    def __exit__(self, *exc: object) -> None:
        signal.setitimer(signal.ITIMER_REAL, 0)

    def _slow(self, _signum: int, frame: Any) -> None:
        from thymio_bt.behaviours.base import node_path

        node = _innermost_node(frame)
        with contextlib.suppress(Exception):
            self.link.send({"slow": node_path(node) if node is not None else None})


def _innermost_node(frame: Any) -> Any:
    """The innermost tree node whose method ``frame`` (or a caller of it) runs."""
    from py_trees.behaviour import Behaviour

    while frame is not None:
        owner = frame.f_locals.get("self")
        if isinstance(owner, Behaviour):
            return owner
        frame = frame.f_back
    return None


#: seconds after which a tick is slow (see :class:`_Watch`)
SLOW = 0.5


def _tick(root: Any) -> tuple[str, dict[str, Any]]:
    """One tick of the tree: its status, and where and why it failed (or why the tick raised)."""
    from thymio_bt.behaviours.base import describe, is_fault
    from thymio_bt.behaviours.flow.ticking import tick
    from thymio_bt.run.result import failing_branch

    try:
        tick(root)
    except BaseException as exc:
        if not is_fault(exc):
            raise
        return "INVALID", {"x": f"the run raised {describe(exc)}"}
    status = root.status.name
    if status == "FAILURE":
        return status, {"f": list(failing_branch(root))}
    return status, {}


if __name__ == "__main__":
    with contextlib.suppress(WireError, KeyboardInterrupt):
        zygote(int(sys.argv[1]))
