"""The maze format: walls as from/to segments with a thickness, and named spawn poses.

A wall is a box ``thickness`` wide that extends ``thickness/2`` past both ends, so the course's
0.61 m Gazebo boxes are 0.6 m segments on a 0.2 m grid. Values accept units (``20cm``, ``pi/2``).

A maze file (YAML)::

    name: corridor
    walls:
      - {from: [0, 0], to: [1, 0]}
      - {from: [0, 20cm], to: [1, 0.2], thickness: 1cm}
    spawns:
      start: [0.1, 0.1, 90deg]

Example (the same maze, as the file's mapping)::

    >>> maze = Maze.model_validate({
    ...     "name": "corridor",
    ...     "walls": [{"from": [0, 0], "to": [1, 0]}, {"from": [0, "20cm"], "to": [1, 0.2], "thickness": "1cm"}],
    ...     "spawns": {"start": [0.1, 0.1, "90deg"]},
    ... })
    >>> maze.walls[1].start, maze.walls[1].thickness, maze.spawn("start")
    ((0.0, 0.2), 0.01, Pose(x=0.1, y=0.1, yaw=1.5707963267948966))
    >>> maze.bounds()                  # the walls' boxes extend half their thickness
    (-0.005, -0.005, 1.005, 0.20500000000000002)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.geometry import Pose
from thymio_bt.inputs.fields import Angle, Length, Point, hinted_error


class Wall(BaseModel):
    """A straight wall: a box from ``from`` to ``to``, ``thickness`` wide, extended by half of it."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True, frozen=True)
    start: Point = Field(alias="from", description="one end of the wall: [x, y] in metres, e.g. from: [0, 0.2]")
    end: Point = Field(alias="to", description="the other end of the wall: [x, y] in metres, e.g. to: [0.6, 0.2]")
    thickness: Annotated[Length, Field(gt=0, le=1.0)] = 0.01
    name: str | None = None

    @model_validator(mode="after")
    def _not_degenerate(self) -> Wall:
        if self.start == self.end:
            raise hinted_error(
                "a wall needs two different end points",
                "a wall goes from one point to another, e.g. {from: [0, 0], to: [0.6, 0]}",
            )
        return self

    @property
    def length(self) -> float:
        """The segment's length from ``from`` to ``to`` (the box is a thickness longer)."""
        return math.dist(self.start, self.end)

    def corners(self) -> list[tuple[float, float]]:
        """The 4 corners of the wall's box, counter-clockwise."""
        return wall_corners(self.start, self.end, self.thickness)


def wall_corners(start: Sequence[float], end: Sequence[float], thickness: float) -> list[tuple[float, float]]:
    """The 4 corners, counter-clockwise, of a wall's box from ``start`` to ``end``: it extends half
    its thickness past each end and to each side."""
    (x0, y0), (x1, y1) = start, end
    length = math.dist(start, end)
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    h = thickness / 2.0
    ex, ey = ux * h, uy * h  # extension past the ends
    nx, ny = -uy * h, ux * h  # half thickness across
    return [
        (x0 - ex - nx, y0 - ey - ny),
        (x1 + ex - nx, y1 + ey - ny),
        (x1 + ex + nx, y1 + ey + ny),
        (x0 - ex + nx, y0 - ey + ny),
    ]


class Obstacle(BaseModel):
    """A static obstacle: a ``box`` (centre, size, yaw) or a convex ``polygon`` (list of points)."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    name: str | None = None
    center: Point | None = None
    size: tuple[Length, Length] | None = None
    yaw: Angle = 0.0
    polygon: list[Point] | None = None

    @model_validator(mode="after")
    def _one_shape(self) -> Obstacle:
        if (self.polygon is None) == (self.center is None or self.size is None):
            raise ValueError("an obstacle is either a box (center and size) or a polygon (a list of points)")
        if self.size is not None and min(self.size) <= 0:
            raise ValueError("a box's size must be positive")
        if self.polygon is not None:
            points = self.polygon
            if len(points) < 3:
                raise ValueError("a polygon needs at least 3 points")
            n = len(points)
            turns = [
                (points[(i + 1) % n][0] - points[i][0]) * (points[(i + 2) % n][1] - points[(i + 1) % n][1])
                - (points[(i + 1) % n][1] - points[i][1]) * (points[(i + 2) % n][0] - points[(i + 1) % n][0])
                for i in range(n)
            ]
            if not (all(t > 0 for t in turns) or all(t < 0 for t in turns)):
                raise hinted_error(
                    "the polygon must be convex with no repeated points",
                    "split a concave obstacle into several convex ones",
                )
        return self

    def corners(self) -> list[tuple[float, float]]:
        """The 4 corners of the box, or the polygon's points, counter-clockwise or as written."""
        if self.polygon is not None:
            return [tuple(p) for p in self.polygon]  # type: ignore[misc]
        assert self.center is not None and self.size is not None
        (cx, cy), (w, h) = self.center, self.size
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return [
            (cx + x * c - y * s, cy + x * s + y * c)
            for x, y in ((-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2))
        ]


class Spawn(BaseModel):
    """A named pose of base_link where the robot may start or be spawned."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    x: Length = Field(description="x of base_link, e.g. x: 0.1 or x: 10cm")
    y: Length = Field(description="y of base_link, e.g. y: 0.1 or y: 10cm")
    yaw: Angle = Field(0.0, description="heading, e.g. yaw: 90deg or yaw: pi/2")

    @model_validator(mode="before")
    @classmethod
    def _from_list(cls, value: Any) -> Any:
        if isinstance(value, (list, tuple)) and len(value) == 3:
            return {"x": value[0], "y": value[1], "yaw": value[2]}
        return value

    def pose(self) -> Pose:
        """The spawn as a :class:`~thymio_bt.geometry.Pose`."""
        return Pose(self.x, self.y, self.yaw)


class Area(BaseModel):
    """An axis-aligned rectangle ``from`` one corner ``to`` the other (e.g. a goal cell)."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True, frozen=True)
    start: Point = Field(alias="from", description="one corner [x, y]")
    end: Point = Field(alias="to", description="the opposite corner [x, y]")

    def contains(self, x: float, y: float) -> bool:
        """Whether (x, y) lies in the rectangle, edges included."""
        (x0, y0), (x1, y1) = self.start, self.end
        return min(x0, x1) <= x <= max(x0, x1) and min(y0, y1) <= y <= max(y0, y1)


class Maze(BaseModel):
    """Static walls and named spawn poses, in world metres; optionally a goal region."""

    model_config = ConfigDict(extra="forbid")
    name: str = "maze"
    description: str = ""
    source: str = ""
    walls: list[Wall] = Field(default=[])
    obstacles: list[Obstacle] = Field(default=[])
    spawns: dict[str, Spawn] = Field(default={})
    #: where the maze's goal is (e.g. a micromouse maze's centre cells): base_link inside any area
    goal: list[Area] = Field(default=[])

    def in_goal(self, x: float, y: float) -> bool:
        """Whether (x, y) lies in one of the goal areas (never, for a maze without a goal)."""
        return any(area.contains(x, y) for area in self.goal)

    def shapes(self) -> tuple[Wall | Obstacle, ...]:
        """The walls, then the obstacles: every solid shape, each with its ``corners()``."""
        return (*self.walls, *self.obstacles)

    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of all walls and obstacles; an empty maze has all zero."""
        corners = [c for wall in self.walls for c in wall.corners()]
        corners += [c for obstacle in self.obstacles for c in obstacle.corners()]
        if not corners:
            return (0.0, 0.0, 0.0, 0.0)
        xs, ys = [c[0] for c in corners], [c[1] for c in corners]
        return (min(xs), min(ys), max(xs), max(ys))

    def outside(self, x: float, y: float) -> bool:
        """Whether (x, y) lies beyond the walls' and obstacles' bounding box (:meth:`bounds`): the
        robot has left the maze."""
        x0, y0, x1, y1 = self.bounds()
        return not (x0 <= x <= x1 and y0 <= y <= y1)

    def spawn(self, name: str) -> Pose:
        """The pose of a named spawn; an unknown name is a :class:`UserError` with a hint."""
        if name not in self.spawns:
            raise UserError(
                Problem(
                    f"maze '{self.name}' has no spawn named '{name}'",
                    hint=did_you_mean(name, self.spawns)
                    if self.spawns
                    else "this maze defines no spawns: give a pose [x, y, yaw] instead",
                )
            )
        return self.spawns[name].pose()

    def to_yaml_dict(self) -> dict[str, Any]:
        """A plain dict in the file format, with values rounded to 0.1 mm."""

        def r(v: float) -> float:
            return round(v, 6) + 0.0

        out: dict[str, Any] = {"name": self.name}
        if self.description:
            out["description"] = self.description
        if self.source:
            out["source"] = self.source
        out["walls"] = [
            {
                **({"name": w.name} if w.name else {}),
                "from": [r(w.start[0]), r(w.start[1])],
                "to": [r(w.end[0]), r(w.end[1])],
                "thickness": r(w.thickness),
            }
            for w in self.walls
        ]
        if self.obstacles:
            out["obstacles"] = [o.model_dump(exclude_none=True, exclude_defaults=True) for o in self.obstacles]
        if self.spawns:
            out["spawns"] = {k: {"x": r(s.x), "y": r(s.y), "yaw": r(s.yaw)} for k, s in self.spawns.items()}
        if self.goal:
            out["goal"] = [
                {"from": [r(a.start[0]), r(a.start[1])], "to": [r(a.end[0]), r(a.end[1])]} for a in self.goal
            ]
        return out
