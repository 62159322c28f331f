"""The smallest gap between the robot's hull and any wall over a run, exact, at every sensor refresh.

Reports carry it as ``min_clearance``: how close the robot came to touching. It must be the true
smallest gap, and it is asked for ten times a simulated second, so :class:`ClearanceTracker` keeps
the common case cheap:

1. one C shape query (:class:`~thymio_bt.backends.sim.fastpath.NearShapes`) asks whether anything is closer
   to the hull than the record, by more than :data:`RESOLUTION` (1 pm): mostly not, and then
   nothing is computed;
2. otherwise each wall box near the axle (:mod:`.walls`) is measured in its own frame: when the
   axle lies beside a long face, the face's line is at distance d from the axle and the hull's
   support point towards it is the nearest hull point; if that point projects onto the face, the
   gap is exactly d - extent (a robot in a corridor, nearly always);
3. otherwise (wall ends, corners, obstacles) d - extent is a lower bound, and the polygon distance
   is computed only for walls whose bound could beat both the record and the gaps of step 2.

The simulation keeps one tracker and asks ``tracker.below(record, near, hull_shape, bx, by, cos,
sin)`` at every sensor refresh: a gap below ``record`` only when one beats it. Its record is the
exact gap plain geometry gives (:func:`~thymio_bt.robot.placement.clearance`), to the last bits:

Example::

    >>> from thymio_bt.backends.sim.world import Simulation
    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> from thymio_bt.robot.interface import Pose
    >>> from thymio_bt.robot.model import COURSE
    >>> from thymio_bt.robot.placement import clearance
    >>> maze, start = load_maze(resolve_maze("two_parts_maze")), Pose(0.1, 0.1, 0.0)
    >>> Simulation(maze, spawn=start).min_clearance, clearance(maze, COURSE, start)
    (0.0391, 0.039099999999999996)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import pymunk

from thymio_bt.backends.sim.fastpath import NearShapes, PointDistance
from thymio_bt.backends.sim.walls import Box, wall_grid
from thymio_bt.maze import Wall
from thymio_bt.robot.model import RobotModel

#: The hull's extent tables are made in 1 degree steps.
EXTENT_STEP = math.radians(1.0)
EXTENT_STEPS = 360
#: A new record must beat the last by more than this (m): the gap is exact to it.
RESOLUTION = 1e-12
#: The wall grid: cell size, and the smallest gap record it serves (m); above it (a run's first
#: ticks) every wall is a candidate.
GRID_CELL = 0.05
GRID_RECORD = 0.05

#: A wall as the tracker sees it: its shape in the space, its box frame (centre x, y, unit direction
#: x, y, half length, half thickness; None for an obstacle polygon) and its corners.
WallFrame = tuple[float, float, float, float, float, float]
TrackedWall = tuple[pymunk.Shape, "WallFrame | None", tuple[tuple[float, float], ...]]


def wall_frame(wall: Wall) -> WallFrame:
    """A wall box's frame: centre, unit direction, half length and half thickness."""
    (x0, y0), (x1, y1) = wall.start, wall.end
    length = wall.length  # a property that measures the segment: once, not three times
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    return (x0 + x1) / 2, (y0 + y1) / 2, ux, uy, (length + wall.thickness) / 2, wall.thickness / 2


@dataclass(frozen=True, slots=True)
class HullTables:
    """A hull seen from its axle: ``reach`` is the farthest hull point from the axle; ``extent`` the
    hull's extent in each direction (1 degree steps), padded by the most it can grow within half a
    step so it never underestimates (a cheap, safe support function); ``support`` the hull vertices
    that can be the support point in each direction."""

    reach: float
    extent: tuple[float, ...]
    support: tuple[tuple[tuple[float, float], ...], ...]


def _farthest_vertex(polygon: tuple[tuple[float, float], ...], step: int) -> int:
    """The index of ``polygon``'s first vertex farthest along the direction ``step`` (in
    :data:`EXTENT_STEP` units)."""
    cos, sin = math.cos(step * EXTENT_STEP), math.sin(step * EXTENT_STEP)
    along = [x * cos + y * sin for x, y in polygon]
    return along.index(max(along))


@lru_cache(maxsize=8)
def hull_tables(hull: tuple[tuple[float, float], ...], axle_x: float) -> HullTables:
    """The :class:`HullTables` of a hull (base_link corners) about its axle at ``axle_x``: computed
    once per robot model.

    >>> from thymio_bt.robot.model import COURSE
    >>> tables = hull_tables(COURSE.hull, COURSE.axle_x)
    >>> round(tables.reach, 4), len(tables.extent), len(tables.support[0])
    (0.08, 360, 3)
    """
    from_axle = tuple((x - axle_x, y) for x, y in hull)
    reach = max(math.hypot(x, y) for x, y in from_axle)
    extent = tuple(
        max(x * math.cos(i * EXTENT_STEP) + y * math.sin(i * EXTENT_STEP) for x, y in from_axle)
        + reach * EXTENT_STEP / 2
        for i in range(EXTENT_STEPS)
    )
    support = tuple(
        tuple(from_axle[(k + j) % len(from_axle)] for j in (-1, 0, 1))
        for k in (_farthest_vertex(from_axle, i) for i in range(EXTENT_STEPS))
    )
    return HullTables(reach, extent, support)


class ClearanceTracker:
    """Measures one robot model's hull against the walls of one space (see the module's steps)."""

    def __init__(
        self,
        model: RobotModel,
        walls: Sequence[tuple[pymunk.Shape, Wall | None, tuple[tuple[float, float], ...], Box]],
        bounds: Box,
    ) -> None:
        """``walls``: each static shape with its maze wall (None for an obstacle polygon), its
        corners and its bounding box."""
        self.hull, self.axle_x = model.hull, model.axle_x
        self.tables = hull_tables(model.hull, model.axle_x)
        self.walls: tuple[TrackedWall, ...] = tuple(
            (shape, None if wall is None else wall_frame(wall), corners) for shape, wall, corners, _ in walls
        )
        self.grid = wall_grid(tuple(box for *_, box in walls), GRID_CELL, self.tables.reach + GRID_RECORD)
        xmin, ymin, xmax, ymax = bounds
        #: no gap inside the maze exceeds it: the record before the first measurement
        self.farthest = math.hypot(xmax - xmin, ymax - ymin)
        self._distance = PointDistance()

    def below(
        self, record: float, near: NearShapes, robot: pymunk.Shape, bx: float, by: float, cos: float, sin: float
    ) -> float:
        """The exact gap between the hull (its body at (bx, by), heading of this cosine and sine) and
        the nearest wall when that is below ``record``; otherwise something not below it."""
        record = self.farthest if self.farthest < record else record
        # nothing can beat the record: one C query. It asks for 1 pm less than the record, still
        # 1e5 times Chipmunk's rounding at these sizes (1e-17 m) and a millionth of the report's
        # (1 µm): a robot cruising beside a wall at exactly its record gap (a corridor's side wall),
        # or a hair above it, would otherwise take the exact path at every refresh
        if record <= RESOLUTION or not near.within(record - RESOLUTION):  # (a touch is the last record)
            return record
        best, candidates = self._measure_near(record, bx + self.axle_x * cos, by + self.axle_x * sin, cos, sin)
        exact = [wall for bound, wall in candidates if bound < best]  # others cannot beat the faces
        if exact:
            gap = self.exact(exact, robot, bx, by, cos, sin)
            best = gap if gap < best else best
        return best

    def _measure_near(
        self, record: float, ax: float, ay: float, cos: float, sin: float
    ) -> tuple[float, list[tuple[float, TrackedWall]]]:
        """Steps 2 and 3 for the walls near the axle at (ax, ay): the smallest exact gap to a long
        face, and the walls whose lower bound could still beat ``record``, with that bound."""
        best = math.inf
        candidates: list[tuple[float, TrackedWall]] = []  # (a lower bound of its gap, wall)
        reach = self.tables.reach
        radius = reach + record
        walls, distance = self.walls, self._distance
        for index in self.grid.near(ax, ay, radius):
            wall = walls[index]
            frame = wall[1]
            if frame is None:  # an obstacle polygon: Chipmunk's distance, then exact
                bound = distance(wall[0], (ax, ay))[0] - reach
            else:
                cx, cy, ux, uy, hl, ht = frame
                dx, dy = ax - cx, ay - cy
                along, across = dx * ux + dy * uy, dy * ux - dx * uy
                out_along = (along if along >= 0.0 else -along) - hl  # beyond an end (> 0)
                out_across = (across if across >= 0.0 else -across) - ht  # beyond a long face (> 0)
                if out_along >= radius or out_across >= radius:
                    continue  # the box is farther than the hull reaches
                if out_across > 0.0 and out_along < 0.0:  # beside a long face, which is out_across away
                    gap, bound = self._face(frame, across, out_across, ax, ay, cos, sin)
                    best = gap if gap < best else best
                elif out_along > 0.0 or out_across > 0.0:  # nearest the box's end or a corner
                    bound = self._corner(frame, along, across, out_along, out_across, cos, sin)
                else:
                    bound = -math.inf  # the axle inside the box
            if bound < record - 1e-6:
                candidates.append((bound, wall))
        return best, candidates

    def _face(
        self, frame: WallFrame, across: float, out_across: float, ax: float, ay: float, cos: float, sin: float
    ) -> tuple[float, float]:
        """The gap to a long face beside the axle, ``out_across`` away: (the exact gap, infinity)
        when the hull's support point towards it lies on the face, else (infinity, a lower bound)."""
        cx, cy, ux, uy, hl, _ = frame
        wx, wy = (uy, -ux) if across > 0.0 else (-uy, ux)  # towards the face
        lx, ly = wx * cos + wy * sin, wy * cos - wx * sin  # the same in the body frame
        step = round(math.atan2(ly, lx) / EXTENT_STEP) % EXTENT_STEPS
        extent = -math.inf
        for sx, sy in self.tables.support[step]:  # the first farthest along it
            toward = sx * lx + sy * ly
            if toward > extent:
                extent, vx, vy = toward, sx, sy
        # the support point, along the wall from its centre: on the face, the gap is exact
        px, py = ax + vx * cos - vy * sin - cx, ay + vx * sin + vy * cos - cy
        if -hl <= px * ux + py * uy <= hl:
            return out_across - extent, math.inf
        return math.inf, out_across - self.tables.extent[step]

    def _corner(
        self, frame: WallFrame, along: float, across: float, out_along: float, out_across: float, cos: float, sin: float
    ) -> float:
        """A lower bound of the gap to a box whose nearest point to the axle is an end or a corner,
        ``out_along`` beyond its end and ``out_across`` beyond its face (the larger one > 0)."""
        _, _, ux, uy, _, _ = frame
        qx = out_along if out_along > 0.0 else 0.0
        qy = out_across if out_across > 0.0 else 0.0
        d = math.hypot(qx, qy)
        # the direction from the axle to the box's nearest point, in the body frame
        nx = -(ux * (qx if along >= 0.0 else -qx) - uy * (qy if across >= 0.0 else -qy)) / d
        ny = -(uy * (qx if along >= 0.0 else -qx) + ux * (qy if across >= 0.0 else -qy)) / d
        step = round(math.atan2(nx * -sin + ny * cos, nx * cos + ny * sin) / EXTENT_STEP) % EXTENT_STEPS
        return d - self.tables.extent[step]

    def exact(
        self, walls: list[TrackedWall], robot: pymunk.Shape, bx: float, by: float, cos: float, sin: float
    ) -> float:
        """The exact distance between the hull and the nearest of ``walls`` (convex polygons): hull
        vertices to each wall, then the wall corners that could be nearer than that to the hull."""
        ax, ay = bx + self.axle_x * cos, by + self.axle_x * sin
        gap = math.inf
        distance = self._distance
        for shape, frame, _ in walls:
            if frame is None:  # a polygon obstacle: ask Chipmunk
                for x, y in self.hull:
                    d = distance(shape, (bx + x * cos - y * sin, by + x * sin + y * cos))[0]
                    if d < gap:
                        gap = d
                continue
            cx, cy, ux, uy, hl, ht = frame
            # a hull vertex (x, y) of the body lies at (ox + x * a + y * b, oy + x * c + y * e) in the
            # wall's frame (along its length, across it)
            ox, oy = (bx - cx) * ux + (by - cy) * uy, (by - cy) * ux - (bx - cx) * uy
            a, b = cos * ux + sin * uy, cos * uy - sin * ux
            c, e = sin * ux - cos * uy, cos * ux + sin * uy
            for x, y in self.hull:
                along, across = ox + x * a + y * b, oy + x * c + y * e
                # abs() without a builtin call: the sign of a zero is lost in subtracting hl, ht > 0
                ex = (along if along >= 0.0 else -along) - hl
                ey = (across if across >= 0.0 else -across) - ht
                if ex >= gap or ey >= gap:  # the distance is at least max(ex, ey): not nearer
                    continue
                if ex > 0.0 or ey > 0.0:
                    d = math.hypot(ex if ex > 0.0 else 0.0, ey if ey > 0.0 else 0.0)
                else:  # inside the box: the (negative) depth
                    d = ex if ex > ey else ey
                if d < gap:
                    gap = d
        reach = self.tables.reach
        for _, _, corners in walls:
            for cx, cy in corners:
                if math.hypot(cx - ax, cy - ay) - reach < gap:  # could this corner be nearer?
                    gap = min(gap, distance(robot, (cx, cy))[0])
        return gap
