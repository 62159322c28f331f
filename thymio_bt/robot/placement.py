"""Where a robot may stand in a maze, by plain geometry (no physics engine).

A spawn or start pose is refused when a coordinate is not finite, when the robot's hull leaves the
maze's bounds, or when it overlaps a wall or obstacle (both convex polygons: the separating axis
test). The simulator adds only what it alone knows (other robots); ``validate`` and the loader use
this directly, so checking a mission never loads pymunk.

Example::

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> from thymio_bt.robot.model import COURSE
    >>> maze = load_maze(resolve_maze("two_parts_maze"))
    >>> placement_problem(maze, COURSE, Pose(0.1, 0.1, 0.0)) is None      # the robot fits there
    True
    >>> print(placement_problem(maze, COURSE, Pose(0.0, 0.1, 0.0)))
    pose (0.000, 0.100) puts part of the robot outside the maze (walls span x in [-0.005, 2.005], y in [-0.005, 0.805])
    >>> round(clearance(maze, COURSE, Pose(0.1, 0.1, 0.0)), 4), round(ray_distance(maze, 0.1, 0.1, 0.0), 4)
    (0.0391, 0.495)
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import lru_cache

from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze
from thymio_bt.maze.model import wall_corners
from thymio_bt.robot.interface import Backend, Collision
from thymio_bt.robot.model import RobotModel

Polygon = Sequence[tuple[float, float]]
Box = tuple[float, float, float, float]
#: Bounding boxes farther apart than this cannot hold overlapping polygons, whatever the rounding of
#: the separating axis test: it is skipped for them.
_APART = 1e-9


def _box(polygon: Polygon) -> Box:
    xs, ys = [x for x, _ in polygon], [y for _, y in polygon]
    return min(xs), min(ys), max(xs), max(ys)


@dataclass(frozen=True)
class MazeShapes:
    """A maze's walls, then its obstacles, as polygons with their bounding boxes, and the maze's
    bounds: computed once for a simulator that checks placements during a run."""

    polygons: tuple[tuple[tuple[float, float], ...], ...]
    boxes: tuple[Box, ...]
    bounds: Box
    #: whether the maze has walls (only then must a robot stay inside its bounds)
    walled: bool

    @classmethod
    def of(cls, maze: Maze) -> MazeShapes:
        """``maze``'s shapes. Its walls' are computed once per geometry (every run of a sweep, and the
        runner's and the simulator's asking in one run, share them: 1 M instructions a run)."""
        geometry = [v for wall in maze.walls for v in (*wall.start, *wall.end, wall.thickness)]
        shapes = _wall_shapes(struct.pack(f"{len(geometry)}d", *geometry))
        if not maze.obstacles:
            return shapes
        polygons = tuple(tuple(obstacle.corners()) for obstacle in maze.obstacles)
        boxes = shapes.boxes + tuple(_box(p) for p in polygons)
        return cls(shapes.polygons + polygons, boxes, _union(boxes), shapes.walled)


def _union(boxes: Sequence[Box]) -> Box:
    """The bounding box of ``boxes`` (all zero for none), as :meth:`Maze.bounds` gives it."""
    if not boxes:
        return (0.0, 0.0, 0.0, 0.0)
    return (min(b[0] for b in boxes), min(b[1] for b in boxes), max(b[2] for b in boxes), max(b[3] for b in boxes))


@lru_cache(maxsize=16)
def _wall_shapes(geometry: bytes) -> MazeShapes:
    """The shapes of walls given as (x0, y0, x1, y1, thickness) doubles: keyed by their bytes, so two
    mazes share them only when every float is the same, bit for bit (0.0 and -0.0 differ)."""
    values = struct.unpack(f"{len(geometry) // 8}d", geometry)
    polygons = tuple(
        tuple(wall_corners(values[i : i + 2], values[i + 2 : i + 4], values[i + 4])) for i in range(0, len(values), 5)
    )
    boxes = tuple(_box(p) for p in polygons)
    return MazeShapes(polygons, boxes, _union(boxes), bool(polygons))


def _axes(polygon: Polygon) -> Iterable[tuple[float, float]]:
    for (x0, y0), (x1, y1) in zip(polygon, [*polygon[1:], polygon[0]], strict=True):
        yield y0 - y1, x1 - x0  # the edge's normal (not normalised: only signs matter)


def convex_overlap(a: Polygon, b: Polygon) -> bool:
    """Whether two convex polygons overlap with a positive area (touching edges do not count)."""
    for nx, ny in (*_axes(a), *_axes(b)):
        pa = [x * nx + y * ny for x, y in a]
        pb = [x * nx + y * ny for x, y in b]
        if max(pa) <= min(pb) or max(pb) <= min(pa):
            return False  # a separating axis
    return True


def _point_segment(px: float, py: float, a: tuple[float, float], b: tuple[float, float]) -> float:
    (ax, ay), (bx, by) = a, b
    dx, dy = bx - ax, by - ay
    t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy or 1.0)))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


def convex_gap(a: Polygon, b: Polygon) -> float:
    """The distance between two convex polygons (0 when they touch or overlap)."""
    if convex_overlap(a, b):
        return 0.0
    return min(
        _point_segment(px, py, p, q)
        for one, other in ((a, b), (b, a))
        for px, py in one
        for p, q in zip(other, [*other[1:], other[0]], strict=True)
    )


def clearance(maze: Maze, model: RobotModel, pose: Pose) -> float:
    """The smallest gap between the robot's hull at ``pose`` and the maze's walls and obstacles."""
    hull = model.hull_at(pose)
    return min((convex_gap(hull, shape.corners()) for shape in maze.shapes()), default=math.inf)


def placement_problem(maze: Maze | MazeShapes, model: RobotModel, pose: Pose) -> str | None:
    """Why the robot ``model`` cannot stand at ``pose`` in ``maze`` (None when it can)."""
    if not all(math.isfinite(v) for v in (pose.x, pose.y, pose.yaw)):
        return "the pose must be finite numbers"
    shapes = maze if isinstance(maze, MazeShapes) else MazeShapes.of(maze)
    hull = model.hull_at(pose)
    if shapes.walled:
        xmin, ymin, xmax, ymax = shapes.bounds
        if not all(xmin <= x <= xmax and ymin <= y <= ymax for x, y in hull):
            return (
                f"pose ({pose.x:.3f}, {pose.y:.3f}) puts part of the robot outside the maze "
                f"(walls span x in [{xmin:.3f}, {xmax:.3f}], y in [{ymin:.3f}, {ymax:.3f}])"
            )
    hx0, hy0, hx1, hy1 = _box(hull)
    for polygon, (x0, y0, x1, y1) in zip(shapes.polygons, shapes.boxes, strict=True):
        if x0 - hx1 > _APART or hx0 - x1 > _APART or y0 - hy1 > _APART or hy0 - y1 > _APART:
            continue
        if convex_overlap(hull, polygon):
            return f"pose ({pose.x:.3f}, {pose.y:.3f}, yaw {pose.yaw:.3f}) overlaps a wall"
    return None


def ray_distance(maze: Maze | MazeShapes, ox: float, oy: float, yaw: float) -> float:
    """How far from (ox, oy) along ``yaw`` the first wall or obstacle face is; inf when none is."""
    shapes = maze if isinstance(maze, MazeShapes) else MazeShapes.of(maze)
    c, s = math.cos(yaw), math.sin(yaw)
    best = math.inf
    for corners, (bx0, by0, bx1, by1) in zip(shapes.polygons, shapes.boxes, strict=True):
        # a box wholly behind the start along x or along y (by more than any rounding) is never hit
        if (
            (c >= 0.0 and bx1 < ox - _APART)
            or (c <= 0.0 and bx0 > ox + _APART)
            or (s >= 0.0 and by1 < oy - _APART)
            or (s <= 0.0 and by0 > oy + _APART)
        ):
            continue
        for (x0, y0), (x1, y1) in zip(corners, [*corners[1:], corners[0]], strict=True):
            hit = _ray_segment(ox, oy, c, s, x0, y0, x1, y1)
            if hit is not None and hit < best:
                best = hit
    return best


def _ray_segment(
    ox: float, oy: float, dx: float, dy: float, x0: float, y0: float, x1: float, y1: float
) -> float | None:
    """Distance along the ray (o, d) to the segment, or None when it misses."""
    ex, ey = x1 - x0, y1 - y0
    denom = dx * ey - dy * ex
    if abs(denom) < 1e-15:
        return None
    t = ((x0 - ox) * ey - (y0 - oy) * ex) / denom
    u = ((x0 - ox) * dy - (y0 - oy) * dx) / denom
    return t if t >= 0 and 0 <= u <= 1 else None


class ContactTracker:
    """A backend's smallest hull-to-wall gap and contact episodes, from a known pose and the maze's
    geometry: for backends without a physics engine of ours (the Playground's ground truth, a ROS 2
    robot's odometry). Call :meth:`update` after each tick's move.

    Example (a stand-in for a backend: its clearance, contacts and clock)::

        >>> import types
        >>> from thymio_bt.maze import load_maze, resolve_maze
        >>> from thymio_bt.robot.model import COURSE
        >>> backend = types.SimpleNamespace(min_clearance=math.inf, collisions=[], time=lambda: 1.5)
        >>> tracker = ContactTracker(load_maze(resolve_maze("two_parts_maze")), COURSE)
        >>> tracker.update(backend, Pose(0.1, 0.1, 0.0))
        >>> round(backend.min_clearance, 4), backend.collisions
        (0.0391, [])
        >>> tracker.update(backend, Pose(0.1, 0.06, 0.0))             # into the wall below
        >>> backend.min_clearance, backend.collisions
        (0.0, [Collision(t=1.5, x=0.1, y=0.06)])
    """

    def __init__(self, maze: Maze, model: RobotModel) -> None:
        self.maze, self.model = maze, model
        self.touching = False

    def update(self, backend: Backend, pose: Pose | None) -> None:
        """Take ``pose`` (None: nothing known) into ``backend.min_clearance`` and ``backend.collisions``."""
        if pose is None or not (self.maze.walls or self.maze.obstacles):
            return
        gap = clearance(self.maze, self.model, pose)
        backend.min_clearance = min(backend.min_clearance, gap)
        if gap <= 0.0 and not self.touching:
            backend.collisions.append(Collision(backend.time(), pose.x, pose.y))
        self.touching = gap <= 0.0
