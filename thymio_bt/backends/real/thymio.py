"""A real Thymio II (or Thymio Suite's simulated one) behind the :class:`Robot` and :class:`Entities`
interfaces, so a mission written for the simulator drives it unchanged.

The robot is reached through a small :class:`AsebaDevice` protocol: motor targets, ``prox.horizontal`` and
the measured wheel speeds. :class:`TdmDevice` implements it with tdmclient (the Thymio Device Manager
of Thymio Suite, optional extra ``thymio-bt[thymio]``); tests use a fake device.

What the backend does with them:

- ``drive(v, ω)``: wheel speeds as the diff-drive plugin computes them, both scaled down together
  when one exceeds the limit (the turn radius is kept), converted to motor units and written at once;
- ``proximity()``: the 7 readings converted to metres through :mod:`thymio_bt.sensor_tables`
  (0, nothing seen, is ``math.inf``), refreshed at every :meth:`ThymioRobot.advance`;
- ``pose()``: odometry, integrated from the measured wheel speeds (``motor.*.speed``) at every
  :meth:`ThymioRobot.advance`; it drifts, and there is no ground truth;
- ``time()``: wall-clock seconds since the backend started, minus the time spent waiting for the
  operator. :meth:`ThymioRobot.advance` is the only place that really waits: until ``duration``
  after the previous tick's deadline, so the runner's 10 Hz tick is paced by the robot's clock;
- delete and spawn: there is nobody to lift the robot, so delete stops the motors and marks the robot
  absent, and spawn asks the operator to place it at the pose, then resets odometry to that pose;
- no collision detection (``collisions`` stays empty) and no clearance (``min_clearance`` is inf).

With Thymio Suite running and a robot connected::

    with ThymioRobot.connect() as robot:
        robot.request_spawn("thymio", Pose(0.1, 0.1, 0.0))
        robot.advance(0.0)                       # prompts: place the robot, press Enter
        robot.drive(0.1, 0.0)
        for _ in range(10):
            robot.advance(0.1)                   # 1 s later: about 0.1 m further

Example (a device that stands still, 5 cm from a wall, and a clock that never moves)::

    >>> class Still(AsebaDevice):
    ...     def set_motors(self, left, right): self.sent = (left, right)
    ...     def read_prox(self): return [0, 0, 2570, 0, 0, 0, 0]
    ...     def read_wheel_speeds(self): return 0, 0
    >>> device = Still()
    >>> robot = ThymioRobot(device, spawn=Pose(0.1, 0.1, 0.0), clock=lambda: 0.0, sleep=lambda s: None)
    >>> robot.drive(0.1, 0.0)
    >>> device.sent, robot.proximity()["front_center"], robot.proximity()["front_left"]   # units; metres
    ((250, 250), 0.05, inf)
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import TYPE_CHECKING, Any

from thymio_bt.errors import Problem, UserError, optional_module
from thymio_bt.geometry import Pose, wrap_angle
from thymio_bt.robot.interface import ROBOT_ENTITY, SENSOR_NAMES, Backend, Scan, Twist
from thymio_bt.robot.model import REAL, RobotModel, integrate_arc

if TYPE_CHECKING:
    from thymio_bt.backends import MissionWorld
    from thymio_bt.backends.real.options import TdmOptions

#: ``prox.horizontal`` index of each sensor: 0-4 front from left to right, 5 rear left, 6 rear right
#: (Mobsya's Thymio API doc, thymio-api.rst L35-41), the same order as :data:`SENSOR_NAMES`.
PROX_INDEX: dict[str, int] = {name: i for i, name in enumerate(SENSOR_NAMES)}

#: The variables the backend reads and writes.
PROX_VARIABLE = "prox.horizontal"
SPEED_VARIABLES = ("motor.left.speed", "motor.right.speed")
TARGET_VARIABLES = ("motor.left.target", "motor.right.target")

_INSTALL_HINT = "pip install 'thymio-bt[thymio]'"


class AsebaDevice(ABC):
    """A Thymio as an Aseba device: the few variables of it the backend uses, in Thymio units."""

    @abstractmethod
    def set_motors(self, left: int, right: int) -> None:
        """Write ``motor.left.target`` and ``motor.right.target`` (units, ±500) and send them now."""

    @abstractmethod
    def read_prox(self) -> list[int]:
        """The latest ``prox.horizontal``: 7 readings, in :data:`PROX_INDEX` order."""

    @abstractmethod
    def read_wheel_speeds(self) -> tuple[int, int]:
        """The latest measured ``motor.left.speed`` and ``motor.right.speed`` (units)."""

    def read_wheel_travel(self) -> tuple[float, float] | None:
        """How far each wheel has turned since the device connected (units x s), integrated at every
        set of variables the robot sent; None for a device that only has the latest speeds (the
        backend then integrates those at its ticks)."""
        return None

    def close(self) -> None:  # noqa: B027 (an optional hook: a device that holds nothing has nothing to do)
        """Release the robot (the default device holds nothing)."""


@dataclass(frozen=True, slots=True)
class TdmAddress:
    """The Thymio Device Manager to reach (None: the local one), its robot to take (None: the first), the wait (s)."""

    tdm_addr: str | None = None
    tdm_port: int | None = None
    password: str | None = None
    robot_name: str | None = None
    timeout: float = 10.0


#: the Thymio Device Manager of this machine and its first robot
LOCAL_TDM = TdmAddress()


def import_tdmclient() -> ModuleType:
    """tdmclient, imported on first use so that the package works without the optional extra."""
    return optional_module("tdmclient", "the 'tdm' backend", _INSTALL_HINT)


class TdmDevice(AsebaDevice):
    """A robot reached through the Thymio Device Manager with tdmclient's cached variables.

    Reads come from the node's variable cache, which the TDM refreshes about every 100 ms while we
    watch it (so at most ~10 Hz); writes go to the cache and :meth:`flush` sends them. ``client`` is
    a ``tdmclient.ClientAsync`` and ``node`` a locked ``ClientAsyncCacheNode`` holding the variables
    (:meth:`connect` makes both).
    """

    def __init__(self, client: Any, node: Any) -> None:
        self.client = client
        self.node = node

    @classmethod
    def connect(cls, address: TdmAddress = LOCAL_TDM) -> TdmDevice:
        """Connect to the TDM at ``address``, lock its robot and wait for the variables. Raises
        :class:`UserError` with a hint when any of it is impossible."""
        tdmclient = import_tdmclient()
        robot_name = address.robot_name
        try:
            client = tdmclient.ClientAsync(
                tdm_addr=address.tdm_addr, tdm_port=address.tdm_port, password=address.password
            )
        except OSError as exc:
            where = f"{address.tdm_addr or '127.0.0.1'}:{address.tdm_port or 8596}"
            raise UserError(
                Problem(
                    f"cannot reach the Thymio Device Manager at {where}: {exc}",
                    hint="start Thymio Suite (it runs the device manager), or pass its address",
                )
            ) from None
        found = tdmclient.aw(client.wait_for_node(timeout=address.timeout, node_name=robot_name))
        if found is None:
            client.disconnect()
            which = f"named '{robot_name}' " if robot_name else ""
            raise UserError(
                Problem(
                    f"no Thymio {which}appeared within {address.timeout:g} s",
                    hint="switch the robot on and plug it (or its dongle) in, or start a "
                    "simulated robot from Thymio Suite's Playground",
                )
            )
        try:
            node = tdmclient.aw(client.lock(node_name=robot_name))
        except tdmclient.NodeLockError as exc:
            client.disconnect()
            raise UserError(
                Problem(
                    f"cannot take control of the robot: {exc}",
                    hint="close the other program using it (a Thymio Suite editor?)",
                )
            ) from None
        tdmclient.aw(node.wait_for_variables({PROX_VARIABLE, *SPEED_VARIABLES, *TARGET_VARIABLES}))
        return cls(client, node)

    def set_motors(self, left: int, right: int) -> None:
        """Write both motor targets to the node's cache and send them."""
        self.node[TARGET_VARIABLES[0]] = int(left)
        self.node[TARGET_VARIABLES[1]] = int(right)
        self.node.flush()

    def read_prox(self) -> list[int]:
        """The TDM's latest ``prox.horizontal`` (its waiting messages processed first)."""
        self.client.process_waiting_messages()
        values = self.node[PROX_VARIABLE]
        return [int(values[i]) for i in range(len(SENSOR_NAMES))]

    def read_wheel_speeds(self) -> tuple[int, int]:
        """The TDM's latest measured wheel speeds (its waiting messages processed first)."""
        self.client.process_waiting_messages()
        return int(self.node[SPEED_VARIABLES[0]]), int(self.node[SPEED_VARIABLES[1]])

    def close(self) -> None:
        """Stop the motors, unlock the robot and disconnect from the TDM."""
        self.set_motors(0, 0)
        self.node.send_unlock_node(ignore_disconnected_error=True)
        self.client.disconnect()


class ThymioRobot(Backend):
    """A real Thymio as a thymio-bt backend (see the module docstring for what differs).

    ``clock`` and ``sleep`` (wall-clock seconds, and waiting) and ``ask`` and ``say`` (the operator's
    console) are injectable so tests run without waiting or typing. ``spawn`` starts with the robot
    present at that pose; without it, the robot is absent until a spawn request is served.
    ``model`` is what the robot is (:data:`~thymio_bt.robot.model.REAL` unless told): its motor units,
    speed limit, wheel separation and calibration table drive the robot, and behaviours read its
    sensor poses and geometry as ``robot.model``. ``speed_scale``: the distance the robot's wheels
    cover per motor unit over the model's (the Playground's Thymio: 0.985 of Enki's).
    ``placed``: the robot already stands where the first spawn puts it (no operator is asked then).
    """

    raw_readings = True  # prox.horizontal's integers, as the robot reports them

    def __init__(
        self,
        device: AsebaDevice,
        spawn: Pose | None = None,
        robot_name: str = ROBOT_ENTITY,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        ask: Callable[[str], str] = input,
        say: Callable[[str], None] = print,
        model: RobotModel = REAL,
        speed_scale: float = 1.0,
        placed: bool = False,
    ) -> None:
        super().__init__()
        self.device = device
        self.model = model
        self.speed_scale = speed_scale
        self._placed = placed  # the first spawn needs nobody: the robot stands there already
        self._spawned = False  # whether a spawn has placed the robot (the next ones move it mid-run)
        self.robot_name = robot_name
        self._clock, self._sleep, self._ask, self._say = clock, sleep, ask, say
        self._start = clock()
        self._paused = 0.0  # seconds spent waiting for the operator
        self._deadline = 0.0  # backend time the current tick ends at
        self._present = False
        self._closed = False
        self._cmd = Twist()
        self._raw: dict[str, int] | None = None
        self._scan: dict[str, float] | None = None
        self._wheels = (0.0, 0.0)  # latest measured wheel speeds, m/s
        self._travel: tuple[float, float] | None = None  # the device's wheel travel at the last reading
        self._read_at = 0.0  # backend time of that measurement
        self._axle = (0.0, 0.0, 0.0)  # odometry of the axle centre: x, y, yaw
        # no bumper: collisions stay empty (COLLISION never fires); no ground truth: min_clearance stays inf
        device.set_motors(0, 0)
        if spawn is not None:
            self._place(spawn)

    @classmethod
    def connect(cls, address: TdmAddress = LOCAL_TDM, **kwargs: Any) -> ThymioRobot:
        """A backend over the first robot the local (or given) Thymio Device Manager knows;
        ``kwargs`` go to the constructor."""
        return cls(TdmDevice.connect(address), **kwargs)

    def __enter__(self) -> ThymioRobot:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop the motors and release the robot; call it however the run ends (again: no effect)."""
        if self._closed:
            return
        self._closed = True
        self.device.set_motors(0, 0)
        self.device.close()

    # ----------------------------------------------------------------- Robot
    def drive(self, linear: float, angular: float) -> None:
        """Hold the body velocity: the motor targets are sent now (nothing while the robot is absent)."""
        if not self._present:
            return
        self._cmd = Twist(float(linear), float(angular))
        self.device.set_motors(*self.motor_targets(self._cmd.linear, self._cmd.angular))

    def motor_targets(self, linear: float, angular: float) -> tuple[int, int]:
        """Motor units for a body velocity: limited as in the simulator (turn radius kept), rounded."""
        return self.model.motor_targets(linear, angular, self.speed_scale)

    def exists(self) -> bool:
        """Whether the robot is present (placed and not deleted)."""
        return self._present

    def proximity(self) -> Scan | None:
        """The last tick's readings in metres, through the calibration table; None while absent."""
        return self._scan if self._present else None

    def proximity_raw(self) -> dict[str, int] | None:
        """The latest readings as the robot reported them, by sensor name."""
        return self._raw if self._present else None

    def pose(self) -> Pose | None:
        """Odometry's base_link pose (it drifts: there is no ground truth); None while absent."""
        base = self.model.base_of(*self._axle) if self._present else None
        return None if base is None else Pose(base.x, base.y, wrap_angle(base.yaw))

    def true_pose(self) -> Pose | None:
        """There is no ground truth on a real robot: the odometry pose, the best estimate there is."""
        return self.pose()

    def velocity(self) -> Twist:
        """The measured wheel speeds as a body velocity (zero while absent)."""
        if not self._present:
            return Twist()
        return Twist(*self.model.body_velocity(*self._wheels))

    def command(self) -> Twist:
        """The held command."""
        return self._cmd

    def time(self) -> float:
        """Wall-clock seconds since the backend started, less the time spent waiting for the operator."""
        return self._clock() - self._start - self._paused

    # -------------------------------------------------------------- Entities
    def spawn_problem(self, name: str, pose: Pose) -> str | None:
        """Why the robot cannot be spawned at ``pose`` (None when it can; walls are the operator's job)."""
        if name != self.robot_name:
            return f"a real robot backend has one entity, '{self.robot_name}', not '{name}'"
        if self._present:
            return f"an entity named '{name}' already exists: delete it first"
        if not all(math.isfinite(v) for v in (pose.x, pose.y, pose.yaw)):
            return "the pose must be finite numbers"
        return None

    # ------------------------------------------------------------- stepping
    def advance(self, duration: float) -> None:
        """Wait until ``duration`` seconds after the previous tick's deadline (no waiting when late:
        the next tick is then timed from now), read the robot, and serve pending requests."""
        self._deadline = max(self._deadline + duration, self.time())
        lag = self._deadline - self.time()
        if lag > 0.0:
            self._sleep(lag)
        if self._present:
            self._read()
        self.serve_requests()

    def _read(self) -> None:
        """Integrate odometry since the last reading, then take the proximity readings.

        Wheel speeds are samples, so each interval moves at the mean of its two end samples (the
        trapezoid rule), along the exact arc for that constant speed pair."""
        previous = self._wheels
        now = self._read_wheels()
        travel = self.device.read_wheel_travel()
        if travel is not None and self._travel is not None:  # the device's own, finer integral
            self._integrate(self._speed(travel[0] - self._travel[0]), self._speed(travel[1] - self._travel[1]), 1.0)
        else:
            left, right = (previous[0] + self._wheels[0]) / 2.0, (previous[1] + self._wheels[1]) / 2.0
            self._integrate(left, right, now - self._read_at)
        self._travel = travel
        self._read_at = now
        self._read_prox()

    def _read_wheels(self) -> float:
        """Take the measured wheel speeds (m/s) and return the backend time they were read at."""
        left_u, right_u = self.device.read_wheel_speeds()
        self._wheels = (self._speed(left_u), self._speed(right_u))
        return self.time()

    def _speed(self, units: float) -> float:
        """The wheel speed (m/s) of ``units`` motor units on this robot."""
        return self.model.wheel_speed_of(units, self.speed_scale)

    def _read_prox(self) -> None:
        values = self.device.read_prox()
        if len(values) != len(SENSOR_NAMES):
            raise ValueError(f"prox.horizontal has {len(values)} values, a Thymio II has {len(SENSOR_NAMES)}")
        self._raw = {name: int(values[i]) for name, i in PROX_INDEX.items()}
        self._scan = {name: self.model.calibration.to_metres(value) for name, value in self._raw.items()}

    def _integrate(self, left: float, right: float, duration: float) -> None:
        self._axle = integrate_arc(*self._axle, *self.model.body_velocity(left, right), duration)

    def _place(self, pose: Pose) -> None:
        """The robot now stands at ``pose``: reset odometry and the command, take fresh readings."""
        self._axle = self.model.axle_of(pose)
        self._cmd = Twist()
        self._present = True
        self._read_at = self._read_wheels()
        self._travel = self.device.read_wheel_travel()
        self._read_prox()

    def _remove(self, name: str) -> str | None:
        if name != self.robot_name or not self._present:
            return f"no entity named '{name}' (existing: {self.robot_name if self._present else 'none'})"
        self.device.set_motors(0, 0)
        self._present, self._cmd = False, Twist()
        self._say(f"[thymio-bt] '{name}' deleted: motors stopped, the robot may stay where it is")
        return None

    def _place_entity(self, name: str, pose: Pose) -> str | None:
        if self._placed:  # the operator said so before the run (--backend-opt placed=true)
            self._placed = False
            problem = None
        else:
            problem = self._operator_places(pose)
        if problem is None:
            self._place(pose)
            self._spawned = True
        return problem

    def _operator_places(self, pose: Pose) -> str | None:
        """Ask the operator to put the robot at ``pose``; the clock is paused while they do."""
        prompt = (
            f"[thymio-bt] place the Thymio with base_link (2.4 cm ahead of the wheel axle) at "
            f"x={pose.x:.3f} m, y={pose.y:.3f} m, facing {math.degrees(pose.yaw):.0f} deg, "
            f"then press Enter (or type 'q' to refuse): "
        )
        asked = self._clock()
        try:
            answer = self._ask(prompt)
        except EOFError:
            answer = None
        finally:
            self._paused += self._clock() - asked
        if answer is None:
            if self._spawned:
                return (
                    "no operator to place the robot (standard input is closed): a spawn during the run "
                    "moves the robot, which needs someone at the keyboard"
                )
            return (
                "no operator to place the robot (standard input is closed); for a run with nobody at "
                "the keyboard, stand the robot at the start first and pass --backend-opt placed=true"
            )
        if answer.strip().lower() in ("q", "quit", "n", "no"):
            return "the operator refused to place the robot"
        return None


def create_tdm(mission: MissionWorld, seed: int, options: TdmOptions) -> ThymioRobot:
    """The ``tdm`` backend kind: the first Thymio of a Thymio Device Manager, with the mission's
    robot model (``real`` unless it names another than the course's)."""
    from thymio_bt.backends import robot_for

    model = robot_for(mission, "tdm")
    return ThymioRobot.connect(
        TdmAddress(options.host, options.port, options.password),
        model=model,
        placed=options.placed,
    )
