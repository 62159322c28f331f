"""The Playground's robot as Enki sees it, over D-Bus (jeepney): its true pose, and teleporting it.

The Playground registers ``ch.epfl.mobots.AsebaPlayground``; ``/world`` lists physical objects by
type, and each object has ``x``, ``y`` (cm) and ``angle`` (rad) properties, writable. Enki's
position is the wheel axle.

With a Playground running (:mod:`.process` starts one)::

    robot = EnkiRobot.find(bus)          # the world's first Thymio
    robot.pose()                          # (x_cm, y_cm, angle)
    robot.place(40.0, 30.0, 1.5708)
"""

from __future__ import annotations

import time
from typing import Any

from thymio_bt.errors import Problem, UserError
from thymio_bt.robot.interface import RobotLost

SERVICE = "ch.epfl.mobots.AsebaPlayground"


def _jeepney() -> Any:
    try:
        import jeepney
        import jeepney.io.blocking
    except ImportError:
        raise UserError(
            Problem(
                "the 'playground' backend needs jeepney, which is not installed", hint="pip install 'thymio-bt[aseba]'"
            )
        ) from None
    return jeepney


class EnkiRobot:
    """One Thymio of a Playground's world, on its D-Bus interface."""

    def __init__(self, connection: Any, path: str) -> None:
        jeepney = _jeepney()
        self.connection = connection
        self.properties = jeepney.Properties(
            jeepney.DBusAddress(path, bus_name=SERVICE, interface="ch.epfl.mobots.EnkiPhysicalObject")
        )

    @classmethod
    def find(cls, bus: str, timeout: float = 5.0) -> EnkiRobot:
        """The first Thymio of the Playground on ``bus`` (waiting for the Playground to register)."""
        jeepney = _jeepney()
        connection = jeepney.io.blocking.open_dbus_connection(bus=bus)
        world = jeepney.DBusAddress("/world", bus_name=SERVICE, interface="ch.epfl.mobots.EnkiWorld")
        try:
            return cls(connection, cls._first_thymio(jeepney, connection, world, timeout))
        except BaseException:  # no Playground, or Ctrl-C while waiting: let go of the bus
            connection.close()
            raise

    @staticmethod
    def _first_thymio(jeepney: Any, connection: Any, world: Any, timeout: float) -> str:
        """The object path of the world's first Thymio, once the Playground has registered."""
        deadline = time.monotonic() + timeout
        while True:
            reply = connection.send_and_get_reply(
                jeepney.new_method_call(world, "PhysicalObjectsByType", "s", ("Thymio2",))
            )
            if reply.header.message_type == jeepney.MessageType.method_return and reply.body[0]:
                break
            if time.monotonic() > deadline:
                raise UserError(
                    Problem(
                        f"the Aseba Playground's D-Bus interface did not appear within {timeout:g} s",
                        hint="is it the Playground of the aseba package (1.6.99 or later)?",
                    )
                )
            time.sleep(0.05)  # realtime: waiting for a program to register
        reply = connection.send_and_get_reply(
            jeepney.new_method_call(world, "PhysicalObject", "s", (reply.body[0][0],))
        )
        return str(reply.body[0])

    def _call(self, message: Any) -> Any:
        """Send ``message``; its reply's body, or RobotLost when the Playground does not answer."""
        jeepney = _jeepney()
        try:
            reply = self.connection.send_and_get_reply(message, timeout=2.0)
        except (OSError, TimeoutError) as exc:
            raise RobotLost(f"the Aseba Playground's D-Bus interface failed: {exc}") from None
        if reply.header.message_type != jeepney.MessageType.method_return:
            raise RobotLost(
                f"the Aseba Playground's D-Bus interface answered: {reply.body[0] if reply.body else 'an error'}"
            )
        return reply.body

    def _get(self, name: str) -> float:
        return float(self._call(self.properties.get(name))[0][1])

    def pose(self) -> tuple[float, float, float]:
        """The wheel axle's x, y (cm) and heading (rad), as the simulation has them."""
        return self._get("x"), self._get("y"), self._get("angle")

    def place(self, x_cm: float, y_cm: float, angle: float) -> None:
        """Teleport the robot (its wheel axle) to (x, y) cm, heading ``angle``."""
        for name, value in (("x", x_cm), ("y", y_cm), ("angle", angle)):
            self._call(self.properties.set(name, "d", float(value)))

    def close(self) -> None:
        """Close the D-Bus connection."""
        self.connection.close()
