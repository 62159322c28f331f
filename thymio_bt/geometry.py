"""The types every room shares, at the bottom of the layers: a planar pose and the angle wrap.

Mazes, robot models, behaviours and backends all speak of poses; they take them from here, so no
room has to import another for them (:mod:`thymio_bt.robot.interface` re-exports them).

Example::

    >>> Pose(0.0, 0.0, 0.0).distance_to(Pose(0.3, 0.4, 0.0))
    0.5
    >>> round(wrap_angle(3 * math.pi / 2), 6)  # a three-quarter turn left is a quarter turn right
    -1.570796
    >>> new_pose(1.0, 2.0, 0.5) == Pose(1.0, 2.0, 0.5)
    True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Pose", "new_pose", "wrap_angle"]


#: pi and 2 pi as module globals: a global is one dictionary read where ``math.pi`` is two (the
#: simulation wraps an angle at every sensor refresh); 2.0 * pi is exact, so the bits are the same
_PI = math.pi
_TAU = 2.0 * math.pi


def wrap_angle(angle: float) -> float:
    """Normalise an angle to [-pi, pi)."""
    return (angle + _PI) % _TAU - _PI


@dataclass(frozen=True, slots=True)
class Pose:
    """A planar pose: position in metres, yaw in radians (counter-clockwise from +x)."""

    x: float
    y: float
    yaw: float

    def as_dict(self) -> dict[str, float]:
        """The pose as ``{"x", "y", "yaw"}``, as events and reports write it."""
        return {"x": self.x, "y": self.y, "yaw": self.yaw}

    def as_tuple(self) -> tuple[float, float, float]:
        """The pose as ``(x, y, yaw)``, for unpacking."""
        return (self.x, self.y, self.yaw)

    def distance_to(self, other: Pose) -> float:
        """The straight-line distance in metres between the two positions (headings aside)."""
        return math.hypot(other.x - self.x, other.y - self.y)


# the slots' member descriptors (``vars`` reaches them without reading them as fields)
_set_x, _set_y, _set_yaw = (vars(Pose)[name].__set__ for name in ("x", "y", "yaw"))


def new_pose(x: float, y: float, yaw: float) -> Pose:
    """``Pose(x, y, yaw)``, its slots filled directly: a frozen dataclass's ``__init__`` sets each
    field through ``object.__setattr__``, twice the cost (a simulation makes one per sensor refresh)."""
    pose = object.__new__(Pose)
    _set_x(pose, x)
    _set_y(pose, y)
    _set_yaw(pose, yaw)
    return pose
