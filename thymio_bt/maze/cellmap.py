"""A map of the walls of a maze of square cells, learnt as the robot goes, and flood fill on it.

Cell (i, j) spans [i·c, (i+1)·c] × [j·c, (j+1)·c] (the micromouse coordinates: origin at the
bottom-left post). Each side of a cell is unknown, open or a wall; the outline is a wall. The flood
fill is a breadth-first distance map from target cells over the sides not known to be walls
(optimistic exploration), or over the sides known to be open (``known_only``: a path sure to exist).

Where the robot is on that grid is a :class:`GridFrame`: odometry drifts, so the map keeps the
rigid transform from the odometry frame to the maze's, and corrects it whenever a wall is seen
square ahead (the heading from two sensors' hits, the distance along it from the front sensor).

Example::

    >>> cells = CellMap(16, 16)
    >>> cells.mark((0, 0), "E", True)
    >>> distance = cells.distances(centre_cells(16, 16))
    >>> distance[(0, 0)]  # steps to the centre, walls not yet seen assumed open
    14
    >>> cells.next_side((0, 0), "E", distance)  # the wall east: north, as short
    'N'
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from dataclasses import dataclass, field
from typing import Any

Cell = tuple[int, int]
#: side -> (di, dj), in the order a tie is broken after "straight on"
STEPS = {"N": (0, 1), "E": (1, 0), "S": (0, -1), "W": (-1, 0)}
OPPOSITE = {"N": "S", "E": "W", "S": "N", "W": "E"}


@dataclass
class GridFrame:
    """The maze frame as seen from odometry: ``maze = R(yaw)·odometry + (x, y)``, a rigid transform."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def to_maze(self, x: float, y: float, yaw: float) -> tuple[float, float, float]:
        """An odometry (x, y, yaw) in maze coordinates."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return c * x - s * y + self.x, s * x + c * y + self.y, yaw + self.yaw

    def correct(self, odometry: tuple[float, float, float], maze: tuple[float, float, float]) -> None:
        """Change the transform so that ``odometry`` maps to ``maze`` (its position and heading)."""
        ox, oy, oyaw = odometry
        mx, my, myaw = maze
        self.yaw = myaw - oyaw
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        self.x, self.y = mx - (c * ox - s * oy), my - (s * ox + c * oy)


@dataclass
class RunningMedian:
    """The median of the latest ``window`` values (a few wild ones do not move it), and how many came."""

    window: int = 31
    values: deque[float] = field(default_factory=deque)
    count: int = 0

    def add(self, value: float) -> None:
        """Take in ``value`` (the oldest goes once the window is full)."""
        self.count += 1
        self.values.append(value)
        if len(self.values) > self.window:
            self.values.popleft()

    @property
    def median(self) -> float:
        """The median of the window (0 before any value)."""
        return statistics.median(self.values) if self.values else 0.0


@dataclass
class CellMap:
    """What is known of a ``cols`` × ``rows`` maze's walls, and which cells were visited."""

    cols: int
    rows: int
    #: (i, j, side) -> True for a wall, False for an opening; absent: unknown
    sides: dict[tuple[int, int, str], bool] = field(default_factory=dict)
    visited: set[Cell] = field(default_factory=set)
    #: odometry to maze coordinates (corrected at walls)
    frame: GridFrame = field(default_factory=GridFrame)
    #: the cell the map was started in
    start: Cell | None = None
    #: how much longer than the geometry the side sensors read a side wall (learnt in corridors)
    side_bias: RunningMedian = field(default_factory=RunningMedian)
    #: how far the map's pose may have drifted along x and along y since a wall ahead last fixed
    #: that coordinate (grows with the distance driven: a turn's heading error turns into drift)
    drift: dict[str, float] = field(default_factory=lambda: {"x": 0.0, "y": 0.0})
    #: the cells a plan last went for as "the goal" (the maze's goal region or the centre block)
    goal: set[Cell] = field(default_factory=set)
    #: the grid's pitch and its origin in the world (the bottom-left post's centre), for drawing
    cell: float = 0.18
    origin: tuple[float, float] = (0.0, 0.0)

    def inside(self, cell: Cell) -> bool:
        """Whether ``cell`` is in the maze."""
        return 0 <= cell[0] < self.cols and 0 <= cell[1] < self.rows

    def mark(self, cell: Cell, side: str, wall: bool) -> None:
        """Record the side of ``cell`` (and the same edge seen from the neighbour)."""
        di, dj = STEPS[side]
        self.sides[(cell[0], cell[1], side)] = wall
        self.sides[(cell[0] + di, cell[1] + dj, OPPOSITE[side])] = wall

    def wall(self, cell: Cell, side: str) -> bool | None:
        """True, False, or None when unknown; the outline is always a wall."""
        di, dj = STEPS[side]
        if not self.inside((cell[0] + di, cell[1] + dj)):
            return True
        return self.sides.get((cell[0], cell[1], side))

    def passable(self, cell: Cell, side: str, known_only: bool = False) -> bool:
        """Whether the way out of ``cell`` through ``side`` may be taken: not a known wall, or (with
        ``known_only``) a known opening."""
        known = self.wall(cell, side)
        return known is False if known_only else known is not True

    def distances(self, targets: set[Cell], known_only: bool = False) -> dict[Cell, int]:
        """Steps from each reachable cell to the nearest target cell."""
        out = {t: 0 for t in targets if self.inside(t)}
        todo = deque(out)
        sides, cols, rows, steps = self.sides, self.cols, self.rows, tuple(STEPS.items())
        while todo:  # passable() inlined: this runs at every cell of every plan
            cell = todo.popleft()
            i, j = cell
            for side, (di, dj) in steps:
                nxt = (i + di, j + dj)
                if nxt in out or not (0 <= nxt[0] < cols and 0 <= nxt[1] < rows):
                    continue
                known = sides.get((i, j, side))
                if known is False or (known is None and not known_only):
                    out[nxt] = out[cell] + 1
                    todo.append(nxt)
        return out

    def summary(self) -> dict[str, Any]:
        """The map as JSON for a run report and its pictures: the known walls as world segments
        ``[x0, y0, x1, y1]``, the cells visited, how many inner sides (edges) are known open, and,
        once a goal was planned for, the flood-fill ``distances`` (``[i, j, steps]``) to it over
        known openings and the shortest known ``path`` (cells) from the start."""
        ox, oy = self.origin
        out: dict[str, Any] = {
            "cols": self.cols,
            "rows": self.rows,
            "cell": self.cell,
            "origin": [round(ox, 6), round(oy, 6)],
            "walls": [list(w) for w in sorted(self.wall_segments())],
            "visited": sorted([list(v) for v in self.visited]),
            "open_sides": len(
                {_edge(i, j, side) for (i, j, side), wall in self.sides.items() if not wall and self.inside((i, j))}
            ),
        }
        if self.goal:
            distance = self.distances(self.goal, known_only=True)
            out["goal"] = sorted([list(g) for g in self.goal])
            out["distances"] = sorted([i, j, d] for (i, j), d in distance.items())
            out["path"] = [list(p) for p in self.path(self.start, distance)] if self.start in distance else []
        return out

    def wall_segments(self) -> set[tuple[float, ...]]:
        """The known walls as world segments (x0, y0, x1, y1), each once."""
        c, (ox, oy) = self.cell, self.origin
        walls = set()
        for (i, j, side), wall in self.sides.items():
            if wall and self.inside((i, j)):
                x0, y0 = ox + i * c, oy + j * c
                end = {
                    "N": (x0, y0 + c, x0 + c, y0 + c),
                    "S": (x0, y0, x0 + c, y0),
                    "E": (x0 + c, y0, x0 + c, y0 + c),
                    "W": (x0, y0, x0, y0 + c),
                }[side]
                walls.add(tuple(round(v, 6) for v in end))
        return walls

    def path(self, start: Cell | None, distance: dict[Cell, int]) -> list[Cell]:
        """The cells from ``start`` down ``distance`` (known openings) to its zero."""
        if start is None:
            return []
        cells, here = [start], start
        while distance.get(here, 0) > 0:
            here = _next(here, self.next_side(here, "N", distance, known_only=True))
            cells.append(here)
        return cells

    def next_side(self, cell: Cell, facing: str, distance: dict[Cell, int], known_only: bool = False) -> str:
        """The side of ``cell`` to leave by, downhill on ``distance``: straight on when that is as good."""
        order = [facing, *(s for s in STEPS if s != facing)]
        options = [s for s in order if self.passable(cell, s, known_only) and _next(cell, s) in distance]
        return min(options, key=lambda s: distance[_next(cell, s)])

    def straight_run(self, cell: Cell, side: str, distance: dict[Cell, int]) -> int:
        """How many cells the way down ``distance`` goes straight on through ``side`` (at least 1)."""
        run, here = 1, _next(cell, side)
        while distance.get(here, 0) > 0 and self.passable(here, side, True):
            nxt = _next(here, side)
            if distance.get(nxt) != distance[here] - 1:
                break
            run, here = run + 1, nxt
        return run


def _edge(i: int, j: int, side: str) -> tuple[int, int, str]:
    """One name for an edge seen from either cell: its N or E side."""
    if side in ("N", "E"):
        return i, j, side
    di, dj = STEPS[side]
    return i + di, j + dj, OPPOSITE[side]


def _next(cell: Cell, side: str) -> Cell:
    """The neighbour of ``cell`` through ``side``."""
    di, dj = STEPS[side]
    return cell[0] + di, cell[1] + dj


def centre_cells(cols: int, rows: int) -> set[Cell]:
    """The contest's goal: the 2 × 2 block at the centre (or the middle cells of an odd size)."""
    xs = {cols // 2} if cols % 2 else {cols // 2 - 1, cols // 2}
    ys = {rows // 2} if rows % 2 else {rows // 2 - 1, rows // 2}
    return {(i, j) for i in xs for j in ys}
