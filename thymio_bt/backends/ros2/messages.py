"""Conversions between ROS 2 message fields and thymio-bt's values (no ROS import needed).

Example::

    >>> round(yaw_of(*quaternion_of(1.2)), 12)
    1.2
    >>> stamp_ns(3, 500_000_000)
    3500000000
    >>> proximity_range(float("-inf"))     # Gazebo: closer than range_min
    0.0
"""

from __future__ import annotations

import math


def quaternion_of(yaw: float) -> tuple[float, float, float, float]:
    """The (x, y, z, w) quaternion of a rotation by ``yaw`` about z."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def yaw_of(x: float, y: float, z: float, w: float) -> float:
    """The rotation about z of a quaternion (roll and pitch ignored: the robot is on the floor)."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def stamp_ns(sec: int, nanosec: int) -> int:
    """A ROS time (builtin_interfaces/Time) in integer nanoseconds."""
    return sec * 1_000_000_000 + nanosec


def stamp_parts(ns: int) -> tuple[int, int]:
    """Integer nanoseconds as (sec, nanosec) for a builtin_interfaces/Time."""
    return divmod(ns, 1_000_000_000)


def proximity_range(value: float, range_max: float = math.inf) -> float:
    """A LaserScan ray or a Range as thymio-bt reads it: metres, ``inf`` when nothing is in range.

    REP 117: ``+inf`` is nothing within range, ``-inf`` something closer than the minimum (0 here),
    NaN an invalid reading (nothing seen); a value beyond ``range_max`` is nothing seen too."""
    if math.isnan(value) or value > range_max:
        return math.inf
    return max(value, 0.0)
