"""What a Thymio is, as data: geometry, sensors, speed limits, motor units and calibration.

Robots differ (the course's URDF, the Thymio makers' Enki simulator, a real robot on a desk), so every
number a backend or behaviour needs about the robot lives in one :class:`RobotModel`, and several
models live side by side in :data:`ROBOTS`, chosen per run by name (``--robot enki``). Nothing here
imports a physics engine: the simulator, the real-robot backends, the behaviours and the plots share it.

Frames: ``base_link`` is the course's spawn and odometry point; the robot turns about the wheel axle,
``-axle_x`` behind it. x points forward, y to the left. Use :meth:`RobotModel.axle_of` and
:meth:`RobotModel.base_of` rather than repeating the arithmetic.

Example::

    >>> robot = robot_model("course")
    >>> robot.wheel_speeds(0.1, 0.0)
    (0.1, 0.1)
    >>> [s.name for s in robot.sensors][:2]
    ['front_left', 'front_center_left']
    >>> robot_model("enki").max_wheel_speed
    0.166
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Literal, TypeGuard, get_args

from thymio_bt.geometry import Pose
from thymio_bt.sensor_tables import ENKI_THYMIO2, WEBOTS_THYMIO2, CalibrationTable

#: The 7 proximity sensors, front (left to right) then rear, as in the course URDF.
SENSOR_NAMES: tuple[str, ...] = (
    "front_left",
    "front_center_left",
    "front_center",
    "front_center_right",
    "front_right",
    "rear_left",
    "rear_right",
)

#: how a robot's own readings are made (:attr:`RobotModel.sensor_model`)
SensorModelName = Literal["rays", "raw", "cone"]
#: how the simulator makes a run's readings (a mission's ``sensor_model``): ``metres`` is ``rays``
SimSensorModel = Literal["metres", "raw", "cone"]
SIM_SENSOR_MODELS: tuple[SimSensorModel, ...] = get_args(SimSensorModel)
#: a robot model's sensor model as the simulator names it (``rays``: the course's exact rays, in metres)
SIM_SENSOR_MODEL: dict[SensorModelName, SimSensorModel] = {"rays": "metres", "raw": "raw", "cone": "cone"}


def is_sim_sensor_model(name: str) -> TypeGuard[SimSensorModel]:
    """Whether ``name`` is one of :data:`SIM_SENSOR_MODELS`.

    >>> is_sim_sensor_model("cone"), is_sim_sensor_model("rays")
    (True, False)
    """
    return name in SIM_SENSOR_MODELS


@dataclass(frozen=True, slots=True)
class SensorPose:
    """One proximity sensor: where it sits in base_link and where it looks (yaw, radians)."""

    name: str
    x: float
    y: float
    yaw: float


@dataclass(frozen=True, slots=True)
class RobotModel:
    """A Thymio II variant: everything that differs between robots, in metres, seconds and radians.

    - ``hull``: the collision outline in base_link, counter-clockwise.
    - ``sensors``: the seven horizontal proximity sensors in :data:`SENSOR_NAMES` order.
    - ``range_min`` / ``range_max``: what a proximity sensor can report, in metres.
    - ``metres_per_unit`` / ``max_units``: Aseba motor units (``motor.left.target``) to wheel speed
      (:meth:`wheel_speed_of`, :meth:`motor_targets`); ``max_wheel_speed`` is ``max_units`` of them.
    - ``calibration``: raw ``prox.horizontal`` reading ↔ distance for this robot.
    - ``sensor_model``: how a simulator should make its readings by default (``rays``: one exact ray
      per sensor as in the course's Gazebo; ``raw``: rays through the calibration, noisy integers;
      ``cone``: Enki's three-ray cones).
    - ``command_delay``: how late a new wheel command is applied (s); ``motor_noise``: relative
      uniform noise on each wheel speed (Enki: 0.027).
    """

    name: str
    description: str
    axle_x: float
    wheel_separation: float
    wheel_radius: float
    max_wheel_speed: float
    mass: float
    hull: tuple[tuple[float, float], ...]
    sensors: tuple[SensorPose, ...]
    range_min: float
    range_max: float
    sensor_rate_hz: float
    metres_per_unit: float
    max_units: int
    calibration: CalibrationTable
    sensor_model: SensorModelName = "rays"
    command_delay: float = 0.0
    motor_noise: float = 0.0

    # ------------------------------------------------------------------ kinematics
    def wheel_speeds(self, linear: float, angular: float) -> tuple[float, float]:
        """Left and right wheel rim speeds (m/s) for a body velocity, as the diff-drive plugin does."""
        half = angular * self.wheel_separation / 2.0
        return linear - half, linear + half

    def body_velocity(self, left: float, right: float) -> tuple[float, float]:
        """Linear and angular velocity from wheel rim speeds."""
        return (left + right) / 2.0, (right - left) / self.wheel_separation

    def limited_wheel_speeds(
        self, linear: float, angular: float, max_wheel: float | None = None
    ) -> tuple[float, float]:
        """The wheel speeds of a command, both scaled down when one would exceed ``max_wheel`` (the
        robot's limit by default), which keeps the turn radius."""
        limit = self.max_wheel_speed if max_wheel is None else max_wheel
        left, right = self.wheel_speeds(linear, angular)
        # max(abs(left), abs(right)) without builtin calls (once per command on the hot path)
        left_abs, right_abs = (-left if left < 0.0 else left), (-right if right < 0.0 else right)
        fastest = right_abs if right_abs > left_abs else left_abs
        if fastest <= limit:
            return left, right
        scale = limit / fastest
        return self.wheel_speeds(linear * scale, angular * scale)

    # ------------------------------------------------------------------ motor units
    def wheel_speed_of(self, units: float, speed_scale: float = 1.0) -> float:
        """The wheel speed (m/s) of ``units`` Aseba motor units (``motor.*.speed``), on a robot whose
        wheels cover ``speed_scale`` times the model's distance per unit.

        >>> COURSE.wheel_speed_of(250), ENKI.wheel_speed_of(500, speed_scale=0.5)
        (0.1, 0.083)
        """
        return units * (self.metres_per_unit * speed_scale)

    def motor_targets(self, linear: float, angular: float, speed_scale: float = 1.0) -> tuple[int, int]:
        """The motor targets (``motor.*.target``, integer units) of a body velocity: its wheel speeds,
        both scaled down when one would exceed ``max_units`` (the turn radius kept), rounded.
        ``speed_scale`` as for :meth:`wheel_speed_of`.

        The speeds are those of :meth:`limited_wheel_speeds`, but scaled as wheel speeds rather than as
        a command: a real robot's targets stay what they have always been to the last unit (the two
        roundings part at exact ties: 2 of 2.7 million commands tried).

        >>> COURSE.motor_targets(0.1, 1.0), COURSE.motor_targets(0.0, 50.0)
        ((133, 367), (-500, 500))
        """
        per_unit = self.metres_per_unit * speed_scale
        left, right = self.wheel_speeds(linear, angular)
        scale = min(1.0, self.max_units * per_unit / max(abs(left), abs(right), 1e-12))
        top = self.max_units
        return (
            max(-top, min(top, round(left * scale / per_unit))),
            max(-top, min(top, round(right * scale / per_unit))),
        )

    # ------------------------------------------------------------------ frames
    def axle_of(self, pose: Pose) -> tuple[float, float, float]:
        """The wheel axle centre (x, y, yaw) of a base_link pose."""
        return (pose.x + self.axle_x * math.cos(pose.yaw), pose.y + self.axle_x * math.sin(pose.yaw), pose.yaw)

    def base_of(self, x: float, y: float, yaw: float) -> Pose:
        """The base_link pose of an axle centre at (x, y) with heading ``yaw``."""
        return Pose(x - self.axle_x * math.cos(yaw), y - self.axle_x * math.sin(yaw), yaw)

    def hull_at(self, pose: Pose) -> list[tuple[float, float]]:
        """The hull's corners in the world for a base_link pose."""
        cos, sin = math.cos(pose.yaw), math.sin(pose.yaw)
        return [(pose.x + x * cos - y * sin, pose.y + x * sin + y * cos) for x, y in self.hull]

    def sensor(self, name: str) -> SensorPose:
        """The sensor called ``name`` (a :data:`SENSOR_NAMES` entry)."""
        return self.sensors[SENSOR_NAMES.index(name)]


def integrate_arc(x: float, y: float, yaw: float, v: float, w: float, duration: float) -> tuple[float, float, float]:
    """Dead reckoning: where a point moving at (v, w) for ``duration`` ends, along the exact arc."""
    turn = w * duration
    if abs(turn) < 1e-9:
        return x + v * duration * math.cos(yaw), y + v * duration * math.sin(yaw), yaw + turn
    radius = v / w
    return (
        x + radius * (math.sin(yaw + turn) - math.sin(yaw)),
        y - radius * (math.cos(yaw + turn) - math.cos(yaw)),
        yaw + turn,
    )


def _course_hull() -> tuple[tuple[float, float], ...]:
    """The course mesh's outline: flat rear with 1 mm chamfers, straight sides, and the front arc.

    The arc is the circle through (0.0303, ±0.0559) and the nose (0.0557, 0), as in the mesh.
    """
    rear, side, arc_start, nose = -0.0543, 0.0559, 0.0303, 0.0557
    centre = (nose**2 - arc_start**2 - side**2) / (2 * (nose - arc_start))
    radius = nose - centre
    half = math.atan2(side, arc_start - centre)
    arc = [
        (centre + radius * math.cos(a), radius * math.sin(a)) for a in (-half + 2 * half * i / 12 for i in range(13))
    ]
    chamfer = 0.001
    return ((rear, -side + chamfer), (rear + chamfer, -side), *arc, (rear + chamfer, side), (rear, side - chamfer))


#: The course's Thymio, number for number (the URDF, Gazebo plugins: docs/sources.md, "Robot geometry and sensors").
COURSE = RobotModel(
    name="course",
    description="the course's URDF in Gazebo classic: one exact ray per sensor to 9.75 cm, 20 cm/s",
    axle_x=-0.0243,
    wheel_separation=0.0935,
    wheel_radius=0.022,
    max_wheel_speed=0.20,  # a real Thymio's limit: 500 motor units ≈ 20 cm/s (Mobsya's API doc)
    mass=0.2599,  # base 0.2052 + two wheels 0.027 + 7 sensor links
    hull=_course_hull(),
    sensors=(  # URDF proximity_sensors.xacro, in base_link
        SensorPose("front_left", 0.0387, 0.0493, 0.66323),
        SensorPose("front_center_left", 0.0513, 0.0261, 0.33161),
        SensorPose("front_center", 0.0557, 0.0, 0.0),
        SensorPose("front_center_right", 0.0513, -0.0261, -0.33161),
        SensorPose("front_right", 0.0387, -0.0493, -0.66323),
        SensorPose("rear_left", -0.0543, 0.0305, math.pi),
        SensorPose("rear_right", -0.0543, -0.0305, math.pi),
    ),
    range_min=0.0005,
    range_max=0.0975,
    sensor_rate_hz=10.0,
    metres_per_unit=0.20 / 500,
    max_units=500,
    calibration=WEBOTS_THYMIO2,
)


def _from_axle(*poses: tuple[float, float, float]) -> tuple[SensorPose, ...]:
    """The seven sensors, given in :data:`SENSOR_NAMES` order in Enki's
    frame (x, y in cm about the wheel axle; yaw), in base_link metres."""
    return tuple(
        SensorPose(name, x_cm / 100 + COURSE.axle_x, y_cm / 100, yaw)
        for name, (x_cm, y_cm, yaw) in zip(SENSOR_NAMES, poses, strict=True)
    )


#: the sensors of Enki's Thymio2 and of Webots' (a real robot), as (x, y) cm about the wheel axle and
#: yaw, in SENSOR_NAMES order (docs/sources.md, "Enki and the real robot")
# fmt: off
_ENKI_SENSORS = (
    (6.2, 4.85, 0.69813), (7.5, 2.55, 0.34906), (7.95, 0.0, 0.0),
    (7.5, -2.55, -0.34906), (6.2, -4.85, -0.69813),
    (-2.95, 2.95, math.pi), (-2.95, -2.95, math.pi),
)
_REAL_SENSORS = (
    (6.34, 5.06, math.radians(39.3)), (7.68, 2.70, math.radians(20.1)), (8.16, 0.0, 0.0),
    (7.68, -2.70, math.radians(-20.1)), (6.34, -5.06, math.radians(-40.1)),
    (-3.07, 3.18, math.pi), (-3.07, -3.18, math.pi),
)
# fmt: on


#: Enki's Thymio2 (Aseba Playground; enki/robots/thymio2/Thymio2.cpp): cone sensors to 14 cm at ±20°/±40°,
#: wheels 9.4 cm apart, 16.6 cm/s at 500 units, commands one 10 ms step late, ±2.7 % motor noise.
ENKI = replace(
    COURSE,
    name="enki",
    description="Enki's Thymio2 (Aseba Playground): 3-ray cone sensors to 14 cm, 16.6 cm/s, 9.4 cm wheel base",
    wheel_separation=0.094,
    max_wheel_speed=0.166,
    sensors=_from_axle(*_ENKI_SENSORS),
    range_max=0.14,
    metres_per_unit=0.166 / 500,
    calibration=ENKI_THYMIO2,
    sensor_model="cone",
    command_delay=0.01,
    motor_noise=0.027,
)

#: A starting point for a real Thymio II: Webots' sensor poses and calibration, 20 cm/s at 500 units.
#: Measure your own with ``thymio-bt calibrate`` — robots and surfaces differ.
REAL = replace(
    ENKI,
    name="real",
    description="a real Thymio II as Webots models it (a starting point: calibrate your own robot)",
    wheel_separation=0.0935,
    max_wheel_speed=0.20,
    sensors=_from_axle(*_REAL_SENSORS),
    range_max=0.0933,
    metres_per_unit=0.20 / 500,
    calibration=WEBOTS_THYMIO2,
    sensor_model="raw",
    command_delay=0.0,
    motor_noise=0.0,
)

#: The robot models a run can name, by name.
ROBOTS: dict[str, RobotModel] = {m.name: m for m in (COURSE, ENKI, REAL)}
#: the robot a mission runs with when it names none (and no backend has its own): the course's
DEFAULT_ROBOT = COURSE.name
#: the furthest any built-in robot's proximity sensors read (m): a sensed length's bound before the robot is known
WIDEST_RANGE = max(m.range_max for m in ROBOTS.values())


def robot_model(name: str | None = None) -> RobotModel:
    """The robot model called ``name``, or the profile file ``name`` (``.yaml``, written by
    ``thymio-bt calibrate``), or :data:`DEFAULT_ROBOT` for None (a mission that names no robot);
    ``KeyError`` with the known names otherwise."""
    if name is None:
        return ROBOTS[DEFAULT_ROBOT]
    if name in ROBOTS:
        return ROBOTS[name]
    from thymio_bt.robot.profile import is_profile_path

    if is_profile_path(name):
        return _profiled(name)
    raise KeyError(f"no robot model named '{name}' (known: {', '.join(ROBOTS)}, or a profile file .yaml)")


@lru_cache(maxsize=16)
def _profiled(path: str) -> RobotModel:
    """The model the profile file at ``path`` describes: its base with the numbers it measured."""
    from thymio_bt.robot.profile import read_profile

    base, changes = read_profile(path, ROBOTS)
    return replace(ROBOTS[base], **changes)
