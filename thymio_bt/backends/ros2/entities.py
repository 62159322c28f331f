"""The entity requests of ``--backend ros2`` (DeleteEntity, SpawnEntity): Gazebo's services called
over later ticks, the robot already in the world adopted when it stands at the start.

A mixin of :class:`~thymio_bt.backends.ros2.backend.Ros2Robot`, which holds the state it names; each
request is a generator moved on once a tick (:meth:`EntitySteps._pump`).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Generator
from typing import Any

from thymio_bt.backends.ros2.messages import Odometry, set_pose
from thymio_bt.backends.ros2.services import call_service, fail
from thymio_bt.backends.ros2.topics import TopicMap
from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze
from thymio_bt.robot.interface import Backend, Request, RequestState, Twist
from thymio_bt.robot.model import RobotModel
from thymio_bt.robot.placement import placement_problem

#: the robot in the world is the mission's start when it is this close (m, rad)
ADOPT_DISTANCE, ADOPT_ANGLE = 0.02, math.radians(3.0)
#: how often (wall s) a waiting tick looks again when no message wakes it
POLL = 0.05

_Step = Generator[None, None, None]


class EntitySteps(Backend):
    """Spawning and deleting the robot through ROS 2 services, over ticks (the module docstring)."""

    topics: TopicMap
    maze: Maze
    model: RobotModel
    timeout: float
    robot_name: str
    _node: Any
    _cond: threading.Condition
    _present: bool
    _first_spawn: bool
    _cmd: Twist
    _steps: list[tuple[Request, _Step]]
    _spawn_client: Any
    _delete_client: Any
    _xml: str | None
    _odom: Odometry | None
    _odom_wall: float
    _odom_count: int
    _ranges: dict[str, tuple[int, float]]

    def _stop_motors(self) -> None:
        raise NotImplementedError

    def spawn_problem(self, name: str, pose: Pose) -> str | None:
        """Why the robot cannot be spawned at ``pose``: one robot, once, at finite numbers, clear of walls."""
        if name != self.robot_name:
            return f"this backend drives one robot, '{self.robot_name}', not '{name}'"
        if self._present:
            return f"an entity named '{name}' already exists: delete it first"
        if not all(math.isfinite(v) for v in pose.as_tuple()):
            return "the pose must be finite numbers"
        return placement_problem(self.maze, self.model, pose) if self.maze.walls or self.maze.obstacles else None

    def serve_requests(self) -> None:
        """Start the queued requests; they move on at every tick (:meth:`_pump`)."""
        pending, self._requests = self._requests, []
        for request in pending:
            steps = self._delete(request) if request.kind == "delete" else self._spawn(request)
            self._steps.append((request, steps))

    def _pump(self) -> None:
        """Move the requests on, one at a time and in order (a spawn asked after a delete waits)."""
        self.serve_requests()
        while self._steps:
            request, steps = self._steps[0]
            try:
                next(steps)
                return
            except StopIteration:
                self._steps.pop(0)

    def _finish_requests(self) -> None:
        self._pump()
        while self._steps:
            with self._cond:
                self._cond.wait(POLL)
            self._pump()

    def _call_delete(self, request: Request) -> Generator[None, None, Any]:
        """Gazebo's DeleteEntity of ``request``'s entity, over later ticks (see :func:`call_service`)."""
        from gazebo_msgs.srv import DeleteEntity

        message = DeleteEntity.Request(name=request.entity)
        return (yield from call_service(self._delete_client, self.topics.delete, message, request, self.timeout))

    def _delete(self, request: Request) -> _Step:
        if request.entity != self.robot_name or not self._present:
            fail(
                request,
                f"no entity named '{request.entity}' (existing: {self.robot_name if self._present else 'none'})",
            )
            return
        self._stop_motors()
        if (yield from self._call_delete(request)) is None:
            return
        self._present, self._cmd = False, Twist()
        request.state = RequestState.SUCCEEDED

    def _spawn(self, request: Request) -> _Step:
        from gazebo_msgs.srv import SpawnEntity

        assert request.pose is not None
        seen = (yield from self._robot_in_world()) if self._first_spawn else None
        self._first_spawn = False
        if (
            seen is not None
            and seen.distance_to(request.pose) <= ADOPT_DISTANCE
            # not wrap_angle: math.remainder is exact where wrap_angle rounds (kept: the same bits as before)
            and abs(math.remainder(seen.yaw - request.pose.yaw, math.tau)) <= ADOPT_ANGLE
        ):
            self._present = True  # the robot already stands there: adopt it
            request.state = RequestState.SUCCEEDED
            return
        # elsewhere: take it away first, as the course does
        if seen is not None and (yield from self._call_delete(request)) is None:
            return
        message = SpawnEntity.Request(name=request.entity, xml=self._xml or "", reference_frame="world")
        set_pose(message.initial_pose, request.pose)
        count = self._odom_count
        if (yield from call_service(self._spawn_client, self.topics.spawn, message, request, self.timeout)) is None:
            return
        with self._cond:
            self._ranges.clear()  # readings from before: the new robot's come next
        deadline = time.monotonic() + self.timeout
        while (
            self._odom_count == count
            or not self._odom_after_spawn(request.pose)
            or len(self._ranges) < len(self.topics.sensors)
        ):
            if time.monotonic() > deadline:
                silent = (
                    [self.topics.odom]
                    if self._odom_count == count
                    else [t for n, t in self.topics.sensors.items() if n not in self._ranges]
                )
                fail(request, f"spawned, but no message on {', '.join(silent)} within {self.timeout:g} s")
                return
            yield
        self._present, self._cmd = True, Twist()
        request.state = RequestState.SUCCEEDED

    def _odom_after_spawn(self, pose: Pose) -> bool:
        """Whether the latest odometry is the new robot's (within a few cm of where it was put)."""
        odom = self._odom
        return odom is not None and math.hypot(odom[1] - pose.x, odom[2] - pose.y) < 0.05

    def _robot_in_world(self) -> Generator[None, None, Pose | None]:
        """Where the robot already in the world is (from /odom), or None when none publishes."""
        if self._odom is None:
            deadline = time.monotonic() + min(self.timeout, 2.0)
            while (
                self._odom is None
                and (time.monotonic() < deadline or self._node.count_publishers(self.topics.odom))
                and time.monotonic() < deadline + self.timeout
            ):
                yield
        odom = self._odom
        if odom is None or time.monotonic() - self._odom_wall > 1.0:
            return None
        return Pose(odom[1], odom[2], odom[3])
