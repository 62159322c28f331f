"""The course's Thymio II, number for number (../shared/course/robot.md), in base_link coordinates.

base_link is the course's spawn and odometry point; the robot turns about the wheel axle,
0.0243 m behind it. x points forward, y to the left.
"""

from __future__ import annotations

import math

#: x of the wheel axle centre (the rotation centre) in base_link.
AXLE_X = -0.0243
#: Distance between the wheels (the diff-drive plugin's wheel_separation).
WHEEL_SEPARATION = 0.0935
WHEEL_RADIUS = 0.022
#: A real Thymio's wheel-speed limit: 500 motor units ≈ 20 cm/s (Mobsya's Thymio API doc).
MAX_WHEEL_SPEED = 0.20
#: Total simulated mass (base 0.2052 + two wheels 0.027 + 7 sensor links), kg.
MASS = 0.2599

#: The proximity rays' range (Gazebo ray sensor min/max) and refresh rate.
RANGE_MIN = 0.0005
RANGE_MAX = 0.0975
SENSOR_RATE_HZ = 10.0

#: (name, x, y, yaw) of each ray's origin and direction in base_link (URDF proximity_sensors.xacro).
SENSORS: tuple[tuple[str, float, float, float], ...] = (
    ("front_left", 0.0387, 0.0493, 0.66323),
    ("front_center_left", 0.0513, 0.0261, 0.33161),
    ("front_center", 0.0557, 0.0, 0.0),
    ("front_center_right", 0.0513, -0.0261, -0.33161),
    ("front_right", 0.0387, -0.0493, -0.66323),
    ("rear_left", -0.0543, 0.0305, math.pi),
    ("rear_right", -0.0543, -0.0305, math.pi),
)


def _hull() -> tuple[tuple[float, float], ...]:
    """The collision outline: flat rear with 1 mm chamfers, straight sides, and the front arc.

    The arc is the circle through (0.0303, ±0.0559) and the nose (0.0557, 0), as in the mesh.
    """
    rear, side, arc_start, nose = -0.0543, 0.0559, 0.0303, 0.0557
    centre = (nose**2 - arc_start**2 - side**2) / (2 * (nose - arc_start))
    radius = nose - centre
    half = math.atan2(side, arc_start - centre)
    arc = [(centre + radius * math.cos(a), radius * math.sin(a))
           for a in (-half + 2 * half * i / 12 for i in range(13))]
    chamfer = 0.001
    return ((rear, -side + chamfer), (rear + chamfer, -side), *arc,
            (rear + chamfer, side), (rear, side - chamfer))


HULL = _hull()


def wheel_speeds(linear: float, angular: float) -> tuple[float, float]:
    """Left and right wheel rim speeds (m/s) for a body velocity, as the diff-drive plugin does."""
    half = angular * WHEEL_SEPARATION / 2.0
    return linear - half, linear + half


def body_velocity(left: float, right: float) -> tuple[float, float]:
    """Linear and angular velocity from wheel rim speeds."""
    return (left + right) / 2.0, (right - left) / WHEEL_SEPARATION


def limit_command(linear: float, angular: float, max_wheel: float = MAX_WHEEL_SPEED) -> tuple[float, float]:
    """Scale both wheels down when one would exceed ``max_wheel``, keeping the turn radius."""
    left, right = wheel_speeds(linear, angular)
    fastest = max(abs(left), abs(right))
    if fastest <= max_wheel:
        return linear, angular
    scale = max_wheel / fastest
    return linear * scale, angular * scale


def integrate_arc(x: float, y: float, yaw: float, v: float, w: float,
                  duration: float) -> tuple[float, float, float]:
    """Dead reckoning: where a point moving at (v, w) for ``duration`` ends, along the exact arc."""
    turn = w * duration
    if abs(turn) < 1e-9:
        return x + v * duration * math.cos(yaw), y + v * duration * math.sin(yaw), yaw + turn
    radius = v / w
    return (x + radius * (math.sin(yaw + turn) - math.sin(yaw)),
            y - radius * (math.cos(yaw + turn) - math.cos(yaw)), yaw + turn)
