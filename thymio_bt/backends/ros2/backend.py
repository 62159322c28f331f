"""``--backend ros2``: a mission driving a Thymio through ROS 2 (the course's Gazebo by default).

The robot is its topics (:class:`~thymio_bt.backends.ros2.topics.TopicMap`): the command goes out on
``/cmd_vel`` (again at every tick: a driver with a command timeout keeps moving), the pose and
velocity come from ``/odom``, the proximity readings from one topic per sensor, and SpawnEntity and
DeleteEntity call Gazebo's services, completing over later ticks like the simulator's requests.

Time: when someone publishes ``/clock`` the run lives in that simulated time, and each 10 Hz tick
waits until the clock reaches it and the sensors have published their reading of that moment (the
ticks are laid on the sensors' own 10 Hz grid, so a tick reads what was sensed at its time);
otherwise the run is paced by the wall clock, as on a real robot. A ``serve ros2`` says which world
it serves: a mission on another maze is refused, and its world is stepped in lock, held at each tick
until the tick's command is sent (:mod:`.lockstep`); a simulator that cannot be held (Gazebo) is
followed, and ticks that woke after their time are counted and reported when the run closes.

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
import sys
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from thymio_bt.backends.ros2 import import_rclpy
from thymio_bt.backends.ros2.entities import POLL, EntitySteps
from thymio_bt.backends.ros2.lockstep import Lateness, WorldLink
from thymio_bt.backends.ros2.messages import odometry_of, reading_of, stamp_ns
from thymio_bt.backends.ros2.node import SpunRosNode
from thymio_bt.backends.ros2.topics import TopicMap
from thymio_bt.backends.ros2.world import maze_problem
from thymio_bt.errors import UserError
from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze
from thymio_bt.maze.files import maze_reference
from thymio_bt.robot.interface import ROBOT_ENTITY, SENSOR_NAMES, RobotLost, Scan, Twist
from thymio_bt.robot.model import RobotModel, robot_model
from thymio_bt.robot.placement import ContactTracker

if TYPE_CHECKING:
    from thymio_bt.backends import MissionWorld
    from thymio_bt.backends.ros2.options import Ros2Options


#: how long (wall s) to wait for a first message: Fast DDS's discovery took up to 3.3 s here (its
#: participants announce themselves again every 3 s; a run that started 2 s after its server missed it)
DISCOVERY = 5.0


class Ros2Robot(EntitySteps):
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
        maze_file: str = "",
    ) -> None:
        super().__init__()
        import_rclpy()  # first: without ROS, a UserError that says how to get it
        from geometry_msgs.msg import Twist as TwistMsg
        from rclpy.qos import QoSDurabilityPolicy, QoSProfile, qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from std_msgs.msg import String

        self.topics, self.maze, self.model, self._maze_file = topics, maze, model, maze_file or maze.name
        self.timeout, self.latency, self.robot_name = timeout, latency, ROBOT_ENTITY
        self._TwistMsg = TwistMsg
        self._ros = SpunRosNode(node_name)
        self._ros_node = self._ros.ros_node
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
        self._steps = []
        self._closed = False
        self._contacts = ContactTracker(maze, model)
        ros_node = self._ros_node
        ros_node.create_subscription(Clock, topics.clock, self._on_clock, qos_profile_sensor_data)
        self._subscribe_readings(qos_profile_sensor_data)
        if robot_xml is None and topics.robot_description:
            latched = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
            ros_node.create_subscription(String, topics.robot_description, self._on_description, latched)
        self._cmd_pub = ros_node.create_publisher(TwistMsg, topics.cmd_vel, 10)
        from gazebo_msgs.srv import DeleteEntity, SpawnEntity

        self._spawn_client = ros_node.create_client(SpawnEntity, topics.spawn) if topics.spawn else None
        self._delete_client = ros_node.create_client(DeleteEntity, topics.delete) if topics.delete else None
        self._link = WorldLink(ros_node, self._cond)
        self._late = Lateness(round(1e9 / topics.sensor_rate))
        self._ros.start("thymio-bt-ros2")
        self._wall_start = time.monotonic()
        self._sim_time = self._detect_clock(clock)
        if self._sim_time:
            self._check_world()
        self._start_ns = self._deadline_ns = self._now_ns()
        self._started = False

    def _subscribe_readings(self, qos: Any) -> None:
        """Subscribe to the odometry and the sensors (best effort, as sensor data; again, reliable,
        when stepping a world in lock: there the one reading of a tick must not be lost)."""
        from nav_msgs.msg import Odometry

        if self.topics.sensor_type == "LaserScan":
            from sensor_msgs.msg import LaserScan as SensorMsg
        else:
            from sensor_msgs.msg import Range as SensorMsg
        self._ros_node.create_subscription(Odometry, self.topics.odom, self._on_odom, qos)
        for name, topic in self.topics.sensors.items():
            self._ros_node.create_subscription(SensorMsg, topic, self._on_sensor(name), qos)

    # ------------------------------------------------------------ callbacks (executor thread)
    def _on_clock(self, msg: Any) -> None:
        with self._cond:
            self._clock_ns = stamp_ns(msg.clock.sec, msg.clock.nanosec)
            self._clock_wall = time.monotonic()
            self._cond.notify_all()

    def _on_odom(self, msg: Any) -> None:
        odom = odometry_of(msg)
        with self._cond:
            if self._odom is not None and odom[0] < self._odom[0]:
                return  # an older one, through the other subscription
            self._odom = odom
            self._odom_wall = time.monotonic()
            self._odom_count += 1
            self._cond.notify_all()

    def _on_sensor(self, name: str) -> Callable[[Any], None]:
        limit = self.model.range_max

        def store(msg: Any) -> None:
            reading = reading_of(msg, self.topics.sensor_type, limit)
            with self._cond:
                if name in self._ranges and reading[0] < self._ranges[name][0]:
                    return  # an older one, through the other subscription
                self._ranges[name] = reading
                self._sensor_wall[name] = time.monotonic()
                self._cond.notify_all()

        return store

    def _on_description(self, msg: Any) -> None:
        self._xml = msg.data

    def _check_world(self) -> None:
        """Refuse (exit 2) a mission on another maze than the one ``serve ros2`` serves."""
        spawn = self._spawn_client
        world = self._link.wait_world(
            max(self.timeout, DISCOVERY), lambda: spawn is not None and spawn.service_is_ready()
        )
        problem = maze_problem(world, self.maze) if world is not None else None
        if problem:
            self._ros.close()
            x, y, yaw = world.start if world is not None else (0.0, 0.0, 0.0)
            raise UserError(
                f"--backend ros2: {problem}; the run would drive blind through walls it does not know "
                f"(hint: restart the server on the mission's maze, 'thymio-bt serve ros2 --maze "
                f"{self._maze_file}', or run the mission with --maze {world.maze if world else ''})"
            )

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
        deadline = time.monotonic() + max(self.timeout, DISCOVERY)
        odom_since: float | None = None  # when odometry was first heard (a robot's driver, or a simulator)
        with self._cond:
            while self._clock_ns is None and time.monotonic() < deadline:
                if odom_since is None and self._odom is not None:
                    odom_since = time.monotonic()
                if odom_since is not None and time.monotonic() - odom_since > 1.0:
                    break  # odometry for a while and no clock: a real robot (the clock would have come with it)
                self._cond.wait(POLL)
            return self._clock_ns is not None

    def _nothing_answered(self) -> str:
        """What to say when no simulator or driver answered at all: what was waited for, how long, and
        how to start one."""
        clients = ((self.topics.spawn, self._spawn_client), (self.topics.delete, self._delete_client))
        services = [name for name, client in clients if client is not None and not client.service_is_ready()]
        env = os.environ
        return (
            f"nothing answered: no message on {self.topics.clock} or {self.topics.odom}"
            + (f" and no {' or '.join(services)} service" if services else "")
            + f" within {time.monotonic() - self._wall_start:.1f} s (ROS_DOMAIN_ID={env.get('ROS_DOMAIN_ID', '0')}, "
            f"ROS_AUTOMATIC_DISCOVERY_RANGE={env.get('ROS_AUTOMATIC_DISCOVERY_RANGE', 'unset')}); start a simulator "
            f"in the same domain ('thymio-bt serve ros2 --maze {self._maze_file}', or the course's Gazebo launch) "
            "or the robot's ROS driver, then run again"
        )

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
            world = self._link.world
            if world is not None and world.lockstep:
                from rclpy.qos import QoSProfile

                self._subscribe_readings(QoSProfile(depth=10))
                self._start_ns = self._deadline_ns = self._link.hold(
                    self._cmd, self._now_ns(), self._start_ns, self._late.sensor_period_ns, self.timeout
                )
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
                raise RobotLost(self._nothing_answered())
            self._finish_requests()
            if not self._started:
                self._start()
            return
        self._deadline_ns += round(duration * 1e9)
        if self._sim_time:
            if self._link.engaged:
                self._link.step(self._cmd if self._present else Twist(), self._deadline_ns)
            self._wait_sim_tick()
            self._late.tick(self._now_ns() - self._deadline_ns)
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

        def fresh() -> bool:
            now = self._clock_ns or 0
            if now < deadline:
                return False
            if not self._present or now >= deadline + sensor_ns:
                return True
            if self._link.engaged and not self._link.robot_held(deadline):
                return True  # held there with no robot (deleted, its answer on the way): no reading comes
            return not self._stale(deadline)

        wall_deadline = time.monotonic() + self.timeout
        stale: list[str] = []
        with self._cond:
            while not fresh():
                if time.monotonic() > max(wall_deadline, self._clock_wall + self.timeout):
                    if self._link.engaged and (self._clock_ns or 0) >= deadline:
                        stale = self._stale(deadline)
                    break
                self._cond.wait(POLL)
        if stale:  # held at the tick (so the clock is silent), waiting for these
            raise RobotLost(f"no message on {', '.join(stale)} for {self.timeout:g} s")
        self._check_alive()

    def _stale(self, tick_ns: int) -> list[str]:
        """The topics whose reading of the tick at ``tick_ns`` has not come (none while the robot is absent)."""
        if not self._present:
            return []
        odom, odom_ns = self._odom, round(1e9 / self.topics.odom_rate)
        sensor_ns = round(1e9 / self.topics.sensor_rate)
        stale = [] if odom is not None and odom[0] > tick_ns - odom_ns else [self.topics.odom]
        return stale + [
            topic
            for name, topic in self.topics.sensors.items()
            if name not in self._ranges or self._ranges[name][0] <= tick_ns - sensor_ns
        ]

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
            from rclpy.duration import Duration

            step_pub = self._link.release()
            if self._present:
                self._stop_motors()
                self._cmd_pub.wait_for_all_acked(Duration(seconds=1))
            step_pub.wait_for_all_acked(Duration(seconds=1))
        finally:
            self._ros.close()
        late = self._late.summary()
        if late:
            print(
                f"warning: --backend ros2: {late}: the simulator ran ahead of this run (a loaded machine?); "
                "its verdict may differ from the direct run's (hint: slow the simulator down, or free the CPU)",
                file=sys.stderr,
            )


def create_ros2(mission: MissionWorld, seed: int, options: Ros2Options) -> Ros2Robot:
    """The ``ros2`` backend kind: the mission's robot behind the topic map of ``options.topics``."""
    from thymio_bt.backends.ros2.topics import COURSE_TOPICS, load_topics

    topics = load_topics(options.topics) if options.topics else COURSE_TOPICS
    xml = None
    if options.robot_xml:
        from thymio_bt.inputs.reading import read_text

        xml = read_text(options.robot_xml, "world")
    return Ros2Robot(
        topics,
        mission.maze,
        robot_model(mission.robot),
        options.timeout,
        options.latency,
        options.clock,
        xml,
        maze_file=maze_reference(mission.maze_file) if mission.maze_file else mission.maze.name,
    )
