"""Conversions between ROS 2 message fields and thymio-bt's values (no ROS import needed: a message
is read or filled by its fields' names, so any object with those fields will do).

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
from typing import Any, Literal

from thymio_bt.geometry import Pose

#: an odometry message as the backend keeps it: stamp (ns), x, y, yaw, linear and angular velocity
Odometry = tuple[int, float, float, float, float, float]


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


def odometry_of(msg: Any) -> Odometry:
    """A nav_msgs/Odometry as (stamp ns, x, y, yaw, v, w).

    >>> from types import SimpleNamespace as M
    >>> stamp, position = M(sec=2, nanosec=5), M(x=0.5, y=0.25)
    >>> pose = M(pose=M(position=position, orientation=M(x=0.0, y=0.0, z=0.0, w=1.0)))
    >>> twist = M(twist=M(linear=M(x=0.1), angular=M(z=-0.2)))
    >>> odometry_of(M(header=M(stamp=stamp), pose=pose, twist=twist))
    (2000000005, 0.5, 0.25, 0.0, 0.1, -0.2)
    """
    p, q, t = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist
    return (
        stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec),
        p.x,
        p.y,
        yaw_of(q.x, q.y, q.z, q.w),
        t.linear.x,
        t.angular.z,
    )


def reading_of(msg: Any, sensor_type: Literal["LaserScan", "Range"], range_max: float) -> tuple[int, float]:
    """A proximity message (a single-ray LaserScan or a Range) as (stamp ns, metres or inf).

    >>> from types import SimpleNamespace as M
    >>> header = M(stamp=M(sec=1, nanosec=0))
    >>> reading_of(M(header=header, ranges=[0.05]), "LaserScan", 0.0975)
    (1000000000, 0.05)
    >>> reading_of(M(header=header, ranges=[]), "LaserScan", 0.0975)      # no ray: nothing seen
    (1000000000, inf)
    >>> reading_of(M(header=header, range=0.2), "Range", 0.0975)          # beyond the range
    (1000000000, inf)
    """
    value = msg.ranges[0] if sensor_type == "LaserScan" and len(msg.ranges) else getattr(msg, "range", math.inf)
    return stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec), proximity_range(float(value), range_max)


def set_pose(msg: Any, pose: Pose) -> None:
    """Fill a geometry_msgs/Pose with a planar pose (z left as it is).

    >>> from types import SimpleNamespace as M
    >>> msg = M(position=M(x=0.0, y=0.0), orientation=M(x=0.0, y=0.0, z=0.0, w=1.0))
    >>> set_pose(msg, Pose(0.1, 0.2, 0.0))
    >>> msg.position.x, msg.position.y, msg.orientation.w
    (0.1, 0.2, 1.0)
    """
    msg.position.x, msg.position.y = pose.x, pose.y
    o = msg.orientation
    o.x, o.y, o.z, o.w = quaternion_of(pose.yaw)
