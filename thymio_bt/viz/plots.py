"""Pictures of a run for lab reports: the path in the maze, the signals over time, an animation.

matplotlib is imported only here (it is the optional ``viz`` extra), with the Agg backend, so
plots work headless and a run that asks for none pays nothing.

``plot_signals(recording, "signals.png")`` takes a recording as ``plot_run`` does; the animation
(``--gif``) is :mod:`thymio_bt.viz.animation`, drawn on the same maze.

Example:

>>> import tempfile
>>> from thymio_bt.testing import recorded
>>> recording = recorded("square")
>>> with tempfile.TemporaryDirectory() as folder:
...     path = plot_run(recording, Path(folder) / "run.png")
...     path.name, path.read_bytes()[:4]
('run.png', b'\x89PNG')
>>> [round(a, 2) for a in unwrapped([3.0, -3.0, math.nan, -3.0])]  # no jump at ±pi; a gap restarts
[3.0, 3.28, nan, -3.0]
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from thymio_bt.errors import UserError
from thymio_bt.logs.recording import Recording
from thymio_bt.robot.model import COURSE
from thymio_bt.viz.display import INSTALL_HINT

#: twice the course robot's reach from base_link (m): two outlines whose base_links are farther apart never overlap
ROBOT_SPAN = 2 * max(math.hypot(x, y) for x, y in COURSE.hull)
KEY_EVENTS = {"delete_entity": ("tab:red", "deleted"), "spawn_entity": ("tab:green", "spawned")}


def pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend (headless); a :class:`UserError` when it is missing."""
    try:
        import matplotlib
    except ImportError:
        raise UserError(f"plots need matplotlib (hint: {INSTALL_HINT})") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def outline(pose: dict[str, float]) -> list[tuple[float, float]]:
    """The robot's outline (the course model's hull) at ``pose``, in maze coordinates."""
    c, s = math.cos(pose["yaw"]), math.sin(pose["yaw"])
    return [(pose["x"] + x * c - y * s, pose["y"] + x * s + y * c) for x, y in COURSE.hull]


def draw_maze(ax: Any, recording: Recording) -> None:
    """The maze's walls and obstacles on ``ax``, its limits holding the maze and the whole trajectory."""
    from matplotlib.patches import Polygon

    for wall in recording.maze.walls:
        ax.add_patch(Polygon(wall.corners(), closed=True, color="0.25", lw=0))
    for obstacle in recording.maze.obstacles:
        ax.add_patch(Polygon(obstacle.corners(), closed=True, color="tab:blue", alpha=0.6, lw=0))
    xmin, ymin, xmax, ymax = recording.maze.bounds()
    xs = [s["pose"]["x"] for s in recording.samples if s["pose"]]
    ys = [s["pose"]["y"] for s in recording.samples if s["pose"]]
    pad = 0.08
    ax.set_xlim(min([xmin, *xs]) - pad, max([xmax, *xs]) + pad)
    ax.set_ylim(min([ymin, *ys]) - pad, max([ymax, *ys]) + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, lw=0.3, alpha=0.5)


def _draw_cell_map(ax: Any, cells: dict[str, Any]) -> None:
    """What the mapping behaviours learnt: visited cells shaded, the walls they found drawn over the
    maze, each cell's steps to the goal over known openings, and the shortest known path."""
    c, (ox, oy) = cells["cell"], cells["origin"]
    for n, (i, j) in enumerate(cells["visited"]):
        ax.add_patch(
            pyplot().Rectangle(
                (ox + i * c, oy + j * c),
                c,
                c,
                color="tab:green",
                alpha=0.12,
                lw=0,
                label="cell visited (map)" if n == 0 else None,
            )
        )
    for n, (x0, y0, x1, y1) in enumerate(cells["walls"]):
        ax.plot([x0, x1], [y0, y1], color="tab:red", lw=2.2, alpha=0.8, label="wall on the map" if n == 0 else None)
    for i, j, steps in cells.get("distances", []):
        ax.annotate(
            str(steps),
            (ox + (i + 0.5) * c, oy + (j + 0.5) * c),
            ha="center",
            va="center",
            fontsize=5,
            color="tab:green",
            alpha=0.9,
        )
    path = cells.get("path", [])
    if len(path) > 1:
        ax.plot(
            [ox + (i + 0.5) * c for i, _ in path],
            [oy + (j + 0.5) * c for _, j in path],
            color="tab:green",
            lw=2.0,
            ls="--",
            alpha=0.9,
            zorder=5,
            label="shortest known path (map)",
        )


def _draw_robot(ax: Any, pose: dict[str, float], colour: str, label: str | None = None, alpha: float = 0.9) -> Any:
    from matplotlib.patches import Polygon

    patch = Polygon(outline(pose), closed=True, fill=False, ec=colour, lw=1.2, alpha=alpha, label=label)
    ax.add_patch(patch)
    return patch


def rays(
    pose: dict[str, float], prox: dict[str, float | None]
) -> list[tuple[tuple[float, float], tuple[float, float], bool]]:
    """Each sensor's ray at ``pose``: (start, end, whether it sees something), out to the range when not."""
    c, s = math.cos(pose["yaw"]), math.sin(pose["yaw"])
    out = []
    for name, x, y, a in ((s.name, s.x, s.y, s.yaw) for s in COURSE.sensors):
        reading = prox.get(name)
        length = COURSE.range_max if reading is None else reading
        ox, oy = pose["x"] + x * c - y * s, pose["y"] + x * s + y * c
        out.append(
            (
                (ox, oy),
                (ox + length * math.cos(pose["yaw"] + a), oy + length * math.sin(pose["yaw"] + a)),
                reading is not None,
            )
        )
    return out


def _segments(recording: Recording) -> list[list[dict[str, float]]]:
    """The trajectory (base_link's poses) split where the robot was deleted and respawned."""
    parts: list[list[dict[str, float]]] = [[]]
    for sample in recording.samples:
        pose = sample["pose"]
        if pose is None:
            if parts[-1]:
                parts.append([])
            continue
        if parts[-1] and math.dist((parts[-1][-1]["x"], parts[-1][-1]["y"]), (pose["x"], pose["y"])) > 0.05:
            parts.append([])
        parts[-1].append(pose)
    return [p for p in parts if p]


def plot_run(recording: Recording, path: str | Path, title: str | None = None) -> Path:
    """The maze, the trajectory, the robot at key events (delete, spawn, turns, end) and the final rays."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9, 5.5), dpi=110)
    draw_maze(ax, recording)
    if recording.end.get("map"):
        _draw_cell_map(ax, recording.end["map"])
    for i, part in enumerate(_segments(recording)):
        ax.plot(
            [pose["x"] for pose in part],
            [pose["y"] for pose in part],
            color="tab:blue",
            lw=1.4,
            label="trajectory (base_link)" if i == 0 else None,
        )
    marks = _EventMarks(ax)
    for event in recording.events:
        marks.draw(event)
    _draw_end(ax, recording)
    status = recording.end.get("status", "")
    ax.set_title(title or f"{recording.mission}: {status}, {recording.end.get('sim_time', 0):.1f} s simulated")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    return _save(fig, plt, path)


class _EventMarks:
    """Draws a run's events on its maze, each kind its own mark, each label once in the legend."""

    def __init__(self, ax: Any) -> None:
        from thymio_bt.plan.registry import default_registry

        self.ax = ax
        self.labelled: set[str] = set()
        self.turns: list[tuple[float, float]] = []  # where an outline after a turn is drawn: one per place
        #: the behaviours whose end is a turn (:attr:`~thymio_bt.behaviours.base.RobotBehaviour.reports`)
        self.turners = {name for name, cls in default_registry().behaviours() if cls.reports == "turn"}

    def draw(self, event: dict[str, Any]) -> None:
        """The mark of ``event``, if its kind has one."""
        mark = _MARKS.get(event["kind"])
        if mark is not None:
            mark(self, event)

    def _label(self, key: str, label: str) -> str | None:
        """``label`` the first time a mark of ``key`` is drawn, then None (one legend entry)."""
        first = key not in self.labelled
        self.labelled.add(key)
        return label if first else None

    def _outline(self, pose: dict[str, float], colour: str, label: str) -> None:
        _draw_robot(self.ax, pose, colour, self._label(label, label), alpha=0.7)

    def key_event(self, event: dict[str, Any]) -> None:
        """The robot's outline where it was deleted or spawned."""
        pose = event.get("pose")
        if pose:
            colour, label = KEY_EVENTS[event["kind"]]
            self._outline(pose, colour, label)

    def turn(self, event: dict[str, Any]) -> None:
        """The robot's outline after a turn that succeeded; a dot where an outline is drawn already
        (a cell-by-cell run turns in each cell up to four times): not outlines piled up."""
        pose = event.get("pose")
        if event.get("name") not in self.turners or event.get("status") != "SUCCESS" or not pose:
            return
        if any(math.dist(place, (pose["x"], pose["y"])) < ROBOT_SPAN for place in self.turns):
            self.ax.plot(pose["x"], pose["y"], ".", color="tab:orange", ms=4)
            return
        self.turns.append((pose["x"], pose["y"]))
        self._outline(pose, "tab:orange", "after a turn")

    def collision(self, event: dict[str, Any]) -> None:
        """A red cross where the robot hit something."""
        self.ax.plot(event["x"], event["y"], "x", color="red", ms=9, mew=2, label=self._label("collision", "collision"))

    def waypoint(self, event: dict[str, Any]) -> None:
        """A star at a waypoint reached, numbered from 1."""
        if "target" not in event:
            return
        x, y = event["target"]
        self.ax.plot(x, y, "*", color="tab:green", ms=11, label=self._label("waypoint", "waypoint reached"))
        self.ax.annotate(str(event["index"] + 1), (x, y), textcoords="offset points", xytext=(6, 6), fontsize=9)


#: the mark of each event kind drawn on the maze
_MARKS: dict[str, Callable[[_EventMarks, dict[str, Any]], None]] = {
    **dict.fromkeys(KEY_EVENTS, _EventMarks.key_event),
    "behaviour_end": _EventMarks.turn,
    "collision": _EventMarks.collision,
    "waypoint_reached": _EventMarks.waypoint,
}


def _draw_end(ax: Any, recording: Recording) -> None:
    """The robot's outline at its last pose, with its rays then (red where they hit)."""
    last = next((s for s in reversed(recording.samples) if s["pose"]), None)
    if last is None:
        return
    _draw_robot(ax, last["pose"], "black", "end")
    for start, end, hit in rays(last["pose"], last["prox"] or {}):
        ax.plot(
            [start[0], end[0]],
            [start[1], end[1]],
            color="tab:red" if hit else "0.6",
            lw=1.0,
            ls="-" if hit else ":",
        )


def _save(fig: Any, plt: Any, path: str | Path) -> Path:
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path)
    except (OSError, ValueError) as exc:
        raise UserError(f"cannot write {path}: {exc}") from None
    finally:
        plt.close(fig)
    return path


def unwrapped(angles: list[float]) -> list[float]:
    """Angles made continuous (no ±pi jumps drawn as vertical lines); a gap (NaN: no robot) restarts
    the unwrapping, since a respawned robot may face anywhere."""
    out: list[float] = []
    previous = math.nan
    for angle in angles:
        if not math.isnan(angle) and not math.isnan(previous):
            # not wrap_angle: math.remainder is exact where wrap_angle rounds (kept: the same bits as before)
            angle = previous + math.remainder(angle - previous, math.tau)
        out.append(angle)
        previous = angle
    return out


def _behaviour_spans(recording: Recording) -> list[tuple[float, float, str]]:
    """(start, end, name) of every robot behaviour that ran, from the start/end events."""
    open_: dict[str, tuple[float, str]] = {}
    spans = []
    for event in recording.events:
        if event["kind"] == "behaviour_start":
            open_[event["path"]] = (event["t"], event["name"])
        elif event["kind"] == "behaviour_end" and event["path"] in open_:
            start, name = open_.pop(event["path"])
            spans.append((start, event["t"], name))
    end = recording.end.get("sim_time", 0.0)
    spans += [(start, end, name) for start, name in open_.values()]
    return sorted(spans)


def plot_signals(recording: Recording, path: str | Path) -> Path:
    """The behaviours that ran (one row each, as bars over time), then pose, commanded and actual
    speeds, and proximity over simulated time. A row per behaviour keeps each name on its own line:
    behaviours that run at once (a parallel's) or one after the other in a blink never overlap."""
    plt = pyplot()
    samples = recording.samples
    t = [s["t"] for s in samples]
    spans = _behaviour_spans(recording)
    names = list(dict.fromkeys(name for _, _, name in sorted(spans)))  # in the order they first ran
    rows = max(len(names), 1)
    fig, axes = plt.subplots(
        5,
        1,
        figsize=(10, 8.5 + 0.22 * rows),
        dpi=100,
        sharex=True,
        gridspec_kw={"height_ratios": [0.22 * rows, 2, 1.6, 1.6, 2]},
    )
    ax = axes[0]
    colours = plt.get_cmap("tab10").colors
    for row, name in enumerate(names):
        bars = [(start, max(end - start, 0.05)) for start, end, span in spans if span == name]
        ax.broken_barh(bars, (row - 0.35, 0.7), color=colours[row % len(colours)])
    ax.set_yticks(range(len(names)), names, fontsize=8)
    ax.set_ylim(rows - 0.5, -0.5)
    ax.set_ylabel("running")

    def series(get: Any) -> list[float]:
        return [get(s) if s["pose"] else math.nan for s in samples]

    ax = axes[1]
    ax.plot(t, series(lambda s: s["pose"]["x"]), label="x [m]")
    ax.plot(t, series(lambda s: s["pose"]["y"]), label="y [m]")
    ax.plot(t, unwrapped(series(lambda s: s["pose"]["yaw"])), label="yaw [rad, unwrapped]")
    ax.set_ylabel("pose")
    ax = axes[2]
    ax.plot(t, [s["cmd"][0] for s in samples], label="commanded v", drawstyle="steps-post")
    ax.plot(t, [s["vel"][0] for s in samples], label="actual v", ls="--")
    ax.set_ylabel("linear [m/s]")
    ax = axes[3]
    ax.plot(t, [s["cmd"][1] for s in samples], label="commanded ω", drawstyle="steps-post")
    ax.plot(t, [s["vel"][1] for s in samples], label="actual ω", ls="--")
    ax.set_ylabel("angular [rad/s]")
    ax = axes[4]
    for name in (s.name for s in COURSE.sensors):
        values = [(s["prox"] or {}).get(name) for s in samples]
        ax.plot(t, [math.nan if v is None else v for v in values], label=name, lw=1)
    ax.set_ylabel("range [m]")
    ax.set_ylim(0, COURSE.range_max * 1.05)
    ax.set_xlabel("simulated time [s]")
    for a in axes:
        a.grid(True, lw=0.3, alpha=0.5)
    for a in axes[1:]:
        a.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    fig.suptitle(f"{recording.mission}: signals, and the behaviours running (top)", y=0.995)
    fig.align_ylabels(axes)
    fig.tight_layout()
    return _save(fig, plt, path)
