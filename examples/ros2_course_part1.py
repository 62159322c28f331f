"""The course's part 1 written as a student would, in plain rclpy (no thymio-bt import).

Drive until the front-centre sensor reads 5 cm, stop, delete the robot and respawn it at
(0.5, 0.3, yaw pi/2), as in the course's session 3. It runs unchanged against the course's Gazebo
launch or against thymio-bt's stand-in:

    DIR/bin/thymio-bt serve ros2 &
    DIR/bin/python examples/ros2_course_part1.py

(DIR made by scripts/ros2-env.sh; in a ROS 2 install, source it and use python3.)
"""

import math

import rclpy
from gazebo_msgs.srv import DeleteEntity, SpawnEntity
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String

STOP_DISTANCE = 0.05  # m, from the front of the robot
SPEED = 0.1  # m/s while nothing is in range
CAUTIOUS_SPEED = 0.02  # m/s once the wall is seen


class Part1(Node):
    def __init__(self):
        super().__init__("part1")
        self.cmd_pub = self.create_publisher(Twist, "/cmd_vel", 10)
        self.create_subscription(Odometry, "/odom", self.odom_callback, 10)
        self.create_subscription(LaserScan, "/thymio_front_center_proximity_sensor", self.front_callback, 10)
        # the robot's URDF, to spawn it again (latched by robot_state_publisher, as spawn_entity.py reads it)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(String, "/robot_description", self.description_callback, latched)
        self.robot_description = ""
        self.delete_client = self.create_client(DeleteEntity, "/delete_entity")
        self.spawn_client = self.create_client(SpawnEntity, "/spawn_entity")
        self.front = float("inf")  # no reading yet: nothing in range
        self.x = self.y = None
        self.state = "MOVE_UNTIL_WALL"
        self.timer = self.create_timer(0.1, self.step)

    def odom_callback(self, msg):
        self.x, self.y = msg.pose.pose.position.x, msg.pose.pose.position.y

    def front_callback(self, msg):
        self.front = float(msg.ranges[0])

    def description_callback(self, msg):
        self.robot_description = msg.data

    def step(self):
        if self.state != "MOVE_UNTIL_WALL":
            return
        cmd = Twist()
        if self.front <= STOP_DISTANCE:
            self.cmd_pub.publish(cmd)  # zero: stop
            self.get_logger().info(f"stopped: front {self.front:.4f} m, odom x={self.x:.4f} y={self.y:.4f}")
            print(f"STOPPED front={self.front:.4f} x={self.x:.4f} y={self.y:.4f}", flush=True)
            self.state = "DELETING"
            self.delete_client.wait_for_service(timeout_sec=5.0)
            self.delete_client.call_async(DeleteEntity.Request(name="thymio")).add_done_callback(self.deleted)
            return
        cmd.linear.x = SPEED if math.isinf(self.front) else CAUTIOUS_SPEED
        self.cmd_pub.publish(cmd)

    def deleted(self, future):
        if not future.result().success:
            print(f"DELETE FAILED {future.result().status_message}", flush=True)
            self.state = "DONE"
            return
        request = SpawnEntity.Request()
        request.name = "thymio"
        request.xml = self.robot_description
        request.initial_pose.position.x, request.initial_pose.position.y = 0.5, 0.3
        request.initial_pose.orientation.z = math.sin(math.pi / 4)
        request.initial_pose.orientation.w = math.cos(math.pi / 4)
        self.state = "SPAWNING"
        self.spawn_client.wait_for_service(timeout_sec=5.0)
        self.spawn_client.call_async(request).add_done_callback(self.spawned)

    def spawned(self, future):
        print(f"SPAWNED {future.result().success}", flush=True)
        self.state = "DONE"


def main():
    rclpy.init()
    node = Part1()
    while rclpy.ok() and node.state != "DONE":
        rclpy.spin_once(node, timeout_sec=0.1)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
