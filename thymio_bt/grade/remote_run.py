"""A run whose tree ticks in a submission's confined process (:mod:`.sandbox`) while the simulation,
the clock, the ground truth and the record stay here, in the grader's worker.

:class:`RemoteRun` is a :class:`~thymio_bt.run.runner.Run` whose tree is a stand-in: each tick it
sends the robot's readings, odometry and clock, and takes back the drive command, the entity
requests, the tree's status and events. What comes back is untrusted data: sizes are capped (by
:mod:`.wire`), numbers must be finite, node paths must be the plan's, events of the entities and of
collisions are the simulator's own (a submission's are dropped), and silence past the run's
wall-clock limit fails the run naming the node that was running.
"""

from __future__ import annotations

import itertools
import math
import os
import time
from typing import Any

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours.base import node_path, snapshot
from thymio_bt.enums import FailureCode
from thymio_bt.errors import ThymioBtError
from thymio_bt.geometry import Pose
from thymio_bt.grade.isolation import Limits, RunLimit
from thymio_bt.grade.sandboxes import Sandbox
from thymio_bt.grade.wire import MAX_DRIVES, Deadline, WireError, is_json, observation_frame, read_json, read_reply
from thymio_bt.logs.entries import STATUS_LETTER
from thymio_bt.robot.interface import SENSOR_NAMES, Request, RequestState
from thymio_bt.run.result import EndKind, RunOutcome, RunResult, RunStatus
from thymio_bt.run.runner import Run

#: events only the simulator says (a submission's of these kinds are dropped)
OWN_EVENTS = frozenset({"delete_entity", "spawn_entity", "collision"})
#: at most this many events, entity requests per tick, characters in a text from a submission
MAX_EVENTS, MAX_REQUESTS, MAX_TEXT = 20_000, 8, 500
#: a status letter of the wire (as a log writes it) -> the status
_STATUS_OF_LETTER = {letter: Status[name] for name, letter in STATUS_LETTER.items()}
#: how often (ticks; seconds while it is silent) the submission's CPU time is read
CPU_EVERY, CPU_POLL = 20, 0.25


class SubmissionFault(ThymioBtError):
    """The submission's process broke the run: its tree raised, or it sent what it must not."""


class RemoteRun(Run):
    """One run of ``mission`` (read here without running its plugins) against the submission's
    process in ``sandbox``; ``spec`` tells that process which mission to load and how."""

    def __init__(self, mission: Any, seed: int, sandbox: Sandbox, limits: Limits, spec: dict[str, Any]) -> None:
        from thymio_bt.run.coverage import plan_paths

        self.sandbox = sandbox
        self.limits = limits
        self.spec = spec
        self.paths = {path for _, path, _ in plan_paths(mission.tree)}
        self.deadline = math.inf
        super().__init__(mission, seed)
        self.shadow = self._shadow()
        self.shadow_nodes = {node_path(node): node for node in self.shadow.iterate()}

    def _build(self, substitutions: dict[str, Any] | None) -> Behaviour:
        return _Remote(self)

    def _shadow(self) -> Behaviour:
        """The mission's tree built here with stand-ins for its plugins (none of its code runs here),
        never ticked: the statuses the submission's process reports each tick are set on its nodes, so
        that a recording of the run (the grade site's replays) shows the tree as it ticked there."""
        from thymio_bt.mission import build_tree

        try:
            return build_tree(self.mission.tree, self.ctx, self.mission.registry)
        except Exception:  # a tree the grader cannot build: the run fails in the submission's process
            return self.root

    def shown_tree(self) -> Behaviour:
        """The tree a recording shows: the stand-in copy, with the statuses of the submission's tree."""
        return self.shadow

    def run(self, *args: Any, **kwargs: Any) -> RunResult:
        """Have the submission's process load its tree, run, then take its node statistics."""
        self.deadline = time.monotonic() + self.limits.wall
        self.cpu_start = _cpu(self.sandbox.pid)
        link = self.sandbox.link
        link.send({"run": self.spec})
        ready = self._receive()
        if "error" in ready:
            raise SubmissionFault(_text(ready["error"]))
        result = super().run(*args, **kwargs)
        link.send({"end": True, "t": self.backend.time()})
        final = self._receive()
        result.node_stats = self._stats(final.get("stats"))
        result.events += self.root.events(final.get("ev"))  # type: ignore[attr-defined]
        return result

    def _receive(self) -> dict[str, Any]:
        """The submission's next JSON message (a tick's frame here: :class:`SubmissionFault`)."""
        frame = self._receive_frame()
        if not is_json(frame):
            raise SubmissionFault("the submission's process sent a tick's reply out of turn")
        return read_json(frame)

    def _receive_frame(self) -> bytes:
        """The submission's next message but its slow-tick notes; its wall-clock or CPU limit (read
        every :data:`CPU_POLL` s while it is silent) is :class:`RunLimit`, naming the node it was in."""
        while True:
            try:
                frame = self.sandbox.link.receive_frame(min(self.deadline, time.monotonic() + CPU_POLL))
                if not is_json(frame) or b'"slow"' not in frame:
                    return frame
                message = read_json(frame)
                if "slow" not in message:
                    return frame
                slow = message["slow"]  # a tick is taking long: the node it is in
                if isinstance(slow, str) and slow in self.paths and isinstance(self.root, _Remote):
                    self.root.tip_path = slow
                if time.monotonic() >= self.deadline:  # (notes sent without end are no way out)
                    raise Deadline("")
            except Deadline:
                if time.monotonic() >= self.deadline:
                    self._limit(f"went over its wall-clock time limit of {self.limits.wall:g} s")
                self.check_cpu()

    def check_cpu(self) -> None:
        """:class:`RunLimit` when the submission's process used more CPU than the run may."""
        if _cpu(self.sandbox.pid) - self.cpu_start > self.limits.cpu:
            self._limit(f"used more than its CPU time limit of {self.limits.cpu:g} s")

    def _limit(self, what: str) -> None:
        where = self.root.tip_path if isinstance(self.root, _Remote) else None
        raise RunLimit(f"the run {what}" + (f", in '{where}'" if where else ""))

    def _stats(self, rows: Any) -> dict[str, Any]:
        if not isinstance(rows, dict):
            return {}
        out = {}
        for path, row in list(rows.items())[: len(self.paths)]:
            if path in self.paths and isinstance(row, dict):
                counts = {k: row.get(k) for k in ("ticks", "successes", "failures", "running_time", "running")}
                if all(isinstance(v, int | float) and math.isfinite(v) and v >= 0 for v in counts.values()):
                    ended = row.get("ended_by")
                    ended_by = (
                        {k: int(v) for k, v in ended.items() if k in self.paths and isinstance(v, int) and v >= 0}
                        if isinstance(ended, dict)
                        else {}
                    )
                    out[path] = {**counts, "ended_by": ended_by}
        return out

    def _end_of_run(self, ending: Any, interrupts: Any) -> RunOutcome:
        remote: _Remote = self.root  # type: ignore[assignment]
        if ending.kind is EndKind.FINISHED:
            if remote.status is Status.FAILURE:
                path, code, reason = remote.failure
                return RunOutcome(RunStatus.FAILURE, reason, code, path)
            return RunOutcome(RunStatus.SUCCESS)
        said = self._cut_short_reason(ending, interrupts)
        return RunOutcome(ending.kind.report_status, said, ending.code, ending.failed_path or remote.tip_path)


class _Remote(Behaviour):
    """The stand-in root: a tick is one exchange with the submission's process."""

    def __init__(self, run: RemoteRun) -> None:
        super().__init__(name=run.mission.tree.name)
        self.run = run
        self.tip_path: str | None = None
        self.failure: tuple[str | None, FailureCode | str, str] = (None, FailureCode.FAILED, "the tree failed")
        self.pending: dict[int, tuple[Request, dict[str, Any]]] = {}
        self.served: list[list[Any]] = []
        self.count = 0
        self.events_taken = 0

    def update(self) -> Status:
        run, backend = self.run, self.run.backend
        self._serve()
        self.count += 1
        if self.count % CPU_EVERY == 0:
            run.check_cpu()
        pose, velocity, command = backend.pose(), backend.velocity(), backend.command()
        scan = backend.proximity()
        frame = observation_frame(
            (
                backend.time(),
                backend.exists(),
                pose is not None,
                scan is not None,
                *((pose.x, pose.y, pose.yaw) if pose is not None else _NO_POSE),
                *([_finite_or_inf(scan.get(n)) for n in SENSOR_NAMES] if scan is not None else _NO_SCAN),
                velocity.linear,
                velocity.angular,
                command.linear,
                command.angular,
                len(backend.collisions),
            ),
            self.served,
        )
        self.served = []
        try:
            run.sandbox.link.send_frame(frame)
        except WireError as exc:
            raise SubmissionFault(str(exc)) from None
        reply = run._receive_frame()  # (a process that ended: WireError, the run crashed)
        try:
            status, drives, rest = read_reply(reply)
        except WireError as exc:
            raise SubmissionFault(str(exc)) from None
        return self._take(status, drives, rest)

    def _take(self, name: str, drives: list[tuple[float, float]], reply: dict[str, Any]) -> Status:
        """Apply a reply (its drives finite, the rest checked here): the commands, the requests,
        the events; the tree's status."""
        run, backend = self.run, self.run.backend
        if "x" in reply:
            raise SubmissionFault(_text(reply["x"]))
        for linear, angular in drives[:MAX_DRIVES]:
            backend.drive(linear, angular)
        if "q" in reply:
            for request in _list(reply["q"])[:MAX_REQUESTS]:
                self._request(request)
        if "ev" in reply:
            run.events.extend(self.events(reply["ev"]))
        if "n" in reply and isinstance(reply["n"], dict):
            self._statuses(reply["n"])
        if "tip" in reply:
            tip = reply["tip"]
            self.tip_path = tip if isinstance(tip, str) and tip in run.paths else None
        status = Status[name]
        if status is Status.FAILURE:
            failure = _list(reply.get("f")) + [None, None, None]
            path = failure[0] if failure[0] in run.paths else None
            self.failure = (path, _text(failure[1] or "FAILED")[:40], _text(failure[2] or "the tree failed"))
        return Status.RUNNING if status is Status.INVALID else status

    def _statuses(self, changed: dict[Any, Any]) -> None:
        """The node statuses that changed in the submission's tree this tick, set on the shadow tree's
        nodes: only the plan's paths and the four statuses are taken, the rest is dropped."""
        nodes = self.run.shadow_nodes
        for path, letter in itertools.islice(changed.items(), len(nodes)):
            node, status = nodes.get(path), _STATUS_OF_LETTER.get(letter) if isinstance(letter, str) else None
            if node is not None and status is not None:
                node.status = status

    def _request(self, request: Any) -> None:
        """An entity request from the tree: served by the simulator, answered in the next observation."""
        backend = self.run.backend
        if not (isinstance(request, list) and len(request) == 6 and isinstance(request[0], int)):
            return
        key, kind, entity, x, y, yaw = request
        if not (isinstance(entity, str) and len(entity) <= 64 and all(_finite(v) for v in (x, y, yaw))):
            return
        if kind == "delete":
            before = snapshot(backend)
            self.pending[key] = (backend.request_delete(entity), {"entity": entity, **before})
        elif kind == "spawn":
            pose = Pose(float(x), float(y), float(yaw))
            fields = {"entity": entity, "pose": {k: round(v, 6) for k, v in pose.as_dict().items()}}
            self.pending[key] = (backend.request_spawn(entity, pose), fields)

    def _serve(self) -> None:
        """The requests the simulator served since the last tick: their answers, their events."""
        for key, (request, fields) in list(self.pending.items()):
            if request.state is RequestState.PENDING:
                continue
            del self.pending[key]
            self.served.append([key, request.state.value, request.reason])
            if request.state is RequestState.SUCCEEDED:
                self.run.events.emit(self.run.backend.time(), f"{request.kind}_entity", **fields)

    def events(self, events: Any) -> list[dict[str, Any]]:
        """The submission's events that may be kept: checked, capped, none of the simulator's kinds."""
        now = self.run.backend.time() + 1e-9
        kept = []
        for event in _list(events):
            if self.events_taken >= MAX_EVENTS:
                break
            if not (isinstance(event, dict) and isinstance(event.get("kind"), str) and _finite(event.get("t"))):
                continue
            if event["kind"] in OWN_EVENTS or not 0 <= event["t"] <= now or len(repr(event)) > 4 * MAX_TEXT:
                continue
            kept.append(event)
            self.events_taken += 1
        return kept


def _finite_or_inf(value: Any) -> float:
    """A range as the submission reads it (inf: nothing in range, or no number)."""
    return float(value) if _finite(value) else math.inf


_NO_POSE, _NO_SCAN = (0.0,) * 3, (math.inf,) * len(SENSOR_NAMES)


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _list(value: Any) -> list[Any]:
    return value if isinstance(value, list) else []


def _text(value: Any) -> str:
    return str(value)[:MAX_TEXT]


def _cpu(pid: int) -> float:
    """The CPU seconds process ``pid`` used so far (0 when it cannot be read)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            fields = stat.read().rsplit(b")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0
