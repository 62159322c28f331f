"""``--backend ros2``: a mission driving a Thymio through ROS 2 (the course's Gazebo by default).

The robot is its topics (:class:`~thymio_bt.backends.ros2.topics.TopicMap`): the command goes out on
``/cmd_vel`` (again at every tick: a driver with a command timeout keeps moving), the pose and
velocity come from ``/odom``, the proximity readings from one topic per sensor, and SpawnEntity and
DeleteEntity call Gazebo's services, completing over later ticks like the simulator's requests.

Time: when someone publishes ``/clock`` the run lives in that simulated time, and each 10 Hz tick
waits until the clock reaches it and the sensors have published their reading of that moment (the
ticks are laid on the sensors' own 10 Hz grid, so a tick reads what was sensed at its time);
otherwise the run is paced by the wall clock, as on a real robot.

The robot already in the world is adopted when it stands at the mission's start (within 2 cm and
3 degrees), else deleted and spawned there. A topic that stays silent for ``timeout`` seconds ends
the run as FAILURE ``ROBOT_LOST`` naming it; a service missing or refusing fails the behaviour that
asked, with the service's reason. The motors are stopped however the run ends.

From the shell, with ROS 2 (``scripts/ros2-env.sh``)::

    thymio-bt serve ros2 &                                   # or the course's Gazebo launch
    thymio-bt run missions/maze_part1_2.yaml --backend ros2
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable, Generator
from typing import TYPE_CHECKING, Any

from thymio_bt.backends.ros2 import import_rclpy
from thymio_bt.backends.ros2.messages import odometry_of, reading_of, set_pose, stamp_ns
from thymio_bt.backends.ros2.node import SpunNode
from thymio_bt.backends.ros2.services import call_service, fail
from thymio_bt.backends.ros2.topics import TopicMap
from thymio_bt.maze import Maze
from thymio_bt.robot.interface import (
    ROBOT_ENTITY,
    SENSOR_NAMES,
    Backend,
    Pose,
    Request,
    RequestState,
    RobotLost,
    Scan,
    Twist,
)
from thymio_bt.robot.model import RobotModel, robot_model
from thymio_bt.robot.placement import ContactTracker, placement_problem

if TYPE_CHECKING:
    from thymio_bt.backends import Ros2Options
    from thymio_bt.mission import Mission

#: the robot in the world is the mission's start when it is this close (m, rad)
ADOPT_DISTANCE, ADOPT_ANGLE = 0.02, math.radians(3.0)
#: how often (wall s) a waiting tick looks again when no message wakes it
POLL = 0.05

_Step = Generator[None, None, None]


class Ros2Robot(Backend):
    """A Thymio behind ROS 2 topics and services (see the module docstring)."""

    def __init__(
        self,
        topics: TopicMap,
        maze: Maze,
        model: RobotModel,
        timeout: float = 5.0,
        latency: float = 0.0,
        clock: str = "auto",
        robot_xml: str | None = None,
        node_name: str = "thymio_bt",
    ) -> None:
        super().__init__()
        import_rclpy()  # first: without ROS, a UserError that says how to get it
        from geometry_msgs.msg import Twist as TwistMsg
        from nav_msgs.msg import Odometry
        from rclpy.qos import QoSDurabilityPolicy, QoSProfile, qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from std_msgs.msg import String

        self.topics, self.maze, self.model = topics, maze, model
        self.timeout, self.latency, self.robot_name = timeout, latency, ROBOT_ENTITY
        self._TwistMsg = TwistMsg
        self._ros = SpunNode(node_name)
        self._node = self._ros.node
        self._cond = threading.Condition()
        self._clock_ns: int | None = None  # latest /clock
        self._clock_wall = 0.0  # wall time it came
        self._odom: tuple[int, float, float, float, float, float] | None = None  # stamp, x, y, yaw, v, w
        self._odom_wall = 0.0
        self._odom_count = 0
        self._ranges: dict[str, tuple[int, float]] = {}  # sensor -> (stamp, metres)
        self._sensor_wall: dict[str, float] = {}
        self._xml = robot_xml
        self._present = False
        self._first_spawn = True  # the first spawn may adopt the robot in the world
        self._cmd = Twist()
        self._steps: list[tuple[Request, _Step]] = []
        self._closed = False
        self._contacts = ContactTracker(maze, model)
        node = self._node
        node.create_subscription(Clock, topics.clock, self._on_clock, qos_profile_sensor_data)
        node.create_subscription(Odometry, topics.odom, self._on_odom, qos_profile_sensor_data)
        if topics.sensor_type == "LaserScan":
            from sensor_msgs.msg import LaserScan as SensorMsg
        else:
            from sensor_msgs.msg import Range as SensorMsg
        for name, topic in topics.sensors.items():
            node.create_subscription(SensorMsg, topic, self._on_sensor(name), qos_profile_sensor_data)
        if robot_xml is None and topics.robot_description:
            latched = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
            node.create_subscription(String, topics.robot_description, self._on_description, latched)
        self._cmd_pub = node.create_publisher(TwistMsg, topics.cmd_vel, 10)
        from gazebo_msgs.srv import DeleteEntity, SpawnEntity

        self._spawn_client = node.create_client(SpawnEntity, topics.spawn) if topics.spawn else None
        self._delete_client = node.create_client(DeleteEntity, topics.delete) if topics.delete else None
        self._ros.start("thymio-bt-ros2")
        self._wall_start = time.monotonic()
        self._sim_time = self._detect_clock(clock)
        self._start_ns = self._deadline_ns = self._now_ns()
        self._started = False

    # ------------------------------------------------------------ callbacks (executor thread)
    def _on_clock(self, msg: Any) -> None:
        with self._cond:
            self._clock_ns = stamp_ns(msg.clock.sec, msg.clock.nanosec)
            self._clock_wall = time.monotonic()
            self._cond.notify_all()

    def _on_odom(self, msg: Any) -> None:
        with self._cond:
            self._odom = odometry_of(msg)
            self._odom_wall = time.monotonic()
            self._odom_count += 1
            self._cond.notify_all()

    def _on_sensor(self, name: str) -> Callable[[Any], None]:
        limit = self.model.range_max

        def store(msg: Any) -> None:
            with self._cond:
                self._ranges[name] = reading_of(msg, self.topics.sensor_type, limit)
                self._sensor_wall[name] = time.monotonic()
                self._cond.notify_all()

        return store

    def _on_description(self, msg: Any) -> None:
        self._xml = msg.data

    # ----------------------------------------------------------------- time
    def _detect_clock(self, mode: str) -> bool:
        """Whether the run lives in /clock time: ``sim``, ``wall``, or ``auto`` (someone publishes it)."""
        if mode != "auto":
            if mode == "sim":
                self._wait_for(
                    lambda: self._clock_ns is not None,
                    self.timeout,
                    f"no message on {self.topics.clock} within {self.timeout:g} s",
                )
            return mode == "sim"
        deadline = time.monotonic() + min(self.timeout, 2.0)
        with self._cond:
            while self._clock_ns is None and time.monotonic() < deadline:
                if self._odom is not None and not self._node.count_publishers(self.topics.clock):
                    break
                self._cond.wait(POLL)
            return self._clock_ns is not None

    def _start(self) -> None:
        """Start the run's time now; in simulated time, at the sensors' next reading (waited for),
        so that every tick finds readings taken at its own time and the first command acts at once."""
        self._start_ns = self._deadline_ns = self._now_ns()
        if self._sim_time and self._present:
            now = self._start_ns
            newer = lambda: any(stamp > now for stamp, _ in self._ranges.values())  # noqa: E731
            self._wait_for(
                newer,
                self.timeout,
                f"no message on {', '.join(self.topics.sensors.values())} within {self.timeout:g} s",
            )
            self._start_ns = self._deadline_ns = max(stamp for stamp, _ in self._ranges.values())
            self._wait_sim_tick()
        self._started = True

    def _now_ns(self) -> int:
        if self._sim_time:
            assert self._clock_ns is not None
            return self._clock_ns
        return int((time.monotonic() - self._wall_start) * 1e9)

    def time(self) -> float:
        """Seconds since the run started, on /clock (simulated time) or the wall clock."""
        return (self._now_ns() - self._start_ns) / 1e9

    def _wait_for(self, ready: Callable[[], bool], seconds: float, lost: str) -> None:
        """Wait (wall clock) until ``ready()``; :class:`RobotLost` saying ``lost`` after ``seconds``."""
        deadline = time.monotonic() + seconds
        with self._cond:
            while not ready():
                left = deadline - time.monotonic()
                if left <= 0:
                    raise RobotLost(lost)
                self._cond.wait(min(left, POLL))

    # ------------------------------------------------------------- Robot
    def drive(self, linear: float, angular: float) -> None:
        """Hold the command and publish it now (again at every tick); nothing while the robot is absent."""
        if not self._present:
            return
        self._cmd = Twist(float(linear), float(angular))
        self._publish_command()

    def _publish_command(self) -> None:
        msg = self._TwistMsg()
        msg.linear.x, msg.angular.z = self._cmd.linear, self._cmd.angular
        self._cmd_pub.publish(msg)

    def exists(self) -> bool:
        """Whether the robot is in the world (adopted or spawned, and not deleted)."""
        return self._present

    def proximity(self) -> Scan | None:
        """The latest reading of each sensor topic (inf for one not heard yet); None while absent."""
        if not self._present:
            return None
        return {name: self._ranges[name][1] if name in self._ranges else math.inf for name in SENSOR_NAMES}

    def pose(self) -> Pose | None:
        """The latest /odom pose; None while absent or before the first message."""
        odom = self._odom
        if not self._present or odom is None:
            return None
        return Pose(odom[1], odom[2], odom[3])

    def true_pose(self) -> Pose | None:
        """The odometry pose: the course's Gazebo publishes the true pose there (odometry_source WORLD)."""
        return self.pose()

    def velocity(self) -> Twist:
        """The latest /odom twist (zero while absent)."""
        odom = self._odom
        return Twist(odom[4], odom[5]) if self._present and odom is not None else Twist()

    def command(self) -> Twist:
        """The held command."""
        return self._cmd

    # ------------------------------------------------------------ stepping
    def advance(self, duration: float) -> None:
        """Wait for the next tick's time and its readings, then move the entity requests on.

        ``advance(0)`` (the runner's, after asking for the start pose) waits for the requests to end."""
        if duration <= 0.0:
            if not self._started and self._clock_ns is None and self._odom is None:
                raise RobotLost(
                    f"nothing heard on {self.topics.odom} or {self.topics.clock}: is the simulator or "
                    f"the robot's driver running, with the same ROS_DOMAIN_ID "
                    f"({os.environ.get('ROS_DOMAIN_ID', '0')})?"
                )
            self._finish_requests()
            if not self._started:
                self._start()
            return
        self._deadline_ns += round(duration * 1e9)
        if self._sim_time:
            self._wait_sim_tick()
        else:
            lag = (self._deadline_ns - self._now_ns()) / 1e9
            if lag > 0:
                time.sleep(lag)  # realtime: a real robot is paced by the wall clock, as the aseba backend is
            self._deadline_ns = max(self._deadline_ns, self._now_ns())
            self._check_alive()
        if self._present and self._cmd != Twist():
            self._publish_command()
        self._pump()
        self._contacts.update(self, self.pose())  # the course's odometry is the true pose

    def _wait_sim_tick(self) -> None:
        """Until the clock reaches the tick and every sensor has published its reading of it
        (or a sensor period more has passed: a sensor that skips a beat does not stall the run)."""
        deadline = self._deadline_ns
        sensor_ns = round(1e9 / self.topics.sensor_rate)
        odom_ns = round(1e9 / self.topics.odom_rate)

        def fresh() -> bool:
            now = self._clock_ns or 0
            if now < deadline:
                return False
            if not self._present or now >= deadline + sensor_ns:
                return True
            odom = self._odom
            return (
                odom is not None
                and odom[0] > deadline - odom_ns
                and all(
                    name in self._ranges and self._ranges[name][0] > deadline - sensor_ns
                    for name in self.topics.sensors
                )
            )

        wall_deadline = time.monotonic() + self.timeout
        with self._cond:
            while not fresh():
                if time.monotonic() > max(wall_deadline, self._clock_wall + self.timeout):
                    break
                self._cond.wait(POLL)
        self._check_alive()

    def _check_alive(self) -> None:
        now = time.monotonic()
        if self._sim_time and now - self._clock_wall > self.timeout:
            raise RobotLost(
                f"no message on {self.topics.clock} for {self.timeout:g} s (the simulator stopped or was paused)"
            )
        if self._present:
            if now - self._odom_wall > self.timeout:
                raise RobotLost(f"no message on {self.topics.odom} for {self.timeout:g} s")
            for name, topic in self.topics.sensors.items():
                if now - self._sensor_wall.get(name, 0.0) > self.timeout:
                    raise RobotLost(f"no message on {topic} for {self.timeout:g} s")

    # ------------------------------------------------------------ entities
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

    # ------------------------------------------------------------ closing
    def _stop_motors(self) -> None:
        self._cmd = Twist()
        self._publish_command()

    def close(self) -> None:
        """Stop the motors (a zero Twist, waited for), then leave ROS; again: no effect."""
        if self._closed:
            return
        self._closed = True
        try:
            if self._present:
                self._stop_motors()
                from rclpy.duration import Duration

                self._cmd_pub.wait_for_all_acked(Duration(seconds=1))
        finally:
            self._ros.close()


def create_ros2(mission: Mission, seed: int, options: Ros2Options) -> Ros2Robot:
    """The ``ros2`` backend kind: the mission's robot behind the topic map of ``options.topics``."""
    from thymio_bt.backends.ros2.topics import COURSE_TOPICS, load_topics

    topics = load_topics(options.topics) if options.topics else COURSE_TOPICS
    xml = None
    if options.robot_xml:
        from thymio_bt.inputs.reading import read_text

        xml = read_text(options.robot_xml, "world")
    return Ros2Robot(
        topics, mission.maze, robot_model(mission.robot), options.timeout, options.latency, options.clock, xml
    )
