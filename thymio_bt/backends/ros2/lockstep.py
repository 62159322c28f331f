"""The client side of :mod:`.world`: what ``--backend ros2`` learns of a ``serve ros2`` and how it
steps that world in lock.

Why lockstep: a simulator publishing ``/clock`` runs on whether or not its client keeps up. Under CPU
load a client's tick woke when the clock had already passed it (by 170 ms of simulated time on the
median, up to 6.5 s), and its commands reached the simulator 40 ms (up to 570 ms) late: part 1 of
the course stopped at 46-49 mm instead of 50 mm and the runs failed (docs/ros2.md, "Under load").
Gazebo cannot be held, so there the backend can only measure how late its ticks are and say so
(:class:`Lateness`); the stand-in, which is ours, waits for each tick's command. That is how a
simulator meant to give a verdict should be driven (as CARLA's synchronous mode or Webots'
synchronisation do): the world's time advances only as far as the controller has decided.

Without ROS, with stand-ins for the node's pieces::

    >>> late = Lateness(sensor_period_ns=100_000_000)
    >>> for lead in (0, 0, 30_000_000, 0):
    ...     late.tick(lead)
    >>> print(late.summary())
    1 of 4 ticks read the world after their time (up to 30 ms of simulated time)
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from thymio_bt.backends.ros2.messages import stamp_ns, stamp_parts
from thymio_bt.backends.ros2.world import HELD_TOPIC, RELEASE, STEP_TOPIC, WORLD_TOPIC, WorldInfo
from thymio_bt.robot.interface import RobotLost, Twist

#: how long to wait for a simulator's world topic once its clock is heard, when none is seen and
#: nothing shows that it has none (wall s)
WORLD_GRACE = 2.0


class Lateness:
    """How late a run's ticks read a simulator's world: ``lead`` is how far ``/clock`` had gone past a
    tick's time when the tick woke (0 when the run keeps up, or steps in lock)."""

    def __init__(self, sensor_period_ns: int) -> None:
        self.sensor_period_ns = sensor_period_ns
        self.ticks = self.late = 0
        self.worst_ns = 0

    def tick(self, lead_ns: int) -> None:
        """Count one tick that woke ``lead_ns`` after its time."""
        self.ticks += 1
        if lead_ns > 0:
            self.late += 1
            self.worst_ns = max(self.worst_ns, lead_ns)

    def summary(self) -> str | None:
        """What to tell the user, or None when every tick was on time."""
        if not self.late:
            return None
        return (
            f"{self.late} of {self.ticks} ticks read the world after their time "
            f"(up to {self.worst_ns / 1e6:.0f} ms of simulated time)"
        )


class WorldLink:
    """The world topic heard, the step topic published and the held topic heard, on the rclpy node
    ``ros_node``; ``cond`` is notified when something comes (the backend's condition)."""

    def __init__(self, ros_node: Any, cond: threading.Condition) -> None:
        from geometry_msgs.msg import TwistStamped
        from rclpy.qos import QoSDurabilityPolicy, QoSProfile
        from std_msgs.msg import Header, String

        self._ros_node, self._cond, self._TwistStamped = ros_node, cond, TwistStamped
        self.world: WorldInfo | None = None
        self.engaged = False  # stepping the world in lock
        self._held_ns: int | None = None  # where the world holds (as last said)
        self._held_robot = False  # and whether the robot is in it there
        latched = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
        ros_node.create_subscription(String, WORLD_TOPIC, self._on_world, latched)
        ros_node.create_subscription(Header, HELD_TOPIC, self._on_held, 10)
        self._step_pub = ros_node.create_publisher(TwistStamped, STEP_TOPIC, 10)

    def _on_world(self, msg: Any) -> None:
        with self._cond:
            self.world = WorldInfo.from_json(msg.data)
            self._cond.notify_all()

    def _on_held(self, msg: Any) -> None:
        with self._cond:
            self._held_ns = stamp_ns(msg.stamp.sec, msg.stamp.nanosec)
            self._held_robot = bool(msg.frame_id)
            self._cond.notify_all()

    def robot_held(self, tick_ns: int) -> bool:
        """Whether the world is not yet held at ``tick_ns``, or is, with the robot in it."""
        return self._held_ns is None or self._held_ns < tick_ns or self._held_robot

    def wait_world(self, timeout: float, later: Callable[[], bool]) -> WorldInfo | None:
        """The world topic's message: waited for up to ``timeout`` s while someone publishes it; while
        nobody is seen to (the course's Gazebo has none), until ``later()`` (something a stand-in makes
        after its world topic has been discovered: discovery reports a participant's endpoints in the
        order they were made) or for :data:`WORLD_GRACE` s: each endpoint is discovered on its own,
        and a loaded client may hear the clock well before it sees the world topic."""
        start = time.monotonic()
        with self._cond:
            while self.world is None:
                waited = time.monotonic() - start
                if waited > timeout:
                    break
                if not self._ros_node.count_publishers(WORLD_TOPIC) and (later() or waited > WORLD_GRACE):
                    break
                self._cond.wait(0.05)
        return self.world

    def step(self, command: Twist, until_ns: int) -> None:
        """Let the world run to ``until_ns`` with ``command`` (the command of the tick)."""
        msg = self._TwistStamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp_parts(until_ns)
        msg.twist.linear.x, msg.twist.angular.z = command.linear, command.angular
        self._step_pub.publish(msg)

    def hold(self, command: Twist, clock_ns: int, grid_ns: int, period_ns: int, timeout: float) -> int:
        """Engage: have the world hold at an instant of the sensors' grid (``grid_ns`` + k
        ``period_ns``) ahead of ``clock_ns``; that instant, once the world holds there."""
        target = grid_ns
        for _ in range(5):  # a held world past the target (the request came late) needs one more
            ahead = max(clock_ns, target)
            target = grid_ns + period_ns * (math.floor((ahead - grid_ns) / period_ns) + 2)
            with self._cond:
                self._held_ns = None
            self.step(command, target)
            deadline = time.monotonic() + timeout
            with self._cond:
                while self._held_ns is None:
                    if time.monotonic() > deadline:
                        raise RobotLost(f"no message on {HELD_TOPIC} within {timeout:g} s (the server stopped?)")
                    self._cond.wait(0.05)
                clock_ns = self._held_ns
            if clock_ns == target:
                self.engaged = True
                return target
        raise RobotLost(f"the server never held at a tick's time (last held at {clock_ns / 1e9:.3f} s)")

    def release(self) -> Any:
        """Let the world run freely again, the motors stopped; the publisher, to wait for its acks."""
        if self.engaged:
            self.engaged = False
            msg = self._TwistStamped()
            msg.header.frame_id = RELEASE
            self._step_pub.publish(msg)
        return self._step_pub
