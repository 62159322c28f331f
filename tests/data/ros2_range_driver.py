"""A stand-in for a real Thymio's ROS driver, for tests/test_ros2.py: no /clock (wall time), Range
proximity messages on its own topic names, no spawn or delete services. It drives a point robot
along +x from (0.1, 0.1) by /cmd_vel, integrated at 50 Hz of wall time, in front of a wall at
x = 0.595, and publishes /odom and the front sensor's Range (inf beyond 0.0975 m) at 10 Hz.

    python tests/data/ros2_range_driver.py      # runs until killed
"""

import math
import time

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Range

WALL_X, FRONT = 0.595, 0.0557
SENSORS = ("left", "center_left", "center", "center_right", "right", "rear_left", "rear_right")


def main():
    rclpy.init()
    node = rclpy.create_node("fake_thymio_driver")
    state = {"x": 0.1, "v": 0.0}
    node.create_subscription(Twist, "/cmd_vel", lambda m: state.update(v=m.linear.x), 10)
    odom_pub = node.create_publisher(Odometry, "/odom", 10)
    range_pubs = {s: node.create_publisher(Range, f"/proximity/{s}", 10) for s in SENSORS}
    last = time.monotonic()
    ticks = 0
    while rclpy.ok():
        rclpy.spin_once(node, timeout_sec=0.02)
        now = time.monotonic()
        if now - last < 0.02:
            continue
        state["x"] += state["v"] * (now - last)
        last = now
        ticks += 1
        stamp = node.get_clock().now().to_msg()
        odom = Odometry()
        odom.header.stamp, odom.header.frame_id, odom.child_frame_id = stamp, "odom", "base_footprint"
        odom.pose.pose.position.x, odom.pose.pose.position.y = state["x"], 0.1
        odom.pose.pose.orientation.w = 1.0
        odom.twist.twist.linear.x = state["v"]
        odom_pub.publish(odom)
        if ticks % 5 == 0:
            gap = WALL_X - state["x"] - FRONT
            for name, pub in range_pubs.items():
                msg = Range()
                msg.header.stamp, msg.header.frame_id = stamp, f"{name}_link"
                msg.min_range, msg.max_range = 0.0005, 0.0975
                msg.range = gap if name == "center" and gap <= 0.0975 else math.inf
                pub.publish(msg)


if __name__ == "__main__":
    import contextlib

    from rclpy.executors import ExternalShutdownException

    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):  # stopped by the test: quietly
        main()
