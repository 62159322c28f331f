"""An rclpy node in a context of its own, spun by a daemon thread: what :mod:`.backend` and
:mod:`.serve` both stand on.

Each gets its own ``rclpy.Context`` (so a backend and a stand-in can live in one process, and
closing one leaves the other alone) and no signal handlers (Ctrl-C stays the CLI's). rclpy is
imported when a node is made, never when this module is.

With ROS 2::

    ros = SpunRosNode("thymio_bt")
    ros.ros_node.create_subscription(...)      # subscriptions, publishers, services
    ros.start("thymio-bt-ros2")                # callbacks now run in a daemon thread
    ros.close()
"""

from __future__ import annotations

import contextlib
import threading
from typing import Any

from thymio_bt.backends.ros2 import import_rclpy


class SpunRosNode:
    """An rclpy node in its own context; :meth:`start` spins it in a daemon thread, :meth:`close` ends it all."""

    def __init__(self, name: str) -> None:
        rclpy = import_rclpy()
        from rclpy.signals import SignalHandlerOptions

        self.context = rclpy.Context()
        rclpy.init(args=[], context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        self.ros_node = rclpy.create_node(name, context=self.context)
        self._executor: Any = None
        self._spinner: threading.Thread

    def start(self, thread_name: str) -> None:
        """Spin the node in a daemon thread named ``thread_name`` (once its topics and services are made)."""
        from rclpy.executors import SingleThreadedExecutor

        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self.ros_node)
        self._spinner = threading.Thread(target=self._spin, name=thread_name, daemon=True)
        self._spinner.start()

    def _spin(self) -> None:
        with contextlib.suppress(Exception):  # the context was shut down under it: the node is closing
            self._executor.spin()

    def close(self) -> None:
        """Stop spinning, destroy the node, shut its context down and wait for the spinner thread."""
        self._executor.shutdown(timeout_sec=1.0)
        self.ros_node.destroy_node()
        self.context.try_shutdown()
        self._spinner.join(timeout=2.0)
