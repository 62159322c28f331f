"""The geometry of a maze corridor as the front sensors see it, shared by the maze behaviours.

The course's ±38° front rays cross a corridor side 0.12 m ahead of the axle, so they see the side
walls of the cell ahead but never a wall exactly beside the robot; where a side ray meets a
straight wall traces that wall, and :func:`line_direction` gives its direction. Robot geometry and
sensor poses: docs/sources.md, "Robot geometry and sensors".

Example::

    >>> side_ray("left"), FRONT_PAIR
    ('front_left', ('front_center_left', 'front_center_right'))
    >>> angle, residual = line_direction([(0.0, 0.0), (1.0, 0.0), (2.0, 0.001)])
    >>> round(math.degrees(angle), 3), residual < 0.001
    (0.029, True)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

from thymio_bt.robot.model import COURSE

Side = Literal["left", "right"]

#: the course robot's sensor range: the largest distance a ``WallAhead`` may ask for
RANGE_MAX = COURSE.range_max
#: base_link's offset from the wheel axle (the same on every robot model)
AXLE_X = COURSE.axle_x
#: stationary readings WallFollow averages before a wall to square its heading to it
SQUARING_READINGS = 3

#: the corridor's heading is re-taken from the line through where a side ray met its wall, once the
#: points span WALL_SPAN of travel and lie within WALL_RESIDUAL of one line, when it differs from the
#: heading held by more than RETAKE_ANGLE and less than RETAKE_MAX (more is a wall across, not beside)
WALL_SPAN, WALL_RESIDUAL = 0.05, 0.0015
RETAKE_ANGLE, RETAKE_MAX = math.radians(1.0), math.radians(15.0)

#: the maze's four directions, as unit vectors in the frame of the start heading (quarter turns)
QUARTERS = ((1, 0), (0, 1), (-1, 0), (0, -1))

#: a front reading this much nearer than the tick before cannot be a wall approached (1 cm a tick
#: at most): a glint, held for a tick
GLINT_JUMP = 0.03
#: a reading nearer than this is a glint too (WallFollow stops 1.5 cm or more from walls)
GLINT_BELOW = 0.003

#: the sensor pairs that see a wall across the corridor ahead and behind, square to it
FRONT_PAIR, REAR_PAIR = ("front_center_left", "front_center_right"), ("rear_left", "rear_right")

#: the sensors that look ahead
FRONT_SENSORS = ("front_left", "front_center_left", "front_center", "front_center_right", "front_right")


def side_ray(side: str) -> str:
    """The outer front sensor on ``side`` (``left`` or ``right``): the one that sees a side wall."""
    return "front_left" if side == "left" else "front_right"


def line_direction(points: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """The direction (rad, modulo pi) of the least-squares line through ``points`` and the largest
    distance of a point from it.

    >>> angle, residual = line_direction([(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)])
    >>> round(math.degrees(angle), 6), round(residual, 9)
    (45.0, 0.0)
    """
    n = len(points)
    mx = sum(p[0] for p in points) / n
    my = sum(p[1] for p in points) / n
    sxx = sum((p[0] - mx) ** 2 for p in points)
    syy = sum((p[1] - my) ** 2 for p in points)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in points)
    angle = 0.5 * math.atan2(2.0 * sxy, sxx - syy)
    nx, ny = -math.sin(angle), math.cos(angle)
    return angle, max(abs((p[0] - mx) * nx + (p[1] - my) * ny) for p in points)
