"""Two runs of one mission side by side: each behaviour's end, matched between them, and by how much
they differ; whether that is within the tolerances a CI job holds (``thymio-bt compare``).

A phase is one end of a behaviour (a ``behaviour_end`` event), matched between the runs by its
node path and occurrence (the 2nd end of ``course/part 2/leg/approach/MoveUntilWall`` in A meets
the 2nd in B). Each phase gives its time, pose (the logged pose of that tick: ground truth where the
backend has it), and the gaps the behaviour was about: the front
range it stopped at (``front``), the angle a turn turned (``turned_deg``, measured on the logged
poses), the side readings at the end of a leg (``left``, ``right``). Lengths are metres, times
seconds, angles (``yaw_deg``, ``turned_deg``) degrees.

Example:

>>> t = Tolerances.parse("gap=5mm,angle=2deg")
>>> t.gap, round(math.degrees(t.angle), 6), t.position, t.time
(0.005, 2.0, 0.01, 0.5)
>>> Tolerances.parse("speed=3")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: --tolerance: unknown tolerance 'speed' (hint: position, angle, gap, time: ...)
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import Any, TypedDict

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.units import UnitError, parse_value
from thymio_bt.logs.entries import checked_events, finite
from thymio_bt.logs.recording import Recording
from thymio_bt.run.divergence import Divergence, first_divergence

#: the unit kind each tolerance takes, and which phase values it bounds
BOUNDS = {
    "position": ("length", ("position",)),
    "angle": ("angle", ("yaw_deg", "turned_deg")),
    "gap": ("length", ("front", "left", "right")),
    "time": ("time", ("time",)),
}


@dataclass(frozen=True)
class Tolerances:
    """How far two runs may be apart and still agree: ``position`` (m, also the divergence's pose
    distance), ``angle`` (rad, also the divergence's heading), ``gap`` (m, a reading) and ``time`` (s)."""

    position: float = 0.01
    angle: float = math.radians(5)
    gap: float = 0.01
    time: float = 0.5

    @classmethod
    def parse(cls, text: str | None) -> Tolerances:
        """``gap=5mm,angle=2deg,...`` over the defaults; a :class:`UserError` says what is wrong."""
        values: dict[str, float] = {}
        for item in (text or "").split(","):
            if not item.strip():
                continue
            name, sep, raw = (part.strip() for part in item.partition("="))
            hint = "position, angle, gap, time: e.g. gap=5mm,angle=2deg"
            if name not in BOUNDS or not sep:
                what = f"unknown tolerance '{name}'" if sep else f"expected NAME=VALUE, got '{item.strip()}'"
                raise UserError(Problem(what, "--tolerance", hint=hint))
            try:
                quantity = parse_value(raw)
            except UnitError as exc:
                raise UserError(Problem(f"{name}: {exc}", "--tolerance", hint=exc.hint or hint)) from None
            kind = BOUNDS[name][0]
            if quantity.kind not in (kind, None) or quantity.value < 0:
                raise UserError(Problem(f"{name}: '{raw}' is not a {kind} >= 0", "--tolerance", hint=hint))
            values[name] = quantity.value
        return cls(**values)

    def limit(self, key: str) -> float | None:
        """The bound on the phase value ``key`` in its unit (angles in degrees), None when unbounded."""
        for name, (_, keys) in BOUNDS.items():
            if key in keys:
                value: float = getattr(self, name)
                return math.degrees(value) if name == "angle" else value
        return None


class PhaseEnd(TypedDict, total=False):
    """One behaviour end of a run: what ended and how, when, where (the logged pose, yaw in degrees),
    and the gaps the behaviour was about, those it has (lengths in m, angles in degrees)."""

    kind: str
    status: str
    time: float
    x: float
    y: float
    yaw_deg: float
    front: float
    turned_deg: float
    left: float
    right: float


#: B's values minus A's (``position``: how far apart; ``status``: ``"SUCCESS -> FAILURE"`` when they differ)
Difference = dict[str, float | str]


@dataclass(frozen=True)
class Phase:
    """A behaviour end matched between the runs: its node path and occurrence (from 1), its end in
    each run (None: not in that one) and their difference (None unless in both)."""

    node: str
    occurrence: int
    a: PhaseEnd | None
    b: PhaseEnd | None
    diff: Difference | None

    def to_json(self) -> dict[str, Any]:
        """A row of ``compare --json``'s ``phases``."""
        return {"node": self.node, "occurrence": self.occurrence, "a": self.a, "b": self.b, "diff": self.diff}


@dataclass
class Comparison:
    """The phase table of two runs, their first divergence, and the phases past the tolerances."""

    phases: list[Phase]
    divergence: Divergence | None
    #: "node #occurrence: key" of each value past its tolerance, or "node #n: only in A"
    exceeded: list[str] = field(default_factory=list)

    @property
    def agree(self) -> bool:
        """Whether the runs agree within the tolerances (``compare`` exits 0)."""
        return not self.exceeded

    def to_json(self) -> dict[str, Any]:
        """``compare --json``: ``{"phases": [...], "divergence": {...} | null}``."""
        divergence = None if self.divergence is None else self.divergence.to_json()
        return {"phases": [p.to_json() for p in self.phases], "divergence": divergence}


def compare(a: Recording, b: Recording, tolerances: Tolerances | None = None) -> Comparison:
    """Match the phases of ``a`` and ``b``, measure their differences, find the first divergence."""
    tolerances = tolerances or Tolerances()
    ends_a, ends_b = phase_values(a), phase_values(b)
    keys = list(ends_a) + [k for k in ends_b if k not in ends_a]
    phases, exceeded = [], []
    for node, occurrence in keys:
        va, vb = ends_a.get((node, occurrence)), ends_b.get((node, occurrence))
        diff = None if va is None or vb is None else _difference(va, vb)
        phases.append(Phase(node, occurrence, va, vb, diff))
        if diff is None:
            exceeded.append(f"{node} #{occurrence}: only in {'A' if vb is None else 'B'}")
            continue
        if "status" in diff:
            exceeded.append(f"{node} #{occurrence}: status")
        for key, value in diff.items():
            limit = tolerances.limit(key)
            if isinstance(value, float | int) and limit is not None and abs(value) > limit + 1e-9:
                exceeded.append(f"{node} #{occurrence}: {key}")
    found = first_divergence(a, b, distance=tolerances.position, angle=tolerances.angle)
    return Comparison(phases, found, exceeded)


def phase_values(recording: Recording) -> dict[tuple[str, int], PhaseEnd]:
    """Each behaviour end of a run by (node path, occurrence from 1), in the order they ended."""
    times = [s["t"] for s in recording.samples]
    started: dict[str, float] = {}
    seen: dict[str, int] = {}
    out: dict[tuple[str, int], PhaseEnd] = {}
    for event in checked_events(recording.events):
        path = str(event.get("path", ""))
        if event.get("kind") == "behaviour_start":
            started[path] = event["t"]
        if event.get("kind") != "behaviour_end":
            continue
        seen[path] = seen.get(path, 0) + 1
        values: PhaseEnd = {"kind": str(event.get("name")), "status": str(event.get("status")), "time": event["t"]}
        pose = _pose_at(recording, times, event["t"]) or event.get("pose")  # ground truth where logged
        if pose:
            values["x"], values["y"], values["yaw_deg"] = pose["x"], pose["y"], round(math.degrees(pose["yaw"]), 4)
        if event.get("range") is not None:
            values["front"] = event["range"]
        if event.get("angle") is not None and pose and path in started:
            before = _pose_at(recording, times, started[path])
            if before is not None:
                # not wrap_angle: math.remainder is exact where wrap_angle rounds (kept: the same bits as before)
                values["turned_deg"] = round(math.degrees(math.remainder(pose["yaw"] - before["yaw"], math.tau)), 4)
        prox = event.get("proximity")
        prox = prox if isinstance(prox, dict) else {}
        left, right = finite(prox.get("front_left")), finite(prox.get("front_right"))
        if "turned_deg" not in values and left is not None and right is not None:
            values["left"], values["right"] = left, right
        out[(path, seen[path])] = values
    return out


def _text(value: Any) -> str | None:
    """A name or status from an event: a string, else None."""
    return value if isinstance(value, str) else None


def _pose_at(recording: Recording, times: list[float], t: float) -> dict[str, float] | None:
    """The logged pose of the last tick at or before ``t``."""
    i = bisect.bisect_right(times, t + 1e-9) - 1
    return recording.samples[i].get("pose") if i >= 0 else None


def _difference(a: PhaseEnd, b: PhaseEnd) -> Difference:
    """B's values minus A's, for the numbers both have (``position``: how far apart the poses are;
    angles wrapped to ±180 degrees); a status that differs is ``"status": "SUCCESS -> FAILURE"``."""
    diff: Difference = {}
    for key, va in a.items():
        vb = b.get(key)
        if isinstance(va, (int, float)) and isinstance(vb, (int, float)):
            d = vb - va
            # not wrap_angle: these are degrees (and math.remainder is exact where wrap_angle rounds)
            diff[key] = round(math.remainder(d, 360.0) if key.endswith("_deg") else d, 6)
    dx, dy = diff.get("x"), diff.get("y")
    if isinstance(dx, float | int) and isinstance(dy, float | int):
        diff["position"] = round(math.hypot(dx, dy), 6)
    if a.get("status") != b.get("status"):
        diff["status"] = f"{a.get('status')} -> {b.get('status')}"
    return diff
