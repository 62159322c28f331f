"""Where two runs of one mission part ways: the first tick their trees or their robots differ.

Two recordings (two seeds, the simulator and the Playground, a log and its what-if replay) are
aligned by simulated time, tick by tick; the first tick where a node's status differs, or the
poses differ by more than ``distance`` metres or ``angle`` radians, is their :class:`Divergence`.
The poses compared are each log's ``pose``: the ground truth where the backend has one (the
simulator, the Playground), else the odometry (a real Thymio, ROS 2), which the divergence says.

Example (the same mission on two noise seeds):

>>> from thymio_bt.logs.recording import Recorder
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> noise = {"noise.wheel": "0.027", "noise.range_sd": "0.001"}
>>> def record(seed):
...     recorder = Recorder(statuses=True)
...     return recorder.finish(Run(load_mission("maze_part1_2", noise), seed=seed).run(on_tick=recorder))
>>> one = record(1)
>>> first_divergence(one, one) is None
True
>>> found = first_divergence(one, record(2))
>>> found.time, found.reason
(8.6, 'course/part 2/leg/approach/MoveUntilWall: RUNNING in A, SUCCESS in B (and 3 more)')
>>> found.a.running, found.b.running
(['course/part 2/leg/approach/MoveUntilWall'], ['course/part 2/leg/stop or turn/turn/centre axle'])
>>> list(found.to_json()["a"])
['tick', 'time', 'running', 'pose', 'pose_source', 'cmd']
"""

from __future__ import annotations

import bisect
import math
from dataclasses import asdict, dataclass
from typing import Any

from thymio_bt.enums import STATUS_LETTER
from thymio_bt.logs.entries import TickRecord
from thymio_bt.logs.recording import Recording

#: the status letters of logs (:data:`~thymio_bt.enums.STATUS_LETTER`) in words
STATUS_WORD = {letter: word for word, letter in STATUS_LETTER.items()}
#: backends whose logged pose is the ground truth; any other logs its odometry there
GROUND_TRUTH = frozenset({"sim", "playground"})


@dataclass(frozen=True)
class RunAt:
    """What one run's tree and robot were doing at a tick: its own ``tick`` and ``time``, the
    running node paths, the logged pose (None: no robot) and what it is (``pose_source``), the
    command (``[linear, angular]``, None where the log has none)."""

    tick: int
    time: float
    running: list[str]
    pose: dict[str, float] | None
    pose_source: str
    cmd: list[float] | None

    def to_json(self) -> dict[str, Any]:
        """As ``compare --json`` writes it (the fields, in their order)."""
        return asdict(self)


@dataclass(frozen=True)
class Divergence:
    """The first tick two runs differ: ``time`` (simulated s) and ``tick`` of run A there, ``reason``
    in words, and what each run's tree and robot were doing (``a``, ``b``)."""

    time: float
    tick: int
    reason: str
    a: RunAt
    b: RunAt

    def mark(self) -> dict[str, Any]:
        """What a run's page marks of it (:mod:`thymio_bt.viz.page`): ``time``, ``tick``, ``reason``."""
        return {"time": self.time, "tick": self.tick, "reason": self.reason}

    def to_json(self) -> dict[str, Any]:
        """The ``divergence`` object of ``compare --json``: ``time``, ``tick``, ``reason``, ``a``, ``b``."""
        return {
            "time": self.time,
            "tick": self.tick,
            "reason": self.reason,
            "a": self.a.to_json(),
            "b": self.b.to_json(),
        }


def pose_source(recording: Recording) -> str:
    """What a log's poses are: ``ground truth``, ``odometry``, or ``as logged`` (an older log that
    does not say which backend wrote it)."""
    backend = recording.header.get("backend")
    if backend is None:
        return "as logged"
    return "ground truth" if backend in GROUND_TRUTH else "odometry"


def first_divergence(
    a: Recording, b: Recording, *, distance: float = 0.01, angle: float = math.radians(5)
) -> Divergence | None:
    """The first tick where ``a`` and ``b`` differ (a node's status, or the poses by more than
    ``distance`` m or ``angle`` rad), or None when they agree to the end of both. Ticks are matched
    by simulated time; when the tick rates differ, each tick of ``a`` meets ``b``'s nearest, and
    the reason says so. A run that ends while the other goes on diverges where it ended."""
    rates = (a.header.get("tick_hz"), b.header.get("tick_hz"))
    note = f" (tick rates differ: {rates[0]:g} Hz in A, {rates[1]:g} Hz in B; nearest ticks compared)"
    note = note if None not in rates and rates[0] != rates[1] else ""
    sources = (pose_source(a), pose_source(b))
    times = [s["t"] for s in b.samples]
    for sa in a.samples:
        sb = _nearest(b.samples, times, sa["t"])
        if sb is None:
            break
        reason = _status_difference(sa, sb) or _pose_difference(sa, sb, sources, distance, angle)
        if reason:
            return _divergence(sa, sb, reason + note, sources)
    return _ending_difference(a, b, sources, note)


def _nearest(samples: list[TickRecord], times: list[float], t: float) -> TickRecord | None:
    """The sample of ``samples`` (sorted by ``times``) nearest ``t``, None past the last one."""
    if not samples or t > times[-1] + 1e-6:
        return None
    i = bisect.bisect_left(times, t - 1e-6)
    if i > 0 and (i == len(times) or abs(times[i - 1] - t) <= abs(times[i] - t)):
        i -= 1
    return samples[i]


def running_paths(sample: TickRecord) -> list[str]:
    """The running leaves of a tick: full node paths where the log has every node's status, else
    the names it logged."""
    nodes: dict[str, str] = sample.get("nodes") or {}
    if not nodes:
        return list(sample.get("running", []))
    running = [p for p, s in nodes.items() if s == "R"]
    return [p for p in running if not any(q.startswith(p + "/") for q in running)]


def _status_difference(sa: TickRecord, sb: TickRecord) -> str | None:
    """The deepest node whose status differs between two ticks, in words (the nodes both trees
    have; ticks without statuses compare their running leaves)."""
    na, nb = sa.get("nodes") or {}, sb.get("nodes") or {}
    if not (na and nb):
        ra, rb = running_paths(sa), running_paths(sb)
        return None if ra == rb else f"running {', '.join(ra) or 'nothing'} in A, {', '.join(rb) or 'nothing'} in B"
    differ = [p for p in na if p in nb and na[p] != nb[p]]
    deepest = [p for p in differ if not any(q.startswith(p + "/") for q in differ)]
    if not deepest:
        return None
    path = deepest[0]
    more = f" (and {len(deepest) - 1} more)" if len(deepest) > 1 else ""
    return f"{path}: {STATUS_WORD[na[path]]} in A, {STATUS_WORD[nb[path]]} in B{more}"


def _pose_difference(
    sa: TickRecord, sb: TickRecord, sources: tuple[str, str], distance: float, angle: float
) -> str | None:
    """How two ticks' poses differ past the tolerances, in words, or None."""
    pa, pb = sa.get("pose"), sb.get("pose")
    if pa is None or pb is None:
        return None if pa is pb else f"no robot in {'A' if pa is None else 'B'}"
    source = sources[0] if sources[0] == sources[1] else f"{sources[0]} in A, {sources[1]} in B"
    gap = math.hypot(pa["x"] - pb["x"], pa["y"] - pb["y"])
    if gap > distance:
        return f"poses {gap * 100:.1f} cm apart ({source})"
    # not wrap_angle: math.remainder is exact where wrap_angle rounds (kept: the same bits as before)
    turn = abs(math.remainder(pa["yaw"] - pb["yaw"], math.tau))
    if turn > angle:
        return f"headings {math.degrees(turn):.1f} degrees apart ({source})"
    return None


def _ending_difference(a: Recording, b: Recording, sources: tuple[str, str], note: str) -> Divergence | None:
    """Where one run ended while the other went on (None when both end on the same tick)."""
    if not a.samples or not b.samples:
        return None
    la, lb = a.samples[-1], b.samples[-1]
    if abs(la["t"] - lb["t"]) < 1e-6:
        return None
    shorter, longer, name, other = (a, b, "A", "B") if la["t"] < lb["t"] else (b, a, "B", "A")
    end = shorter.samples[-1]
    after = next(s for s in longer.samples if s["t"] > end["t"] + 1e-6)
    status = shorter.end.get("status", "INCOMPLETE")
    reason = f"run {name} ended at {end['t']:.1f} s ({status}), run {other} went on{note}"
    sa, sb = (end, after) if name == "A" else (after, end)
    return _divergence(sa, sb, reason, sources)


def _divergence(sa: TickRecord, sb: TickRecord, reason: str, sources: tuple[str, str]) -> Divergence:
    """The divergence at the ticks ``sa`` of A and ``sb`` of B."""
    return Divergence(sa["t"], sa["tick"], reason, _doing(sa, sources[0]), _doing(sb, sources[1]))


def _doing(sample: TickRecord, source: str) -> RunAt:
    """What a run's tree and robot were doing at one tick (a log's tick record), as the divergence shows it."""
    return RunAt(sample["tick"], sample["t"], running_paths(sample), sample.get("pose"), source, sample.get("cmd"))
