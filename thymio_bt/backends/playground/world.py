"""A maze as an Aseba Playground world file (XML, centimetres, radians).

The Playground's arena starts at (0, 0) and has its own walls; the maze is shifted in by a margin
and a parking bay is added to its right, where a deleted robot waits. Playground 1.6.99 walls have
no angle, so every wall must be parallel to an axis.

Example::

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> world = playground_world(load_maze(resolve_maze("two_parts_maze")), Pose(0.1, 0.1, 0.0), port=33333)
    >>> world.text.count("<wall"), world.text.count("<robot")      # written to a .playground file
    (21, 1)
    >>> x_cm, y_cm = world.to_enki(0.5, 0.3)          # the Playground's (x, y) in cm of a maze point
    >>> round(x_cm, 2), round(y_cm, 2), world.from_enki(x_cm, y_cm)
    (80.5, 60.5, (0.5, 0.3))
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

from thymio_bt.errors import Problem, UserError
from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze

#: room around the maze inside the arena, and the width of the parking bay on its right (m): a robot
#: that leaves the maze (the 6x6 missions) must find open floor, beyond its sensors' 14 cm
MARGIN, BAY = 0.30, 0.30
WALL_HEIGHT = 0.05


@dataclass(frozen=True)
class PlaygroundWorld:
    """A world file's text and how maze coordinates map to the Playground's."""

    text: str
    offset: tuple[float, float]  # maze (x, y) + offset = Playground position, in m
    parking: tuple[float, float]  # where a deleted robot waits, maze coordinates

    def to_enki(self, x: float, y: float) -> tuple[float, float]:
        """The Playground's position (cm) of the maze point (x, y) (m)."""
        return 100.0 * (x + self.offset[0]), 100.0 * (y + self.offset[1])

    def from_enki(self, x_cm: float, y_cm: float) -> tuple[float, float]:
        """The maze point (m) of the Playground's position (x, y) in cm."""
        return x_cm / 100.0 - self.offset[0], y_cm / 100.0 - self.offset[1]


#: an edge within this angle of an axis counts as parallel to it (rad; 1 mm over a metre)
AXIS_TOLERANCE = 1e-3


def _axis_aligned(corners: list[tuple[float, float]]) -> bool:
    for (x0, y0), (x1, y1) in zip(corners, [*corners[1:], corners[0]], strict=True):
        angle = math.atan2(y1 - y0, x1 - x0) % (math.pi / 2)
        if min(angle, math.pi / 2 - angle) > AXIS_TOLERANCE:
            return False
    return True


def playground_world(maze: Maze, axle: Pose, port: int, name: str = "thymio") -> PlaygroundWorld:
    """The world of ``maze`` with one Thymio whose wheel axle is at ``axle`` (maze coordinates)."""
    if maze.walls or maze.obstacles:
        xmin, ymin, xmax, ymax = maze.bounds()
    else:
        xmin, ymin, xmax, ymax = axle.x - 0.5, axle.y - 0.5, axle.x + 0.5, axle.y + 0.5
    offset = (MARGIN - xmin, MARGIN - ymin)
    width, height = xmax - xmin + 2 * MARGIN + BAY, ymax - ymin + 2 * MARGIN
    world = PlaygroundWorld("", offset, (xmax + MARGIN + BAY / 2, (ymin + ymax) / 2))
    lines = [
        "<!DOCTYPE aseba-playground>",
        "<aseba-playground>",
        '  <color name="wall" r="0.8" g="0.8" b="0.8"/>',
        f'  <world w="{100 * width:.4f}" h="{100 * height:.4f}" color="wall"/>',
    ]
    for i, shape in enumerate(maze.shapes()):
        corners = shape.corners()
        xs, ys = [x for x, _ in corners], [y for _, y in corners]
        if not _axis_aligned(corners):
            raise UserError(
                Problem(
                    f"the maze's shape {i + 1} is not parallel to an axis",
                    hint="Aseba Playground 1.6.99 walls have no angle: turn the maze's walls parallel to x and y",
                )
            )
        cx, cy = world.to_enki((min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2)
        lines.append(
            f'  <wall x="{cx:.4f}" y="{cy:.4f}" l1="{100 * (max(xs) - min(xs)):.4f}" '
            f'l2="{100 * (max(ys) - min(ys)):.4f}" h="{100 * WALL_HEIGHT:.1f}" color="wall"/>'
        )
    rx, ry = world.to_enki(axle.x, axle.y)
    lines.append(
        f'  <robot type="thymio2" name={quoteattr(name)} x="{rx:.4f}" y="{ry:.4f}" '
        f'angle="{axle.yaw:.6f}" port="{port}" nodeId="1"/>'
    )
    lines.append("</aseba-playground>")
    return PlaygroundWorld("\n".join(lines) + "\n", offset, world.parking)
