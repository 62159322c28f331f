"""``thymio-bt serve ros2``: our simulation standing in for the course's Gazebo classic world.

It offers what the course's launch file gives a student's node (docs/sources.md, "Robot geometry and
sensors"), so a node written for the course runs against it unchanged:

- ``/cmd_vel`` (geometry_msgs/Twist) in, held until the next one (no timeout);
- ``/odom`` (nav_msgs/Odometry, frame ``odom`` -> ``base_footprint``, the true pose as Gazebo's
  ``odometry_source WORLD``) and its TF at 50 Hz, the wheels' TF too;
- ``/thymio_<prefix>_sensor`` (sensor_msgs/LaserScan, one ray, frame ``<prefix>_link``, ``inf``
  when nothing is within 0.0975 m) for the 7 proximity sensors at 10 Hz;
- ``/spawn_entity`` and ``/delete_entity`` (gazebo_msgs) for the robot ``thymio``;
- ``/clock`` (rosgraph_msgs/Clock) at every physics step (100 Hz), ``/tf_static`` with the sensor
  links, and ``/robot_description`` as robot_state_publisher gives it;
- ``/thymio_bt/world``, latched: which maze and start it serves (:mod:`.world`).

The world runs at real time x ``speedup`` of the wall clock (that is the point of a stand-in); its
physics is the same deterministic simulation as ``thymio-bt run``. A client that steps it in lock
(``--backend ros2`` does, :mod:`.world`) holds it at each of its ticks until it has sent that tick's
command, so a slow or loaded client sees the same world as the direct run.

From the shell, with ROS 2 (``scripts/ros2-env.sh``)::

    thymio-bt serve ros2 --maze two_parts_maze --start 0.1,0.1,0 --speedup 2
"""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from thymio_bt.backends.ros2 import import_rclpy
from thymio_bt.backends.ros2.messages import quaternion_of, stamp_ns, stamp_parts, yaw_of
from thymio_bt.backends.ros2.node import SpunRosNode
from thymio_bt.backends.ros2.topics import COURSE_TOPICS, PREFIXES, TopicMap
from thymio_bt.backends.ros2.world import HELD_TOPIC, HOLD_TIMEOUT, RELEASE, STEP_TOPIC, WORLD_TOPIC, WorldInfo
from thymio_bt.backends.sim.world import SimConfig, Simulation
from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze
from thymio_bt.robot.interface import ROBOT_ENTITY
from thymio_bt.robot.model import RobotModel

#: what the course's diff-drive plugin reports as its covariances (x, y, yaw)
ODOM_COVARIANCE = (0.00001, 0.00001, 0.001)
#: the proximity rays' limits in the course's URDF (min, max) and their half-aperture (rad)
RAY_MIN, RAY_HALF_ANGLE = 0.0005, 0.05
SENSOR_Z = 0.035
#: a Fast DDS profile announcing the stand-in's participant every 0.5 s instead of every 3 s: a client
#: started after it found it only at its next announcement, up to 3.3 s later (more when one was lost)
FOUND_QUICKLY = (
    '<?xml version="1.0" encoding="UTF-8" ?>'
    '<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">'
    '<participant profile_name="thymio_bt_serve" is_default_profile="true"><rtps><builtin><discovery_config>'
    "<leaseAnnouncement><sec>0</sec><nanosec>500000000</nanosec></leaseAnnouncement>"
    "</discovery_config></builtin></rtps></participant></profiles>"
)
PROFILE_VARIABLES = ("FASTDDS_DEFAULT_PROFILES_FILE", "FASTRTPS_DEFAULT_PROFILES_FILE")


@contextlib.contextmanager
def found_quickly() -> Iterator[None]:
    """While a participant is made inside, have Fast DDS announce it every 0.5 s (:data:`FOUND_QUICKLY`);
    nothing when another middleware is chosen or the user has a Fast DDS profile of their own."""
    rmw = os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    if not rmw.startswith("rmw_fastrtps") or any(os.environ.get(name) for name in PROFILE_VARIABLES):
        yield
        return
    with tempfile.TemporaryDirectory(prefix="thymio-bt-dds-") as folder:
        profile = Path(folder) / "serve.xml"
        profile.write_text(FOUND_QUICKLY)
        os.environ[PROFILE_VARIABLES[0]] = str(profile)
        try:
            yield
        finally:
            del os.environ[PROFILE_VARIABLES[0]]


def robot_urdf(model: RobotModel) -> str:
    """A URDF naming the course robot's frames (what /robot_description carries), from the model."""
    links = [
        "base_footprint",
        "base_link",
        "left_wheel_link",
        "right_wheel_link",
        *(f"{prefix}_link" for prefix in PREFIXES.values()),
    ]
    joints = [
        '<joint name="base_joint" type="fixed"><parent link="base_footprint"/><child link="base_link"/>'
        '<origin xyz="0 0 0"/></joint>'
    ]
    for side, sign in (("left", 1), ("right", -1)):
        joints.append(
            f'<joint name="{side}_wheel_joint" type="continuous"><parent link="base_link"/>'
            f'<child link="{side}_wheel_link"/><axis xyz="0 1 0"/><origin xyz="{model.axle_x} '
            f'{sign * model.wheel_separation / 2} {model.wheel_radius}"/></joint>'
        )
    for sensor in model.sensors:
        prefix = PREFIXES[sensor.name]
        joints.append(
            f'<joint name="{prefix}_joint" type="fixed"><parent link="base_link"/>'
            f'<child link="{prefix}_link"/><origin xyz="{sensor.x} {sensor.y} {SENSOR_Z}" '
            f'rpy="0 0 {sensor.yaw}"/></joint>'
        )
    body = "".join(f'<link name="{name}"/>' for name in links) + "".join(joints)
    return f'<?xml version="1.0"?><robot name="thymio">{body}</robot>'


class GazeboStandIn:
    """A :class:`Simulation` behind the course's Gazebo topics and services (module docstring)."""

    def __init__(
        self,
        maze: Maze,
        start: Pose | None,
        model: RobotModel,
        speedup: float = 1.0,
        physics_hz: float = 100.0,
        topics: TopicMap = COURSE_TOPICS,
    ) -> None:
        import_rclpy()  # first: without ROS, a UserError that says how to get it
        from gazebo_msgs.srv import DeleteEntity, SpawnEntity
        from geometry_msgs.msg import Twist, TwistStamped
        from nav_msgs.msg import Odometry
        from rclpy.qos import QoSDurabilityPolicy, QoSProfile
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan
        from std_msgs.msg import Header, String
        from tf2_msgs.msg import TFMessage

        self.maze, self.model, self.speedup, self.topics = maze, model, speedup, topics
        self.sim = Simulation(maze, spawn=start, config=SimConfig(physics_hz=physics_hz, robot=model))
        self.dt = 1.0 / physics_hz
        self._odom_every = max(1, round(physics_hz / topics.odom_rate))
        self._sensor_every = max(1, round(physics_hz / model.sensor_rate_hz))
        self._lock = threading.Condition()
        self._until_ns: int | None = None  # lockstep: the simulated time a client lets the world run to
        self._step_wall = 0.0  # when its last step message came (wall)
        self._held_at: int | None = None  # where the world holds, once said on the held topic
        self.world = WorldInfo.of(maze, start or self.sim.true_pose() or Pose(0.0, 0.0, 0.0), model.name, speedup)
        self._wheel_angles = [0.0, 0.0]
        self._msgs = {
            "Clock": Clock,
            "Odometry": Odometry,
            "LaserScan": LaserScan,
            "TFMessage": TFMessage,
            "Header": Header,
        }
        with found_quickly():
            self._ros = SpunRosNode("gazebo")
        ros_node = self._ros.ros_node
        latched = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
        self._clock_pub = ros_node.create_publisher(Clock, topics.clock, 10)
        self._odom_pub = ros_node.create_publisher(Odometry, topics.odom, 10)
        self._tf_pub = ros_node.create_publisher(TFMessage, "/tf", 10)
        self._scan_pubs = {
            name: ros_node.create_publisher(LaserScan, topic, 10)  # reliable, as Gazebo's
            for name, topic in topics.sensors.items()
        }
        ros_node.create_publisher(TFMessage, "/tf_static", latched).publish(TFMessage(transforms=self._static_tf()))
        ros_node.create_publisher(String, topics.robot_description, latched).publish(String(data=robot_urdf(model)))
        ros_node.create_publisher(String, WORLD_TOPIC, latched).publish(String(data=self.world.to_json()))
        ros_node.create_subscription(Twist, topics.cmd_vel, self._on_cmd_vel, 1)
        ros_node.create_subscription(TwistStamped, STEP_TOPIC, self._on_step, 10)
        self._held_pub = ros_node.create_publisher(Header, HELD_TOPIC, 10)
        # the services last: a client that sees them knows it would have seen the world topic (WorldLink)
        ros_node.create_service(SpawnEntity, topics.spawn, self._on_spawn)
        ros_node.create_service(DeleteEntity, topics.delete, self._on_delete)
        self._ros.start("thymio-bt-serve")

    # ------------------------------------------------------------ requests (executor thread)
    def _on_cmd_vel(self, msg: Any) -> None:
        with self._lock:
            if self._until_ns is None:  # in lockstep, the step message is the command of the tick
                self.sim.drive(msg.linear.x, msg.angular.z)

    def _on_step(self, msg: Any) -> None:
        with self._lock:
            self.sim.drive(msg.twist.linear.x, msg.twist.angular.z)
            released = msg.header.frame_id == RELEASE
            self._until_ns = None if released else stamp_ns(msg.header.stamp.sec, msg.header.stamp.nanosec)
            self._step_wall, self._held_at = time.monotonic(), None
            self._lock.notify_all()

    def _entity_request(self, ask: Callable[[], Any], response: Any) -> Any:
        with self._lock:
            request = ask()
            self.sim.serve_requests()
        response.success = request.state.name == "SUCCEEDED"
        response.status_message = request.reason or ""
        return response

    def _on_spawn(self, request: Any, response: Any) -> Any:
        if request.name != ROBOT_ENTITY:
            response.success = False
            response.status_message = f"this stand-in simulates one Thymio, named '{ROBOT_ENTITY}'"
            return response
        p, q = request.initial_pose.position, request.initial_pose.orientation
        yaw = yaw_of(q.x, q.y, q.z, q.w)
        return self._entity_request(lambda: self.sim.request_spawn(request.name, Pose(p.x, p.y, yaw)), response)

    def _on_delete(self, request: Any, response: Any) -> Any:
        return self._entity_request(lambda: self.sim.request_delete(request.name), response)

    # ------------------------------------------------------------ publishing
    def _transform(
        self,
        stamp: Any,
        parent: str,
        child: str,
        x: float,
        y: float,
        z: float,
        quaternion: tuple[float, float, float, float],
    ) -> Any:
        from geometry_msgs.msg import TransformStamped

        tf = TransformStamped()
        tf.header.stamp, tf.header.frame_id, tf.child_frame_id = stamp, parent, child
        tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z = x, y, z
        r = tf.transform.rotation
        r.x, r.y, r.z, r.w = quaternion
        return tf

    def _static_tf(self) -> list[Any]:
        from builtin_interfaces.msg import Time

        zero = Time()
        tfs = [self._transform(zero, "base_footprint", "base_link", 0.0, 0.0, 0.0, quaternion_of(0.0))]
        for sensor in self.model.sensors:
            tfs.append(
                self._transform(
                    zero,
                    "base_link",
                    f"{PREFIXES[sensor.name]}_link",
                    sensor.x,
                    sensor.y,
                    SENSOR_Z,
                    quaternion_of(sensor.yaw),
                )
            )
        return tfs

    def _publish(self, steps: int) -> None:
        sim = self.sim
        stamp = self._time(round(sim.time() * 1e9))
        pose = sim.true_pose()
        if pose is not None and steps % self._odom_every == 0:
            self._publish_odom(stamp, pose)
        if pose is not None and steps % self._sensor_every == 0:
            scan = sim.proximity() or {}
            for name, publisher in self._scan_pubs.items():
                publisher.publish(self._scan(stamp, name, scan.get(name, math.inf)))
        self._clock_pub.publish(self._msgs["Clock"](clock=stamp))

    def _publish_odom(self, stamp: Any, pose: Pose) -> None:
        velocity = self.sim.velocity()
        odom = self._msgs["Odometry"]()
        odom.header.stamp, odom.header.frame_id, odom.child_frame_id = stamp, "odom", "base_footprint"
        odom.pose.pose.position.x, odom.pose.pose.position.y = pose.x, pose.y
        o = odom.pose.pose.orientation
        o.x, o.y, o.z, o.w = quaternion_of(pose.yaw)
        cx, cy, cyaw = ODOM_COVARIANCE
        odom.pose.covariance[0], odom.pose.covariance[7], odom.pose.covariance[35] = cx, cy, cyaw
        odom.twist.twist.linear.x, odom.twist.twist.angular.z = velocity.linear, velocity.angular
        self._odom_pub.publish(odom)
        period = self._odom_every * self.dt
        tfs = [self._transform(stamp, "odom", "base_footprint", pose.x, pose.y, 0.0, quaternion_of(pose.yaw))]
        for i, (side, sign) in enumerate((("left", 1), ("right", -1))):
            wheel = velocity.linear - sign * velocity.angular * self.model.wheel_separation / 2
            self._wheel_angles[i] += wheel / self.model.wheel_radius * period
            half = self._wheel_angles[i] / 2
            tfs.append(
                self._transform(
                    stamp,
                    "base_link",
                    f"{side}_wheel_link",
                    self.model.axle_x,
                    sign * self.model.wheel_separation / 2,
                    self.model.wheel_radius,
                    (0.0, math.sin(half), 0.0, math.cos(half)),
                )
            )
        self._tf_pub.publish(self._msgs["TFMessage"](transforms=tfs))

    def _scan(self, stamp: Any, name: str, value: float) -> Any:
        msg = self._msgs["LaserScan"]()
        msg.header.stamp, msg.header.frame_id = stamp, f"{PREFIXES[name]}_link"
        msg.angle_min, msg.angle_max, msg.angle_increment = -RAY_HALF_ANGLE, RAY_HALF_ANGLE, 2 * RAY_HALF_ANGLE
        msg.range_min, msg.range_max = RAY_MIN, self.model.range_max
        msg.ranges = [value if value >= RAY_MIN else -math.inf]
        msg.intensities = [0.0]
        return msg

    # ------------------------------------------------------------ running
    def run(self, stop: Callable[[], bool], on_second: Callable[[float, float], None] | None = None) -> None:
        """Step and publish at real time x speedup until ``stop()``; ``on_second(sim_time, speed)``
        is called once per simulated second with the speed-up achieved so far."""
        wall_start = pace_start = time.monotonic()
        steps = 0
        self._publish(0)
        while not stop():
            if self._holding():
                pace_start = time.monotonic() - steps * self.dt / self.speedup  # on from here, no catching up
                continue
            with self._lock:
                self.sim.advance(self.dt)
            steps += 1
            self._publish(steps)
            sim_time = steps * self.dt
            lag = pace_start + sim_time / self.speedup - time.monotonic()
            if lag > 0:
                time.sleep(lag)  # realtime: a stand-in for Gazebo runs against the wall clock (x speedup)
            if on_second is not None and steps % round(1.0 / self.dt) == 0:
                on_second(sim_time, sim_time / max(time.monotonic() - wall_start, 1e-9))

    def _holding(self) -> bool:
        """Whether a lockstep client holds the world here (then wait a moment for its next step): it
        has let it run to this time, and is still there (a publisher of the step topic, heard from
        within :data:`HOLD_TIMEOUT` s)."""
        with self._lock:
            now = round(self.sim.time() * 1e9)
            if self._until_ns is None or now < self._until_ns:
                return False
            gone = not self._ros.ros_node.count_publishers(STEP_TOPIC)
            if gone or time.monotonic() - self._step_wall > HOLD_TIMEOUT:
                self._until_ns = None  # the client went away: run freely, as Gazebo would
                return False
            if self._held_at != now:
                self._held_at = now
                robot = ROBOT_ENTITY if self.sim.true_pose() is not None else ""
                self._held_pub.publish(self._msgs["Header"](stamp=self._time(now), frame_id=robot))
            self._lock.wait(0.05)
            return True

    @staticmethod
    def _time(ns: int) -> Any:
        from builtin_interfaces.msg import Time

        stamp = Time()
        stamp.sec, stamp.nanosec = stamp_parts(ns)
        return stamp

    def close(self) -> None:
        """Stop spinning, leave ROS and end the spinner thread."""
        self._ros.close()
