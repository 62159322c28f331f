"""The abstract robot: what behaviours may use, and what a backend must provide.

Behaviours talk to the robot only through these interfaces, so the same mission can drive the
pymunk simulation (:mod:`thymio_bt.backends.sim`), a real Thymio (``aseba``, ``tdm``), the Aseba
Playground or a ROS 2 robot (:mod:`thymio_bt.backends`). Units are metres, seconds and radians;
the pose is the course's ``base_link`` in the world frame (0.0243 m ahead of the wheel axle the
robot turns about).

A behaviour drives and senses through the :class:`Robot` it is given (``robot.drive(0.1, 0.0)``
holds a command like cmd_vel; ``robot.proximity()["front_center"]`` is a range in metres, inf when
nothing is in range); poses and angles are plain values:

Example::

    >>> Pose(0.0, 0.0, 0.0).distance_to(Pose(0.3, 0.4, 0.0))
    0.5
    >>> round(wrap_angle(3 * math.pi / 2), 6)  # a three-quarter turn left is a quarter turn right
    -1.570796
    >>> Backend.latency, Backend.model.name  # what a backend that says nothing of itself is
    (0.0, 'course')
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum

from thymio_bt.errors import ThymioBtError
from thymio_bt.geometry import Pose, new_pose, wrap_angle
from thymio_bt.robot.model import COURSE, SENSOR_NAMES, RobotModel

#: The entity name of the robot, as in the course's spawn service calls.
ROBOT_ENTITY = "thymio"


class RobotLost(ThymioBtError):
    """Raised by a backend whose robot stopped answering: the run ends as FAILURE ``ROBOT_LOST``."""


@dataclass(frozen=True, slots=True)
class Twist:
    """A planar velocity: linear along the robot's heading (m/s), angular (rad/s, left positive)."""

    linear: float = 0.0
    angular: float = 0.0


@dataclass(frozen=True, slots=True)
class Collision:
    """The start of one contact episode between the robot and a wall: when (backend time) and where."""

    t: float
    x: float
    y: float


Scan = Mapping[str, float]
"""Proximity ranges by sensor name, in metres; ``math.inf`` when nothing is in range. Treat it as
read-only (the simulation's is: it casts each ray when first read); ``dict(scan)`` is a copy to keep
or change."""


class Robot(ABC):
    """A differential-drive robot with 7 proximity sensors and odometry."""

    #: what the robot is (sensor poses, geometry, speed limits): behaviours that depend on where its
    #: sensors look read it here. A backend that does not set it drives the course's robot
    model: RobotModel = COURSE
    #: seconds from the world a reading shows to the moment a command sent now takes effect
    #: (sensing, transport, motors): behaviours that stop on a reading or an angle lead by it.
    #: 0 for the simulation, whose behaviours see the world of this tick.
    latency: float = 0.0
    #: whether :meth:`proximity_raw` can give a real Thymio's integer readings (a real robot, a
    #: simulation of them): what a calibration samples
    raw_readings: bool = False

    @abstractmethod
    def drive(self, linear: float, angular: float) -> None:
        """Command a velocity; it is held until the next command (no timeout, like cmd_vel)."""

    @abstractmethod
    def exists(self) -> bool:
        """Whether the robot entity currently exists (it does not between delete and spawn)."""

    @abstractmethod
    def proximity(self) -> Scan | None:
        """The latest proximity scan (refreshed at 10 Hz), or None while the robot does not exist."""

    def proximity_raw(self) -> dict[str, int] | None:
        """The latest readings as a real Thymio's integers, by sensor name; None while the robot does
        not exist, or from a robot without them (``raw_readings`` false)."""
        return None

    @abstractmethod
    def pose(self) -> Pose | None:
        """The odometry pose of base_link, or None while the robot does not exist."""

    @abstractmethod
    def velocity(self) -> Twist:
        """The measured velocity (zero while the robot does not exist)."""

    @abstractmethod
    def command(self) -> Twist:
        """The drive command currently held."""

    @abstractmethod
    def time(self) -> float:
        """The backend's clock in seconds (simulated time in the simulator)."""


class RequestState(Enum):
    """Where an entity :class:`Request` stands: waiting, or done one way or the other."""

    PENDING = "pending"
    SUCCEEDED = "succeeded"
    FAILED = "failed"


@dataclass(slots=True)
class Request:
    """An asynchronous entity request (like a ROS service call): poll ``state`` every tick."""

    kind: str
    entity: str
    pose: Pose | None = None
    state: RequestState = RequestState.PENDING
    reason: str | None = None

    @property
    def done(self) -> bool:
        """Whether the request is served (SUCCEEDED or FAILED)."""
        return self.state is not RequestState.PENDING


class Entities(ABC):
    """Delete and spawn entities; requests complete over later ticks with success or a reason."""

    @abstractmethod
    def request_delete(self, name: str) -> Request:
        """Ask to remove an entity; refused (FAILED) when no entity has that name."""

    @abstractmethod
    def request_spawn(self, name: str, pose: Pose) -> Request:
        """Ask for a fresh robot at ``pose``; refused when the name is taken or the pose is not free."""


class Backend(Robot, Entities):
    """A robot and its world as the runner drives them: the pymunk simulation or a real Thymio.

    Besides :class:`Robot` and :class:`Entities`, the runner needs to let time pass between ticks
    (instantly in a simulation, by waiting on a real robot), a best-known pose for the report, and
    what the backend knows of contacts with walls (a real Thymio has no bumper: nothing).

    The base queues entity requests and serves them (:meth:`serve_requests`, from :meth:`advance`):
    a backend only says how to remove and place a robot (:meth:`_remove`, :meth:`_place_entity`),
    and keeps ``collisions`` and ``min_clearance`` up to date where it can measure them.
    """

    #: the entity name of the robot
    robot_name: str = ROBOT_ENTITY
    #: contact episodes so far, oldest first
    collisions: list[Collision]
    #: the smallest hull-to-wall gap so far in metres (inf when unknown)
    min_clearance: float = math.inf
    #: entity requests not yet served; :meth:`serve_requests` serves them
    _requests: list[Request]

    def __init__(self) -> None:
        self._requests = []
        self.collisions = []
        self.min_clearance = math.inf

    def request_delete(self, name: str) -> Request:
        """Queue a delete request; :meth:`serve_requests` serves it (through :meth:`_remove`)."""
        request = Request("delete", name)
        self._requests.append(request)
        return request

    def request_spawn(self, name: str, pose: Pose) -> Request:
        """Queue a spawn request; :meth:`serve_requests` checks and serves it (:meth:`_place_entity`)."""
        request = Request("spawn", name, pose)
        self._requests.append(request)
        return request

    def serve_requests(self) -> None:
        """Complete the queued requests in order, each SUCCEEDED or FAILED with a reason."""
        if not self._requests:  # the common case, every tick
            return
        pending, self._requests = self._requests, []
        for request in pending:
            if request.kind == "delete":
                problem = self._remove(request.entity)
            else:
                assert request.pose is not None
                problem = self.spawn_problem(request.entity, request.pose) or self._place_entity(
                    request.entity, request.pose
                )
            request.reason = problem
            request.state = RequestState.FAILED if problem else RequestState.SUCCEEDED

    def _remove(self, name: str) -> str | None:
        """Remove entity ``name``; why it cannot be (e.g. no such entity), or None when done.
        Every backend that keeps :meth:`serve_requests` must define it (one whose requests take
        several ticks, like ROS 2 service calls, overrides :meth:`serve_requests` instead)."""
        raise NotImplementedError(f"{type(self).__name__} serves requests without defining _remove")

    def _place_entity(self, name: str, pose: Pose) -> str | None:
        """Put a fresh robot ``name`` at ``pose`` (already checked by :meth:`spawn_problem`); why
        it could not be (e.g. an operator refused), or None when done. See :meth:`_remove`."""
        raise NotImplementedError(f"{type(self).__name__} serves requests without defining _place_entity")

    @abstractmethod
    def advance(self, duration: float) -> None:
        """Let ``duration`` seconds of backend time pass, then serve pending entity requests."""

    @abstractmethod
    def true_pose(self) -> Pose | None:
        """The robot's real pose where the backend knows it (a simulator), else its best estimate."""

    @abstractmethod
    def spawn_problem(self, name: str, pose: Pose) -> str | None:
        """Why ``name`` cannot be spawned at ``pose`` now, or None when it can."""

    def close(self) -> None:
        """Release the robot (stop its motors); called however a run ends. Nothing to do by default."""


__all__ = [
    "ROBOT_ENTITY",
    "SENSOR_NAMES",
    "Backend",
    "Collision",
    "Entities",
    "Pose",
    "Request",
    "RequestState",
    "Robot",
    "RobotLost",
    "Scan",
    "Twist",
    "new_pose",
    "wrap_angle",
]
