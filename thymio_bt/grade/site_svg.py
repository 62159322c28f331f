"""A variant's picture on a student's page: the maze's walls, the robot's path, where it went wrong.

Inline SVG drawn from the numbers of results.json (a run's ``trajectory`` of ``[t, x, y, yaw]``,
its criteria's ``moment``, its ``final_pose``) and the variant's maze file. The view is cropped to
where the robot went (plus a margin), so a small part of a big maze stays readable; a respawn (a
spawn event of the run) is drawn as a dashed jump, not as a path through walls.

Example (no maze file: the path alone):

>>> run = {"status": "FAILURE", "code": "TIMEOUT", "criteria": {}, "final_pose": {"x": 0.3, "y": 0.12, "yaw": 0.1},
...        "trajectory": [[0, 0.1, 0.1, 0], [1, 0.2, 0.1, 0], [2, 0.3, 0.12, 0.1]]}
>>> svg, marks = trajectory_svg(None, {"name": "course"}, [run])
>>> svg.startswith("<svg"), svg.count("<polyline"), [(m.number, m.text) for m in marks]
(True, 1, [(1, 'at the end: ended FAILURE: TIMEOUT')])
>>> split_jumps([(0, 0, 0), (0.5, 0.05, 0), (1.0, 0.5, 0.3), (1.5, 0.51, 0.3)], spawns=[0.9])
[[(0, 0), (0.05, 0)], [(0.5, 0.3), (0.51, 0.3)]]
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from thymio_bt.errors import UserError
from thymio_bt.grade.site_page import as_dict, as_list, esc, fmt, num
from thymio_bt.maze.files import load_maze, resolve_maze
from thymio_bt.maze.model import Maze

WIDTH, HEIGHT = 560.0, 440.0  # the largest picture, px
PAD = 14.0  # px around the view
MARGIN = 0.12  # m of maze shown around where the robot went
JUMP_SPEED = 0.5  # m/s: over twice a Thymio's top speed, so a respawn (or a teleport), not a path
MERGE = 0.03  # m: one mark for the runs that missed a criterion this close to each other
SCALE_BAR = 18.0  # px below the maze for the scale bar

Point = tuple[float, float]


def load_mazes(assignment: dict[str, Any]) -> dict[str, Maze | str]:
    """Each variant's maze by variant name, or why it could not be read (a picture then has no walls).

    A relative path is looked up beside the assignment file, then from the current folder, then as
    a maze name (``two_parts_maze``), as missions name them."""
    base = Path(str(assignment.get("file") or ".")).parent
    mazes: dict[str, Maze | str] = {}
    by_ref: dict[str, Maze | str] = {}
    for variant in as_list(assignment.get("variants")):
        variant = as_dict(variant)
        ref = variant.get("maze")
        if not isinstance(ref, str) or not ref:
            mazes[str(variant.get("name"))] = "no maze named"
            continue
        if ref not in by_ref:
            try:
                by_ref[ref] = load_maze(resolve_maze(ref, relative_to=base))
            except UserError as exc:
                by_ref[ref] = f"the maze {ref} could not be read: {exc}"
            except OSError as exc:
                by_ref[ref] = f"the maze {ref} could not be read: {exc.strerror or exc}"
        mazes[str(variant.get("name"))] = by_ref[ref]
    return mazes


def samples(run: dict[str, Any]) -> list[tuple[float, float, float]]:
    """A run's trajectory as (t, x, y), the malformed samples left out."""
    out = []
    for sample in as_list(run.get("trajectory")):
        values = [num(v) for v in as_list(sample)[:3]]
        if len(values) == 3 and all(v is not None for v in values):
            t, x, y = values
            assert t is not None and x is not None and y is not None
            out.append((t, x, y))
    return out


def split_jumps(
    points: Sequence[tuple[float, float, float]], spawns: Sequence[float] | None = None
) -> list[list[Point]]:
    """The path cut at each respawn: where a ``spawns`` time (the run's spawn events) falls between
    two samples; for results without them, where the robot moved faster than :data:`JUMP_SPEED`.
    The pieces."""
    pieces: list[list[Point]] = []
    for i, (t, x, y) in enumerate(points):
        if i:
            t0, x0, y0 = points[i - 1]
            if spawns is not None:
                jumped = any(t0 < s <= t for s in spawns)
            else:
                step = math.hypot(x - x0, y - y0)
                jumped = step > 0.02 and step > JUMP_SPEED * max(t - t0, 0.0)
            if jumped:
                pieces.append([])
        if not pieces:
            pieces.append([])
        pieces[-1].append((x, y))
    return pieces


def _pose(value: Any) -> tuple[float, float, float | None] | None:
    """(x, y, yaw or None) of a ``{x, y, yaw}`` mapping, or None."""
    pose = as_dict(value)
    x, y = num(pose.get("x")), num(pose.get("y"))
    return None if x is None or y is None else (x, y, num(pose.get("yaw")))


def failure_marks(run: dict[str, Any]) -> list[tuple[float, float, str, str]]:
    """Where ``run`` went wrong: each failed criterion at its ``moment``; at the run's last pose, the
    failed criteria without a moment and how the run ended if it did not succeed. Each is
    (x, y, what: a criterion's name or '' for the end, text)."""
    marks, at_end = [], []
    for name, verdict in as_dict(run.get("criteria")).items():
        verdict = as_dict(verdict)
        if verdict.get("passed") is not False:
            continue
        moment = _pose(verdict.get("moment"))
        feedback = verdict.get("feedback")
        if moment is None:
            at_end.append(str(name) + (f": {feedback}" if feedback else ""))
            continue
        t = fmt(as_dict(verdict.get("moment")).get("t"), 1)
        marks.append((moment[0], moment[1], str(name), f"{name} at t = {t} s" + (f": {feedback}" if feedback else "")))
    if run.get("status") not in (None, "SUCCESS"):
        why = " ".join(str(v) for v in (run.get("code"), run.get("reason")) if v)
        at_end.append(f"ended {run.get('status')}" + (f": {why}" if why else ""))
    last = _pose(run.get("final_pose"))
    points = samples(run)
    if last is None and points:
        last = (points[-1][1], points[-1][2], None)
    if at_end and last is not None:
        marks.append((last[0], last[1], "", "at the end: " + "; ".join(at_end)))
    return marks


def start_pose(value: Any, maze: Maze | None) -> tuple[float, float, float | None] | None:
    """A variant's start: ``{x, y, yaw}``, ``"x,y,yaw"`` (metres, radians) or a spawn of the maze."""
    if isinstance(value, str):
        numbers = value.split(",")
        if len(numbers) == 3:
            try:
                x, y, yaw = (float(n) for n in numbers)
            except ValueError:
                return None
            return (x, y, yaw) if all(map(math.isfinite, (x, y, yaw))) else None
        if maze is not None and value in maze.spawns:
            pose = maze.spawn(value)
            return (pose.x, pose.y, pose.yaw)
        return None
    return _pose(value)


def _yaw(run: dict[str, Any], index: int) -> float | None:
    """The heading of a run's trajectory sample ``index``, if it has one."""
    sample = as_list(as_list(run.get("trajectory"))[index])
    return num(sample[3]) if len(sample) > 3 else None


class _View:
    """World metres to picture pixels (y up in the world, down on the screen)."""

    def __init__(self, box: tuple[float, float, float, float]) -> None:
        x0, y0, x1, y1 = box
        self.x0, self.y1 = x0, y1
        self.scale = min((WIDTH - 2 * PAD) / max(x1 - x0, 1e-3), (HEIGHT - 2 * PAD) / max(y1 - y0, 1e-3))
        self.width = (x1 - x0) * self.scale + 2 * PAD
        self.height = (y1 - y0) * self.scale + 2 * PAD + SCALE_BAR

    def __call__(self, x: float, y: float) -> str:
        return f"{(x - self.x0) * self.scale + PAD:.1f},{(self.y1 - y) * self.scale + PAD:.1f}"

    def xy(self, x: float, y: float) -> tuple[float, float]:
        """The pixel position of a world point."""
        return (x - self.x0) * self.scale + PAD, (self.y1 - y) * self.scale + PAD


def _view_box(maze: Maze | None, points: list[Point]) -> tuple[float, float, float, float]:
    """What to show: where the robot went plus :data:`MARGIN`, within the maze; else the maze."""
    bounds = maze.bounds() if maze is not None and maze.shapes() else None
    if not points:
        return bounds or (-0.5, -0.5, 0.5, 0.5)
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    box = (min(xs) - MARGIN, min(ys) - MARGIN, max(xs) + MARGIN, max(ys) + MARGIN)
    if bounds is not None:
        box = (max(box[0], bounds[0]), max(box[1], bounds[1]), min(box[2], bounds[2]), min(box[3], bounds[3]))
        if box[0] >= box[2] or box[1] >= box[3]:  # the robot left the maze entirely
            box = (min(xs + [bounds[0]]), min(ys + [bounds[1]]), max(xs + [bounds[2]]), max(ys + [bounds[3]]))
    return box


def _cross(view: _View, x: float, y: float, colour: str, title: str, label: str) -> str:
    """A failure mark: a ringed cross with a tooltip and its number beside it."""
    px, py = view.xy(x, y)
    return (
        f'<g class="fail-mark"><title>{esc(title)}</title>'
        f'<circle cx="{px:.1f}" cy="{py:.1f}" r="8" fill="#fff" fill-opacity="0.8" stroke="{colour}" stroke-width="2"/>'
        f'<path d="M{px - 4:.1f},{py - 4:.1f} L{px + 4:.1f},{py + 4:.1f} M{px - 4:.1f},{py + 4:.1f} '
        f'L{px + 4:.1f},{py - 4:.1f}" stroke="{colour}" stroke-width="2"/>'
        f'<text x="{px + 10:.1f}" y="{py - 8:.1f}" font-size="12" font-weight="700" fill="{colour}" '
        f'stroke="#fff" stroke-width="3" paint-order="stroke">{esc(label)}</text></g>'
    )


def _pose_mark(view: _View, pose: tuple[float, float, float | None], colour: str, title: str) -> str:
    """A robot pose: a disc and, when the heading is known, a line the way it faces."""
    px, py = view.xy(pose[0], pose[1])
    heading = ""
    if pose[2] is not None:
        hx, hy = px + 12 * math.cos(pose[2]), py - 12 * math.sin(pose[2])
        heading = f'<line x1="{px:.1f}" y1="{py:.1f}" x2="{hx:.1f}" y2="{hy:.1f}" stroke="{colour}" stroke-width="2"/>'
    return (
        f"<g><title>{esc(title)}</title>"
        f'<circle cx="{px:.1f}" cy="{py:.1f}" r="5" fill="{colour}" stroke="#fff" stroke-width="1.5"/>{heading}</g>'
    )


def _scale_bar(view: _View) -> str:
    """A 10 cm (or 1 m) bar in the bottom-left corner."""
    length = 0.1 if view.scale * 0.1 >= 30 else 1.0
    px = length * view.scale
    x, y = PAD, view.height - 7
    return (
        f'<g class="scale"><line x1="{x}" y1="{y:.1f}" x2="{x + px:.1f}" y2="{y:.1f}" stroke="#52606d" '
        f'stroke-width="2"/><text x="{x + px + 4:.1f}" y="{y + 1:.1f}" font-size="10" fill="#52606d">'
        f"{'10 cm' if length < 1 else '1 m'}</text></g>"
    )


class Mark:
    """One place where runs went wrong, numbered on the picture and explained below it."""

    __slots__ = ("number", "x", "y", "text", "seeds", "traced")

    def __init__(self, number: int, x: float, y: float, text: str) -> None:
        self.number, self.x, self.y, self.text = number, x, y, text
        self.seeds: list[str] = []
        self.traced = False

    @property
    def seed_text(self) -> str:
        """Which runs: ``seed 0`` or ``seeds 0, 1``."""
        return f"seed{'s' if len(self.seeds) > 1 else ''} {', '.join(self.seeds)}"

    @property
    def colour(self) -> str:
        """Red on the drawn run's path, orange for another seed's run (its path is not drawn)."""
        return "#c53030" if self.traced else "#dd6b20"


def collect_marks(runs: list[dict[str, Any]], traced: dict[str, Any] | None) -> list[Mark]:
    """The failure marks of ``runs``, the drawn run's first: runs (seeds) that missed the same
    criterion within :data:`MERGE` of each other share one mark, which keeps the first one's text."""
    marks: list[tuple[str, Mark]] = []
    ordered = ([traced] if traced is not None else []) + [r for r in runs if r is not traced]
    for run in ordered:
        for x, y, what, text in failure_marks(run):
            mark = next((m for w, m in marks if w == what and math.hypot(m.x - x, m.y - y) <= MERGE), None)
            if mark is None:
                mark = Mark(len(marks) + 1, x, y, text)
                marks.append((what, mark))
            if str(run.get("seed")) not in mark.seeds:
                mark.seeds.append(str(run.get("seed")))
            mark.traced |= run is traced
    return [m for _, m in marks]


def trajectory_svg(maze: Maze | None, variant: dict[str, Any], runs: list[dict[str, Any]]) -> tuple[str, list[Mark]]:
    """The picture of one variant for one student, and its numbered failure marks: ``runs`` are that
    student's runs of the variant; the path is the first one that carries a trajectory."""
    traced = next((r for r in runs if samples(r)), None)
    points = samples(traced) if traced is not None else []
    pieces = _pieces(traced, points)
    start = start_pose(variant.get("start"), maze) or _first_pose(traced, points)
    marks = collect_marks(runs, traced)
    seen = [(x, y) for piece in pieces for x, y in piece]
    seen += [(m.x, m.y) for m in marks] + ([start[:2]] if start else [])
    view = _View(_view_box(maze, seen))
    parts = [_head(view, str(variant.get("name") or "variant")), _walls(view, maze), _paths(view, pieces)]
    if start is not None:
        parts.append(_pose_mark(view, start, "#2f855a", "start pose"))
    if traced is not None:
        end = _pose(traced.get("final_pose")) or ((points[-1][1], points[-1][2], None) if points else None)
        if end is not None:
            parts.append(_pose_mark(view, end, "#1f2933", f"final pose (seed {traced.get('seed')})"))
    for mark in sorted(marks, key=lambda m: m.traced):  # the drawn run's marks on top
        title = f"{mark.number}. {mark.text} ({mark.seed_text})"
        parts.append(_cross(view, mark.x, mark.y, mark.colour, title, str(mark.number)))
    parts.append(_scale_bar(view))
    parts.append("</svg>")
    return "".join(parts), marks


def _pieces(traced: dict[str, Any] | None, points: list[tuple[float, float, float]]) -> list[list[Point]]:
    """The drawn run's path, split where it jumped (a respawn: at its ``spawns`` times when it has them)."""
    spawns = traced.get("spawns") if traced is not None else None
    return split_jumps(
        points, [t for t in as_list(spawns) if isinstance(t, (int, float))] if spawns is not None else None
    )


def _first_pose(
    traced: dict[str, Any] | None, points: list[tuple[float, float, float]]
) -> tuple[float, float, float | None] | None:
    """The drawn run's first pose, for a variant whose start is not known."""
    return (points[0][1], points[0][2], _yaw(traced, 0)) if traced is not None and points else None


def _head(view: _View, name: str) -> str:
    """The picture's ``<svg>`` element opened, its title and its background."""
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" class="trajectory" role="img" width="{view.width:.0f}" '
        f'height="{view.height:.0f}" viewBox="0 0 {view.width:.1f} {view.height:.1f}" '
        f'aria-label="{esc(f"the path of the robot in variant {name}")}">'
        f"<title>{esc(f'variant {name}')}</title>"
        f'<rect width="{view.width:.1f}" height="{view.height:.1f}" fill="#fbfcfd"/>'
    )


def _walls(view: _View, maze: Maze | None) -> str:
    """The maze's walls and obstacles as polygons ("" without a maze)."""
    if maze is None:
        return ""
    polygons = "".join(f'<polygon points="{" ".join(view(x, y) for x, y in s.corners())}"/>' for s in maze.shapes())
    return f'<g class="walls" fill="#334e68">{polygons}</g>'


def _paths(view: _View, pieces: list[list[Point]]) -> str:
    """The path's pieces as lines, and a dashed line for each jump between them (a respawn)."""
    jumps = []
    for before, after in zip(pieces, pieces[1:], strict=False):
        (x1, y1), (x2, y2) = view.xy(*before[-1]), view.xy(*after[0])
        jumps.append(
            f'<line class="jump" x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" stroke="#9aa5b1" '
            f'stroke-width="1.5" stroke-dasharray="4 4"><title>respawned</title></line>'
        )
    lines = [
        f'<polyline class="path" points="{" ".join(view(x, y) for x, y in piece)}" fill="none" '
        f'stroke="#2b6cb0" stroke-width="2.2" stroke-linejoin="round" stroke-linecap="round"/>'
        for piece in pieces
    ]
    return "".join(jumps + lines)
