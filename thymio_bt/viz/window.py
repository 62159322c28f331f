"""A live pygame window of a run (``thymio-bt run --view``) or of a log (``thymio-bt replay --view``):
the maze, the robot, its seven rays, the trajectory so far and the running node, paced at a chosen
speed-up of simulated time, with pause and single-step keys.

pygame is imported only when a window is opened (it is in the optional ``viz`` extra). The window
only reads the simulation, so a run with a window ends exactly as one without. With
``SDL_VIDEODRIVER=dummy`` it draws offscreen, which is how the tests run it.

Keys: SPACE pause/resume, N or RIGHT one tick (and pause), + / - double/halve the speed-up,
Q or ESC close. Closing the window of a live run raises :class:`ViewerClosed`, a
:class:`thymio_bt.errors.StopRun`: the run ends there as a FAILURE with code STOPPED, and its
report, log and pictures are written as for any other ending.

Example (offscreen; ``replay(read_log("run.jsonl"), speedup=10)`` shows a log the same way):

>>> import os
>>> from thymio_bt.mission import load_mission
>>> _ = os.environ.setdefault("SDL_VIDEODRIVER", "dummy")  # no window opens
>>> run = Run(load_mission("square"))
>>> view = live_hook(run, speedup=1000, hold=False)
>>> result = run.run(on_tick=view)  # result.code is FailureCode.STOPPED if the window was closed
>>> view.finish(result)
>>> result.status, view.viewer.shown, view.viewer.outcome
(<RunStatus.SUCCESS: 'SUCCESS'>, 228, <RunStatus.SUCCESS: 'SUCCESS'>)
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from thymio_bt.behaviours.base import node_path
from thymio_bt.errors import StopRun, UserError
from thymio_bt.logs.entries import number
from thymio_bt.logs.recording import Recording
from thymio_bt.maze import Maze
from thymio_bt.maze.cellmap import CellMap
from thymio_bt.robot.model import COURSE
from thymio_bt.run.result import RunResult, learnt_map
from thymio_bt.run.runner import Run
from thymio_bt.viz.display import INSTALL_HINT
from thymio_bt.viz.plots import outline, rays

#: matplotlib's tab10 colours that plots.py draws with ("tab:blue", "tab:red", "tab:green"), as RGB,
#: so that pictures and window agree.
TAB_BLUE, TAB_RED, TAB_GREEN = (31, 119, 180), (214, 39, 40), (44, 160, 44)
#: Colours (RGB) of the window: tab10's where plots.py uses it for the same thing.
BACKGROUND = (250, 250, 250)
WALL = (64, 64, 64)
OBSTACLE = TAB_BLUE
TRAIL = TAB_BLUE
ROBOT_FILL = (174, 199, 232)
ROBOT_EDGE = (0, 0, 0)
RAY_HIT = TAB_RED
RAY_FREE = (180, 180, 180)
BAR = (40, 40, 40)
BAR_TEXT = (235, 235, 235)
PAUSED_TEXT = (255, 190, 60)
MAP_VISITED = TAB_GREEN
MAP_WALL = TAB_RED

#: Height of the status bar (pixels), margin around the world (metres), and the largest jump of
#: the base_link between ticks still drawn as one line (a larger one is a respawn, as in plots.py).
BAR_HEIGHT = 26
WORLD_MARGIN = 0.06
TRAIL_JUMP = 0.05
#: While waiting (paced or paused), look at the keyboard at least this often (milliseconds).
IDLE_MS = 20
KEYS_HELP = "SPACE pause   N step   + / - speed   Q quit"


class ViewerClosed(StopRun):
    """The user closed the window (Q, ESC or the window's close button): end the run there."""

    def __init__(self) -> None:
        super().__init__("the viewer window was closed")


@dataclass(frozen=True)
class Frame:
    """What one frame shows: simulated time, base_link pose (None while the robot is deleted),
    proximity readings by sensor (None: nothing in range) and the running node's text."""

    t: float
    pose: dict[str, float] | None
    prox: dict[str, float | None]
    node: str = ""
    #: the mapping behaviours' map (:class:`~thymio_bt.maze.cellmap.CellMap`), if the run has one
    cells: CellMap | None = None


def _pygame() -> Any:
    """pygame, imported on first use, or a :class:`UserError` telling how to install it."""
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # no banner on stdout
    try:
        import pygame
    except ImportError:
        raise UserError(f"pygame is not installed (hint: {INSTALL_HINT})") from None
    return pygame


class Viewer:
    """A pygame window drawing :class:`Frame` s of one run at ``speedup`` times real time.

    :meth:`show` paces: the frame for simulated time ``t`` is shown no earlier than ``t / speedup``
    seconds of wall time after the first frame (pauses and speed changes move that origin). Frames
    that come faster than ``max_fps`` are added to the trail but not drawn (``None``: draw all).
    ``hold`` keeps the window open after :meth:`finish` until it is closed; by default it does
    unless the video driver is ``dummy`` or ``offscreen`` (nobody could close it).
    """

    def __init__(
        self,
        maze: Maze,
        speedup: float = 1.0,
        title: str = "thymio-bt",
        size: tuple[int, int] = (1000, 640),
        include: Iterable[tuple[float, float]] = (),
        max_fps: float | None = 60.0,
        hold: bool | None = None,
    ) -> None:
        if not speedup > 0:
            raise UserError(f"the speed-up must be > 0, got {speedup:g} (hint: --speedup 4)")
        self.pg = pg = _pygame()
        try:
            pg.display.init()
            self.screen = pg.display.set_mode(size, pg.RESIZABLE)
        except pg.error as exc:
            raise UserError(
                f"cannot open a window: {exc} (hint: run where there is a display, "
                "or set SDL_VIDEODRIVER=dummy to draw offscreen)"
            ) from None
        pg.font.init()
        pg.display.set_caption(title)
        self.font = pg.font.Font(None, 22)
        self.small = pg.font.Font(None, 18)
        self.maze = maze
        self.speedup = float(speedup)
        self.paused = False
        self.frames = 0  # frames drawn
        self.shown = 0  # frames given to show()
        self.outcome = ""
        self.hold = pg.display.get_driver() not in ("dummy", "offscreen") if hold is None else hold
        self._min_interval = 1.0 / max_fps if max_fps else 0.0
        self._last_draw = -math.inf
        self._anchor: tuple[float, float] | None = None  # (simulated t, wall time) of the pacing origin
        self._frame: Frame | None = None
        self._trail: list[list[tuple[float, float]]] = []
        self._open = True
        empty = (math.inf, math.inf, -math.inf, -math.inf)
        xmin, ymin, xmax, ymax = maze.bounds() if maze.walls or maze.obstacles else empty
        for x, y in include:
            xmin, ymin, xmax, ymax = min(xmin, x), min(ymin, y), max(xmax, x), max(ymax, y)
        if not math.isfinite(xmin):
            xmin = ymin = xmax = ymax = 0.0
        self._box = (xmin - WORLD_MARGIN, ymin - WORLD_MARGIN, xmax + WORLD_MARGIN, ymax + WORLD_MARGIN)
        self._fit()

    # ------------------------------------------------------------------ geometry
    def _fit(self) -> None:
        """The world→screen transform fitting the world box under the status bar, y up."""
        width, height = self.screen.get_size()
        x0, y0, x1, y1 = self._box
        span_x, span_y = max(x1 - x0, 0.3), max(y1 - y0, 0.3)
        self.scale = max(min(width / span_x, (height - BAR_HEIGHT) / span_y), 1e-6)
        self._origin = (
            width / 2 - (x0 + x1) / 2 * self.scale,
            BAR_HEIGHT + (height - BAR_HEIGHT) / 2 + (y0 + y1) / 2 * self.scale,
        )
        self._background = self._draw_background()

    def to_screen(self, x: float, y: float) -> tuple[float, float]:
        """Pixel coordinates of the world point (x, y) (metres, y up)."""
        return self._origin[0] + x * self.scale, self._origin[1] - y * self.scale

    def _grow(self, pose: dict[str, float]) -> None:
        """Widen the world box when the robot or its rays leave it (e.g. out of a maze's exit)."""
        reach = COURSE.range_max + 0.06
        x0, y0, x1, y1 = self._box
        if x0 <= pose["x"] - reach and pose["x"] + reach <= x1 and y0 <= pose["y"] - reach and pose["y"] + reach <= y1:
            return
        self._box = (
            min(x0, pose["x"] - reach),
            min(y0, pose["y"] - reach),
            max(x1, pose["x"] + reach),
            max(y1, pose["y"] + reach),
        )
        self._fit()

    # ------------------------------------------------------------------ drawing
    def _draw_background(self) -> Any:
        """The maze and the trail so far on a surface of the window's size; new trail is added to it."""
        pg = self.pg
        surface = pg.Surface(self.screen.get_size())
        surface.fill(BACKGROUND)
        for wall in self.maze.walls:
            pg.draw.polygon(surface, WALL, [self.to_screen(*c) for c in wall.corners()])
        for obstacle in self.maze.obstacles:
            pg.draw.polygon(surface, OBSTACLE, [self.to_screen(*c) for c in obstacle.corners()])
        for part in self._trail:
            if len(part) > 1:
                pg.draw.lines(surface, TRAIL, False, [self.to_screen(*p) for p in part], 2)
        return surface

    def _extend_trail(self, pose: dict[str, float] | None) -> None:
        """Add the pose to the trail; a deletion or a jump (respawn) starts a new part."""
        if pose is None:
            if self._trail and self._trail[-1]:
                self._trail.append([])
            return
        point = (pose["x"], pose["y"])
        if not self._trail or (self._trail[-1] and math.dist(self._trail[-1][-1], point) > TRAIL_JUMP):
            self._trail.append([])
        part = self._trail[-1]
        if part:
            self.pg.draw.line(self._background, TRAIL, self.to_screen(*part[-1]), self.to_screen(*point), 2)
        part.append(point)

    def draw(self) -> None:
        """Draw the current frame: maze and trail, rays, robot, status bar; flip the display."""
        pg, screen, frame = self.pg, self.screen, self._frame
        screen.blit(self._background, (0, 0))
        if frame is not None and frame.cells is not None:
            self._draw_cell_map(frame.cells)
        if frame is not None and frame.pose is not None:
            for start, end, hit in rays(frame.pose, frame.prox):
                pg.draw.line(screen, RAY_HIT if hit else RAY_FREE, self.to_screen(*start), self.to_screen(*end), 1)
                if hit:
                    pg.draw.circle(screen, RAY_HIT, self.to_screen(*end), 3)
            body = [self.to_screen(*p) for p in outline(frame.pose)]
            pg.draw.polygon(screen, ROBOT_FILL, body)
            pg.draw.polygon(screen, ROBOT_EDGE, body, 2)
        self._draw_status(frame)
        pg.display.flip()
        self.frames += 1
        self._last_draw = time.perf_counter()

    def _draw_cell_map(self, cells: CellMap) -> None:
        """What the map knows so far: a dot in each visited cell, the walls found drawn over the maze's."""
        c, (ox, oy) = cells.cell, cells.origin
        for i, j in cells.visited:
            self.pg.draw.circle(self.screen, MAP_VISITED, self.to_screen(ox + (i + 0.5) * c, oy + (j + 0.5) * c), 4)
        for x0, y0, x1, y1 in cells.wall_segments():
            self.pg.draw.line(self.screen, MAP_WALL, self.to_screen(x0, y0), self.to_screen(x1, y1), 3)

    def _draw_status(self, frame: Frame | None) -> None:
        width, height = self.screen.get_size()
        self.pg.draw.rect(self.screen, BAR, (0, 0, width, BAR_HEIGHT))
        if frame is not None:
            robot = "" if frame.pose is not None else "   (no robot)"
            text = f"t = {frame.t:6.1f} s   x{self.speedup:g}   {frame.node}{robot}"
            self.screen.blit(self.font.render(text, True, BAR_TEXT), (8, 5))
        right = "PAUSED" if self.paused else self.outcome
        if right:  # over the end of a long node path
            label = self.font.render(right, True, PAUSED_TEXT, BAR)
            self.screen.blit(label, (width - label.get_width() - 8, 5))
        help_ = self.small.render(KEYS_HELP, True, WALL)
        self.screen.blit(help_, (width - help_.get_width() - 6, height - help_.get_height() - 4))

    def save(self, path: str | Path) -> Path:
        """Write what the window shows as an image (PNG by the suffix)."""
        path = Path(path)
        try:
            self.pg.image.save(self.screen, str(path))
        except (OSError, self.pg.error) as exc:
            raise UserError(f"cannot write {path}: {exc}") from None
        return path

    # ------------------------------------------------------------------ pacing and keys
    def show(self, frame: Frame) -> None:
        """Add ``frame`` to the trail and show it once its wall time has come, handling keys while
        waiting; returns after it, or after a single step while paused. Raises :class:`ViewerClosed`."""
        if not self._open:
            raise ViewerClosed()
        self.shown += 1
        self._frame = frame
        if frame.pose is not None:
            self._grow(frame.pose)
        self._extend_trail(frame.pose)
        if self._anchor is None:
            self._anchor = (frame.t, time.perf_counter())
        stale = True
        while True:
            event = self.pg.event.poll()
            if event.type == self.pg.NOEVENT:
                if self.paused:
                    if stale:
                        self.draw()
                        stale = False
                    event = self.pg.event.wait(IDLE_MS)
                    if event.type == self.pg.NOEVENT:
                        continue
                else:
                    lag = self._due(frame.t) - time.perf_counter()
                    if lag <= 0:
                        break
                    time.sleep(min(lag, IDLE_MS / 1000))  # realtime: the viewer paces frames, never the simulation
                    continue
            if event.type in (self.pg.KEYDOWN, self.pg.QUIT, self.pg.VIDEORESIZE, self.pg.WINDOWSIZECHANGED):
                stale = True
                if self._handle(event, frame.t):
                    break
        if stale and (self.paused or time.perf_counter() - self._last_draw >= self._min_interval):
            self.draw()

    def _due(self, t: float) -> float:
        """Wall time (perf_counter) at which the frame of simulated time ``t`` may be shown."""
        assert self._anchor is not None
        t0, wall0 = self._anchor
        return wall0 + (t - t0) / self.speedup

    def _handle(self, event: Any, t: float) -> bool:
        """React to one event; True when it asks for a single step (the frame at ``t`` is shown)."""
        pg = self.pg
        if event.type == pg.QUIT or (event.type == pg.KEYDOWN and event.key in (pg.K_q, pg.K_ESCAPE)):
            self.close()
            raise ViewerClosed()
        if event.type in (pg.VIDEORESIZE, pg.WINDOWSIZECHANGED):
            self._fit()
        elif event.type == pg.KEYDOWN:
            if event.key in (pg.K_n, pg.K_RIGHT):
                self.paused = True
                return True
            if event.key == pg.K_SPACE:
                self.paused = not self.paused
            elif event.key in (pg.K_PLUS, pg.K_EQUALS, pg.K_KP_PLUS):
                self.speedup *= 2
            elif event.key in (pg.K_MINUS, pg.K_KP_MINUS):
                self.speedup /= 2
            else:
                return False
            self._anchor = (t, time.perf_counter())  # resumed or new speed: pace from here
        return False

    def finish(self, outcome: str = "") -> None:
        """Draw the last frame with the outcome; with ``hold``, wait until the window is closed."""
        if not self._open:
            return
        self.outcome = f"{outcome}   (Q closes)" if self.hold else outcome
        self.paused = False
        self.draw()
        while self.hold:
            event = self.pg.event.wait()
            if event.type == self.pg.QUIT or (
                event.type == self.pg.KEYDOWN and event.key in (self.pg.K_q, self.pg.K_ESCAPE)
            ):
                break
            if event.type in (self.pg.VIDEORESIZE, self.pg.WINDOWSIZECHANGED):
                self._fit()
                self.draw()
        self.close()

    def close(self) -> None:
        """Close the window (idempotent)."""
        if self._open:
            self._open = False
            self.pg.display.quit()


def _node_text(run: Run) -> str:
    """The path of the deepest running node and its feedback message."""
    tip = run.root.tip()
    if tip is None:
        return ""
    feedback = tip.feedback_message
    return node_path(tip) + (f" — {feedback}" if feedback else "")


class LiveView:
    """The ``on_tick`` hook of ``run --view``: shows the simulation after every tree tick."""

    def __init__(self, run: Run, speedup: float, **options: Any) -> None:
        start = run.mission.start
        self.viewer = Viewer(
            run.mission.maze, speedup, title=f"thymio-bt: {run.mission.name}", include=[(start.x, start.y)], **options
        )
        self.cells: CellMap | None = None

    def __call__(self, run: Run) -> None:
        """Show the simulation as this tick left it (paced; keys handled); :class:`ViewerClosed` ends the run."""
        sim = run.backend
        pose = sim.true_pose()
        scan = sim.proximity() or {}
        if self.cells is None:  # a mapping mission's map, once one of its behaviours made it
            self.cells = learnt_map(run.root)
        self.viewer.show(
            Frame(
                sim.time(),
                None if pose is None else pose.as_dict(),
                {name: number(value) for name, value in scan.items()},
                _node_text(run),
                self.cells,
            )
        )

    def finish(self, result: RunResult) -> None:
        """Show the run's outcome; with ``hold``, wait until the window is closed."""
        self.viewer.finish(result.status if result.code is None else f"{result.status} [{result.code}]")


def live_hook(run: Run, speedup: float, **options: Any) -> LiveView:
    """A tick hook showing ``run`` live at ``speedup`` times real time (options: see :class:`Viewer`)."""
    return LiveView(run, speedup, **options)


def replay(recording: Recording, speedup: float, **options: Any) -> Viewer:
    """Show a recorded run (e.g. from :func:`~thymio_bt.logs.read_log`) at ``speedup`` times
    real time; closing the window just ends the replay. Returns the (closed) viewer."""
    points = [(s["pose"]["x"], s["pose"]["y"]) for s in recording.samples if s["pose"]]
    viewer = Viewer(recording.maze, speedup, title=f"thymio-bt replay: {recording.mission}", include=points, **options)
    try:
        for sample in recording.samples:
            viewer.show(Frame(sample["t"], sample["pose"], sample["prox"] or {}, ", ".join(sample.get("running", []))))
        viewer.finish(recording.end.get("status", ""))
    except ViewerClosed:
        pass
    return viewer
