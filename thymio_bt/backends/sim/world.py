"""The pymunk backend: the course's Thymio in a maze, implementing :class:`Robot` and :class:`Entities`.

The physics (walls, the robot's bodies and joints) is built by :mod:`.space`; this module steps it,
drives the robot, refreshes its sensors (:mod:`.readings`, :mod:`.sensor_models`) and clearance,
and spawns and deletes entities.

Example::

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> sim = Simulation(load_maze(resolve_maze("two_parts_maze")), spawn=Pose(0.1, 0.1, 0.0))
    >>> sim.drive(0.1, 0.0)
    >>> sim.advance(1.0)            # 1 s of simulated time in 100 Hz sub-steps
    >>> sim.pose()
    Pose(x=0.20000000000000007, y=0.1, yaw=0.0)
    >>> sim.proximity()["front_center"], sim.min_clearance       # nothing in range; the closest gap so far
    (inf, 0.0391)
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING

import pymunk

from thymio_bt.backends.sim.fastpath import RayCaster, RayReader, stepper
from thymio_bt.backends.sim.noise import NoiseConfig, NoiseSource
from thymio_bt.backends.sim.readings import lazy_scan
from thymio_bt.backends.sim.space import ROBOT_TYPE, WALL_TYPE, WALLS, MazeSpace, RobotBody
from thymio_bt.geometry import Pose, new_pose, wrap_angle
from thymio_bt.maze import Maze
from thymio_bt.robot.interface import ROBOT_ENTITY, Backend, Collision, Scan, Twist
from thymio_bt.robot.model import COURSE, RobotModel, SimSensorModel, integrate_arc
from thymio_bt.robot.placement import convex_overlap, placement_problem
from thymio_bt.sensor_tables import RawProximityModel, raw_scan_to_metres

if TYPE_CHECKING:
    from thymio_bt.backends.sim.sensor_models import ConeSensors

#: a pose's three floats as bytes: a key that tells 0.0 from -0.0 (as a placement message would)
_POSE_BITS = struct.Struct("3d").pack


@dataclass(frozen=True, slots=True)
class SimConfig:
    """Simulation settings; the defaults are the course's Gazebo model (noise-free)."""

    physics_hz: float = 100.0
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    seed: int = 0
    #: the robot simulated (geometry, sensor poses and range, speed limit)
    robot: RobotModel = COURSE
    #: the wheel-speed limit (m/s); None: the robot's own
    max_wheel_speed: float | None = None
    #: "metres": the course's ideal rays; "raw": what a real Thymio reports (noisy integer readings
    #: through the calibration table, to 9.33 cm), converted back to metres as the real backend does;
    #: "cone": Enki's three-ray cones (:mod:`thymio_bt.backends.sim.cone`), read through the robot's calibration
    sensor_model: SimSensorModel = "metres"


class Simulation(Backend):
    """A 2D simulation of one Thymio in a maze; advance it with :meth:`advance`."""

    def __init__(
        self, maze: Maze, spawn: Pose | None = None, config: SimConfig | None = None, robot_name: str = ROBOT_ENTITY
    ) -> None:
        self.maze = maze
        super().__init__()
        self.config = config or SimConfig()
        self.model = self.config.robot
        self._max_wheel = (
            self.model.max_wheel_speed if self.config.max_wheel_speed is None else self.config.max_wheel_speed
        )
        self.robot_name = robot_name
        self._build_space(maze)
        self._noise = NoiseSource(self.config.noise, self.config.seed)
        self._drifts = bool(self.config.noise.odometry)  # odometry drifts from the true pose
        if not self._drifts:
            # the same answer, a call less (asked several times a tick): an instance attribute
            # shadowing the method, which mypy cannot express
            self.pose = self.true_pose  # type: ignore[method-assign]
        self._noisy_wheels = bool(self.config.noise.wheel)
        #: range noise on the metres (raw readings get the raw model's noise instead)
        self._range_noise = bool(self.config.noise.range_sd) and self.config.sensor_model == "metres"
        #: noise-free metres are cast only when read (noise draws from streams whose order must hold)
        self._lazy_scan = self.config.sensor_model == "metres" and not self._range_noise
        self._raw_model: RawProximityModel | None = None
        if self.config.sensor_model == "raw":
            from thymio_bt.backends.sim.sensor_models import raw_model  # the metres model needs none of it

            self._raw_model = raw_model(self.config.seed, self.model)
        self._raw: dict[str, int] | None = None
        #: integers to read (:meth:`proximity_raw`) only with the raw and cone sensor models
        self.raw_readings = self.config.sensor_model in ("raw", "cone")
        self._entities: dict[str, RobotBody] = {}
        #: the robot's true pose at this physics step once read (None: not read since the last step)
        self._pose_now: Pose | None = None
        #: the held command (linear, angular) as floats; command() makes it a Twist when asked
        self._cmd = (0.0, 0.0)
        #: the last drive() arguments and their floats: a behaviour cruising passes the same float
        #: objects tick after tick
        self._drive_args: tuple[object, object, tuple[float, float]] = (None, None, self._cmd)
        self._applied = (0.0, 0.0)
        self._wheels_of: tuple[tuple[float, float] | None, tuple[float, float]] = (None, (0.0, 0.0))
        #: the last command whose wheel speeds were worked out (limited), and those speeds
        self._wheels_of_command: tuple[tuple[float, float] | None, tuple[float, float]] = (None, (0.0, 0.0))
        self._velocity = (0.0, 0.0)  # the body velocity (v, w) of the command, noise included
        self._delay_steps = round(self.model.command_delay * self.config.physics_hz)
        self._pending = False
        self._scan: Scan | None = None
        #: the last refresh's body pose (x, y, cos, sin) while _scan is None: proximity() reads from there
        self._sensed: tuple[float, float, float, float] | None = None
        self._odo = (0.0, 0.0, 0.0)  # dead-reckoned axle x, y and yaw (drift model only)
        self._odo_pose: tuple[tuple[float, float, float] | None, Pose | None] = (None, None)  # (_odo, its pose)
        self._contacts = 0
        #: the last pose's bits asked of _placement_problem, and its answer
        self._placed: tuple[bytes | None, str | None] = (None, None)
        self._build_sensors()
        self.space.on_collision(ROBOT_TYPE, WALL_TYPE, begin=self._on_begin, separate=self._on_separate)
        if spawn is not None:
            problem = self.spawn_problem(robot_name, spawn)
            if problem:
                raise ValueError(problem)
            self._add_robot(robot_name, spawn)

    def _build_space(self, maze: Maze) -> None:
        """The physics (:class:`~.space.MazeSpace`): the maze's static shapes and a clearance tracker over them."""
        built = MazeSpace(maze, self.model)
        self.space, self._shapes, self.bounds, self._clearance = (
            built.space,
            built.shapes,
            built.bounds,
            built.clearance,
        )
        self._dt = 1.0 / self.config.physics_hz
        self._step = stepper(self.space)
        self._ray = RayCaster(self.space)
        self._steps = 0

    def _build_sensors(self) -> None:
        """The proximity sensors: their rays, noise-free metres cast when read (walls only), Enki's cones."""
        self._sensor_every = max(1, round(self.config.physics_hz / self.model.sensor_rate_hz))
        reach = self._range_max = self.model.range_max
        self._range_min = self.model.range_min
        self._ray_names = [s.name for s in self.model.sensors]
        self._rays = [
            (s.x, s.y, s.x + reach * math.cos(s.yaw), s.y + reach * math.sin(s.yaw)) for s in self.model.sensors
        ]
        self._reader = RayReader(
            self.space,
            dict(zip(self._ray_names, self._rays, strict=True)),
            reach,
            self._range_min,
            pymunk.ShapeFilter(mask=WALLS),
        )
        self._cone: ConeSensors | None = None
        if self.config.sensor_model == "cone":
            from thymio_bt.backends.sim.sensor_models import ConeSensors

            self._cone = ConeSensors(self.model, self.config.seed)

    # ----------------------------------------------------------------- Robot
    def drive(self, linear: float, angular: float) -> None:
        """Hold (linear, angular); applied at once, or a few physics steps later with a command delay."""
        entity = self._entities.get(self.robot_name)
        if entity is None:
            return
        last_linear, last_angular, cmd = self._drive_args
        if linear is not last_linear or angular is not last_angular:
            cmd = (float(linear), float(angular))
            self._drive_args = (linear, angular, cmd)
        self._cmd = cmd
        if self._delay_steps:
            self._pending = True  # applied a few physics steps into the next advance (Enki: one)
        else:
            self._apply_command(entity)

    def exists(self) -> bool:
        """Whether the robot entity exists (it does not between a delete and a spawn)."""
        return self.robot_name in self._entities

    def proximity(self) -> Scan | None:
        """The last sensor refresh's readings (each ray cast when first read when noise-free); None while absent."""
        if self.robot_name not in self._entities:
            return None
        scan, sensed = self._scan, self._sensed
        if scan is None and sensed is not None:  # the last refresh's, each ray cast when read
            scan = self._scan = lazy_scan(self._reader, sensed)
        return scan

    def proximity_raw(self) -> dict[str, int] | None:
        """The latest readings as a real Thymio's integers (``sensor_model="raw"`` only), or None."""
        return self._raw if self.exists() else None

    def pose(self) -> Pose | None:
        """Odometry's pose: the true pose, or the dead-reckoned one when odometry noise is on."""
        if self._drifts:
            return self._odometry_pose() if self.robot_name in self._entities else None
        return self.true_pose()

    def true_pose(self) -> Pose | None:
        """The ground-truth pose (equal to :meth:`pose` unless odometry drift is on). Read once per
        physics step: behaviours ask for it several times a tick."""
        pose = self._pose_now
        if pose is None:
            entity = self._entities.get(self.robot_name)
            if entity is None:
                return None
            pose = self._pose_now = entity.pose()
        return pose

    def velocity(self) -> Twist:
        """The body's velocity along its heading and its turn rate (zero while absent)."""
        entity = self._entities.get(self.robot_name)
        if entity is None:
            return Twist()
        body = entity.body
        return Twist(body.velocity.dot(body.rotation_vector), body.angular_velocity)

    def command(self) -> Twist:
        """The held command as a Twist."""
        return Twist(*self._cmd)

    def time(self) -> float:
        """Simulated seconds: physics steps times the step length."""
        return self._steps * self._dt

    # -------------------------------------------------------------- Entities
    def spawn_problem(self, name: str, pose: Pose) -> str | None:
        """Why a robot cannot be spawned at ``pose`` (None when it can): the maze's geometry
        (:func:`~thymio_bt.robot.placement.placement_problem`), then the robots already there."""
        if name in self._entities:
            return f"an entity named '{name}' already exists: delete it first"
        problem = self._placement_problem(pose)
        if problem:
            return problem
        if self._entities:  # other robots: the hull against each
            hull = self.model.hull_at(pose)
            if any(convex_overlap(hull, self.model.hull_at(other.pose())) for other in self._entities.values()):
                return f"pose ({pose.x:.3f}, {pose.y:.3f}, yaw {pose.yaw:.3f}) overlaps another robot"
        return None

    def _placement_problem(self, pose: Pose) -> str | None:
        """:func:`~thymio_bt.robot.placement.placement_problem` in this maze for this robot, a function
        of the pose alone here: remembered for the last pose asked, bit for bit (the runner checks the
        start, then serving the spawn request checks it again: 0.25 M instructions each)."""
        key = _POSE_BITS(pose.x, pose.y, pose.yaw)  # the floats' bits: 0.0 and -0.0 differ
        asked, problem = self._placed
        if key != asked:
            problem = placement_problem(self._shapes, self.model, pose)
            self._placed = (key, problem)
        return problem

    # ------------------------------------------------------------- stepping
    def advance(self, duration: float) -> None:
        """Run the physics for ``duration`` seconds of simulated time, then serve pending requests."""
        entity = self._entities.get(self.robot_name)
        steps = round(duration / self._dt)
        if self._pending:
            self._pending = False
            delay = min(self._delay_steps, steps)
            self._run_steps(entity, delay)  # the old command still drives (the robot's command delay)
            self._apply_command(entity)
            steps -= delay
        self._run_steps(entity, steps)
        if self._requests:
            self.serve_requests()

    def _run_steps(self, entity: RobotBody | None, steps: int) -> None:
        """``steps`` physics steps with the applied command, refreshing the sensors at their rate."""
        (step, space), dt = self._step, self._dt
        self._pose_now = None  # the robot moves
        if entity is None:
            for _ in range(steps):
                step(space, dt)
                self._steps += 1
            return
        if self._drifts:
            self._integrate_odometry(steps * dt)
        v, w = self._applied
        turning = v != 0.0 and w != 0.0
        every, done, aim = self._sensor_every, self._steps + steps, entity.aim
        while self._steps < done:
            first = self._steps
            refresh = first + every - first % every  # the step count of the next sensor refresh
            last = refresh if refresh < done else done
            # during a step, _steps counts the steps before it (a collision's time)
            for self._steps in range(first, last):
                if turning or self._contacts:
                    aim(v)  # keep the control body's velocity along the heading as it changes
                    if self._contacts:
                        entity.spin(w)
                step(space, dt)
            self._steps = last
            if last == refresh:
                self._refresh_sensors(entity)

    def _apply_command(self, entity: RobotBody | None) -> None:
        """Turn the held command into wheel speeds (limited, optionally noisy) and a body velocity,
        driving ``entity`` (the robot's, None while absent: looked up by the caller)."""
        model, cmd = self.model, self._cmd
        last, wheels = self._wheels_of_command
        linear, angular = cmd
        fresh = last is not cmd and (last is None or linear != last[0] or angular != last[1])
        if fresh:  # the limited wheel speeds are a function of the command: once per command
            wheels = model.limited_wheel_speeds(linear, angular, self._max_wheel)
            self._wheels_of_command = (cmd, wheels)
        if fresh or self._noisy_wheels:
            left, right = wheels
            if self._noisy_wheels:  # noisy wheels err anew with every command sent
                fl, fr = self._noise.wheel_factors()
                left, right = left * fl, right * fr
            self._velocity = model.body_velocity(left, right)
        v, w = self._applied = self._velocity
        if entity is not None:
            # Chipmunk moves bodies before solving joints: out of contact, the body's velocity is
            # seeded too, so motion starts now
            entity.drive(v, w, self._contacts == 0)

    def _integrate_odometry(self, duration: float) -> None:
        """Dead-reckon the axle from the wheel speeds as encoders measure them (with a per-call error).

        Encoders count wheel turns, not body motion: a robot whose wheels slip against a wall
        believes it moves, as a real Thymio does. The arc is integrated exactly for the held command.
        """
        applied, wheels = self._wheels_of
        if applied is not self._applied:  # the applied command's wheel speeds, once per command
            wheels = self.model.wheel_speeds(*self._applied)
            self._wheels_of = (self._applied, wheels)
        left, right = wheels
        fl, fr = self._noise.encoder_factors()
        v, w = self.model.body_velocity(left * fl, right * fr)
        self._odo = integrate_arc(*self._odo, v, w, duration)

    def _odometry_pose(self) -> Pose:
        """The pose odometry believes, computed once per dead-reckoning step (asked several times a tick)."""
        odo, pose = self._odo_pose
        if odo is not self._odo or pose is None:
            base = self.model.base_of(*self._odo)
            pose = Pose(base.x, base.y, wrap_angle(base.yaw))
            self._odo_pose = (self._odo, pose)
        return pose

    def _refresh_sensors(self, entity: RobotBody) -> None:
        """The robot's readings and clearance, and its true pose for this step (one read of the body)."""
        bx, by, angle = entity.read()
        self._pose_now = new_pose(bx, by, wrap_angle(angle))  # space.pose_of, a call less a refresh
        cos, sin = math.cos(angle), math.sin(angle)
        if self._cone is not None:
            self._raw = self._cone.measure(self._ray, entity.filter, bx, by, cos, sin)
            self._scan = MappingProxyType(raw_scan_to_metres(self._raw, self.model.calibration))
        elif self._lazy_scan and len(self._entities) == 1:
            # noise-free metres alone in the maze depend on nothing but this pose and the walls: each
            # ray is cast when first read (behaviours read few; a quarter of refreshes are not read),
            # seeing walls only, so a robot spawned before the read stays unseen as it should
            self._scan, self._sensed = None, (bx, by, cos, sin)
        else:  # noise (random streams in a fixed order) or other robots: now
            self._scan = MappingProxyType(self._cast(entity, bx, by, cos, sin))
        record = self.min_clearance
        gap = self._clearance.below(record, entity.near, entity.shape, bx, by, cos, sin)
        if gap < record:
            self.min_clearance = max(gap, 0.0)

    def _cast(self, entity: RobotBody, bx: float, by: float, cos: float, sin: float) -> dict[str, float]:
        """The seven rays' readings of ``entity`` at (bx, by), heading with this cosine and sine."""
        alphas = self._ray.fan(self._rays, bx, by, cos, sin, entity.filter)
        noise, raw, noisy = self._noise, self._raw_model, self._range_noise
        lo, hi, inf = self._range_min, self._range_max, math.inf
        scan: dict[str, float] = {}
        for name, alpha in zip(self._ray_names, alphas, strict=True):
            if alpha is None:
                scan[name] = inf
                continue
            value = alpha * hi
            if value < lo:  # max(value, lo) without a builtin call: 7 a tick
                value = lo
            scan[name] = noise.range(value, lo, hi) if noisy else value
        if raw is not None:
            self._raw = raw.measure_scan(scan)
            scan = raw_scan_to_metres(self._raw, raw.table)
        return scan

    # -------------------------------------------------------------- entities
    def _add_robot(self, name: str, pose: Pose) -> None:
        entity = RobotBody(self.space, pose, group=1 + len(self._entities), model=self.model)
        self._entities[name] = entity
        if name == self.robot_name:
            self._odo = self.model.axle_of(pose)
            self._cmd = (0.0, 0.0)
            self._applied = (0.0, 0.0)
            self._refresh_sensors(entity)

    def _remove(self, name: str) -> str | None:
        entity = self._entities.pop(name, None)
        if entity is None:
            return f"no entity named '{name}' (existing: {', '.join(sorted(self._entities)) or 'none'})"
        entity.remove(self.space)
        if name == self.robot_name:
            self._scan, self._cmd, self._contacts, self._pose_now = None, (0.0, 0.0), 0, None
        return None

    def _place_entity(self, name: str, pose: Pose) -> str | None:
        self._add_robot(name, pose)
        return None

    # ------------------------------------------------------------ collisions
    def _on_begin(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        self._contacts += 1
        if self._contacts == 1:
            points = arbiter.contact_point_set.points
            if points:
                x, y = points[0].point_a
            else:
                body = arbiter.shapes[0].body
                assert body is not None  # a shape in the space has a body
                x, y = body.position
            self.collisions.append(Collision(self.time(), x, y))

    def _on_separate(self, arbiter: pymunk.Arbiter, space: pymunk.Space, data: object) -> None:
        self._contacts = max(0, self._contacts - 1)
