"""A Thymio over its own protocol (Aseba): a real robot on USB serial, or a simulated one on TCP.

:class:`AsebaNode` implements the backend's :class:`~thymio_bt.backends.real.thymio.AsebaDevice` with
thymiodirect's :class:`Connection` (optional extra ``thymio-bt[aseba]``), avoiding the traps
measured with thymiodirect 0.1.2 on the Aseba Playground 1.6.99:

- connecting has a deadline (thymiodirect's own ``Thymio.connect`` waits for ever on a closed port);
- the connection's threads are daemons and are shut down on :meth:`AsebaNode.close` (thymiodirect's
  are not, and keep a process alive);
- the robot refreshes the few variables used (``prox.horizontal``, ``motor.*.speed``) by itself every
  :data:`REFRESH` s; a read takes the latest values, a write is sent without waiting;
- the wheel speeds are integrated as each refresh arrives (:meth:`AsebaNode.read_wheel_travel`),
  not only at the backend's 10 Hz ticks: a speed that changes in a step (a turn starting) was
  sampled a tick apart, and each 90° turn's odometry came out up to 5° off on the Playground;
- values arrive as unsigned 16-bit words and are returned signed;
- a link that fails (a cable pulled, a TCP peer gone) is recorded, not raised in thymiodirect's
  threads (which would print a traceback); a robot that sends nothing for :data:`LOST_AFTER`
  seconds, or a connection that fails, raises
  :class:`~thymio_bt.robot.interface.RobotLost` at the next read: the run ends as FAILURE ``ROBOT_LOST``;
- thymiodirect trusts its peer, so it is given whole messages only, each judged first
  (:mod:`~thymio_bt.backends.real.frames`): garbage, a message cut short or one no Thymio sends
  fails the link (RobotLost, with the reason), what a Thymio may ignore is dropped;
- a ``tcp:HOST:PORT`` device is checked before connecting (:func:`tcp_address`): a port above 65535
  would wrap round to another one.

With a robot (or the Playground) to talk to::

    node = AsebaNode.connect("tcp:127.0.0.1:33333")     # or "/dev/ttyACM0", or "" for the only one
    node.set_motors(100, 100)
    node.read_prox()                                      # [0, 0, 1203, 0, 0, 0, 0]
    node.close()

Example (the words it receives)::

    >>> signed(0xFFFF), signed(1203)          # a wheel turning back at 1 unit, a proximity reading
    (-1, 1203)
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import socket
import threading
import time
from typing import TYPE_CHECKING, Any

from thymio_bt.backends.real.frames import HEADER, MAX_PAYLOAD, Gate, LinkError
from thymio_bt.backends.real.thymio import (
    PROX_VARIABLE,
    SPEED_VARIABLES,
    TARGET_VARIABLES,
    AsebaDevice,
    ThymioRobot,
)
from thymio_bt.errors import Problem, UserError, optional_module
from thymio_bt.robot.interface import RobotLost

if TYPE_CHECKING:
    from thymio_bt.backends import MissionWorld
    from thymio_bt.backends.real.options import AsebaOptions

#: A robot silent for this long (s) is lost; thymiodirect alone would wait 3 s and then say nothing.
LOST_AFTER = 0.8
#: How often the robot is asked for its variables (s), and how often it is looked for while connecting.
REFRESH, DISCOVER = 0.03, 0.1
#: A message begun but not finished within this long (s) was cut short: the link has failed.
CUT_SHORT = LOST_AFTER
_CUT = f"a message was cut short: nothing more for {CUT_SHORT:g} s"
#: The variables (name: words) the link reads and writes: a node without them is no Thymio II.
REQUIRED = {PROX_VARIABLE: 7, **dict.fromkeys((*SPEED_VARIABLES, *TARGET_VARIABLES), 1)}
_INSTALL_HINT = "pip install 'thymio-bt[aseba]'"
_TCP_HINT = "write tcp:HOST:PORT with a port from 1 to 65535, e.g. tcp:127.0.0.1:33333"


def signed(word: int) -> int:
    """An Aseba 16-bit word as the signed number it holds."""
    return word - 0x10000 if word >= 0x8000 else word


def tcp_address(device: str) -> tuple[str, int]:
    """The host and port of a ``tcp:HOST:PORT`` device (an IPv6 host in brackets); a UserError with a
    hint when the host is empty or the port is not a number from 1 to 65535 (70000 would wrap).

    >>> tcp_address("tcp:127.0.0.1:33333"), tcp_address("tcp:[::1]:33333")
    (('127.0.0.1', 33333), ('::1', 33333))
    >>> tcp_address("tcp:127.0.0.1:70000")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: --backend-opt device=tcp:127.0.0.1:70000: the port is 70000, above 65535 (hint: ...)
    """
    host, sep, port = device.removeprefix("tcp:").rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    if not sep:
        problem = "no HOST:PORT after tcp:"
    elif not host.strip():
        problem = "no host before the port"
    elif not port:
        problem = "no port after the host"
    elif not (port.isascii() and port.isdigit()):
        problem = f"the port {port!r} is not a number"
    elif not 1 <= int(port) <= 0xFFFF:
        problem = f"the port is {int(port)}, " + ("below 1" if int(port) < 1 else "above 65535")
    else:
        return host, int(port)
    raise UserError(Problem(f"--backend-opt device={device}: {problem}", hint=_TCP_HINT))


class _Link(io.RawIOBase):
    """A link to the robot as the byte stream thymiodirect reads: whole messages only, each judged by
    a :class:`~thymio_bt.backends.real.frames.Gate` first, so that nothing the peer sends can raise
    in thymiodirect's threads (which would end them with a traceback on the user's terminal).

    A failed link (a closed socket, a pulled cable, a message cut short or refused) is recorded in
    ``failed``, which the node reports as RobotLost; ``midway`` says a message has begun and not
    ended, so that a robot silent since then is said to have cut it short, whichever timer ends
    first. Subclasses say how to receive (b"" when nothing came in time), send and close."""

    def __init__(self) -> None:
        self.failed: BaseException | None = None
        self.gate = Gate(REQUIRED)
        self.stopping = False  # set on close: a message being received is given up
        self.midway = False  # a message has begun and not ended: a silence now cuts it short
        self._ready = bytearray()  # whole messages the gate passed, not yet read

    def _receive(self, n: int) -> bytes:
        raise NotImplementedError

    def _send(self, data: Any) -> None:
        raise NotImplementedError

    def _shut(self) -> None:
        raise NotImplementedError

    def read(self, n: int = -1) -> bytes:
        """Up to ``n`` bytes of the messages passed; b"" when none came in time or the link has failed."""
        if n == 0:
            return b""
        if not self._ready and self.failed is None:
            try:
                self._next_message()
            except OSError as exc:  # serial.SerialException is one, and LinkError: the link is gone
                self.failed = exc
        if not self._ready:
            if self.failed is not None:
                time.sleep(0.05)  # realtime: a dead link (thymiodirect's reader would spin), not a sim step
            return b""
        size = len(self._ready) if n < 0 else n
        data = bytes(self._ready[:size])
        del self._ready[:size]
        return data

    def _next_message(self) -> None:
        """Receive one message (or nothing, when none is begun in time) and keep it if the gate passes it."""
        header = self._take(HEADER.size, idle=True)
        if header is None:
            return
        length, source, kind = HEADER.unpack(header)
        if length > MAX_PAYLOAD:
            raise LinkError(
                f"a message {length} bytes long arrived (Aseba's are at most {MAX_PAYLOAD}): "
                "the peer does not speak Aseba, or the line carries garbage"
            )
        payload = self._take(length, idle=False) if length else b""
        self.midway = False
        if payload is not None and self.gate.admits(source, kind, payload):
            self._ready += header + payload

    def _take(self, n: int, idle: bool) -> bytes | None:
        """``n`` bytes; None when ``idle`` and nothing came in time, or on close. LinkError when a
        message stops arriving for :data:`CUT_SHORT` s."""
        data = bytearray()
        since = time.monotonic()
        while len(data) < n and not self.stopping:
            chunk = self._receive(n - len(data))
            if chunk:
                data += chunk
                since = time.monotonic()
                self.midway = True
            elif idle and not data:
                return None
            elif time.monotonic() - since > CUT_SHORT:
                raise LinkError(_CUT)
        return bytes(data) if len(data) == n else None

    def write(self, data: Any) -> int:
        """Send ``data`` (dropped once the link has failed, which ``failed`` says)."""
        if self.failed is None:
            try:
                self._send(data)
            except OSError as exc:
                self.failed = exc
        return len(data)

    def close(self) -> None:
        """Close the link (one already gone is closed)."""
        self.stopping = True
        with contextlib.suppress(OSError):
            self._shut()
        super().close()


class _SocketIO(_Link):
    """A TCP socket; reads time out so thymiodirect's thread can stop."""

    def __init__(self, sock: socket.socket) -> None:
        super().__init__()
        self.sock = sock
        sock.settimeout(0.2)

    def _receive(self, n: int) -> bytes:
        try:
            data = self.sock.recv(n)
        except TimeoutError:
            return b""
        if not data:
            raise ConnectionError("the peer closed the connection")
        return data

    def _send(self, data: Any) -> None:
        self.sock.sendall(data)

    def _shut(self) -> None:
        self.sock.close()


class _SerialIO(_Link):
    """A serial port (pyserial): a USB Thymio, or a pseudo-terminal bridged to one."""

    def __init__(self, port: Any) -> None:
        super().__init__()
        self.port = port

    def _receive(self, n: int) -> bytes:
        return bytes(self.port.read(n))

    def _send(self, data: Any) -> None:
        self.port.write(data)

    def _shut(self) -> None:
        self.port.close()


def _thymiodirect() -> Any:
    return optional_module("thymiodirect.connection", "the 'aseba' backend", _INSTALL_HINT).Connection


def _open_stream(device: str, timeout: float) -> Any:
    """The byte stream to ``device``: ``tcp:HOST:PORT``, a serial port, or "" for the only Thymio on USB."""
    Connection = _thymiodirect()
    if device.startswith("tcp:"):
        try:
            sock = socket.create_connection(tcp_address(device), timeout=timeout)
        except OSError as exc:
            raise UserError(
                Problem(
                    f"cannot reach a Thymio at {device}: {exc.strerror or exc}",
                    hint="start the Aseba Playground or the robot's TCP bridge, or check the port",
                )
            ) from None
        return _SocketIO(sock)
    import serial

    port = device or _only_serial_port(Connection)
    try:
        return _SerialIO(serial.Serial(port, timeout=0.2))
    except (OSError, serial.SerialException) as exc:
        raise UserError(
            Problem(
                f"cannot open the serial port {port}: {exc}",
                hint="plug the Thymio in (its USB cable or dongle); on Linux, join the dialout group",
            )
        ) from None


def _only_serial_port(Connection: Any) -> str:
    ports = Connection.serial_ports()
    if len(ports) != 1:
        found = ", ".join(ports) if ports else "none"
        raise UserError(
            Problem(
                f"found {len(ports)} serial ports that may be a Thymio ({found})",
                hint="name one: --backend-opt device=/dev/ttyACM0 (or device=tcp:HOST:PORT)",
            )
        )
    return str(ports[0])


class AsebaNode(AsebaDevice):
    """One Thymio on an Aseba connection (see the module docstring)."""

    def __init__(
        self, connection: Any, node_id: int, loop: asyncio.AbstractEventLoop, device: str, thread: threading.Thread
    ) -> None:
        self.connection, self.node_id, self.loop, self.device = connection, node_id, loop, device
        self.thread = thread
        self._closed = False
        self._lock = threading.Lock()
        self._travel = (0.0, 0.0)  # units x s, since connecting
        self._last: tuple[float, int, int] | None = None  # the last speeds received, and when
        connection.on_variables_received = self._received

    async def _received(self, node_id: int) -> None:
        """thymiodirect's callback (its event loop's thread): a set of variables arrived."""
        if node_id != self.node_id:
            return
        remote = self.connection.remote_nodes.get(node_id)
        if remote is None:
            return
        left, right = (signed(remote.get_var(name)) for name in SPEED_VARIABLES)
        now = time.monotonic()
        with self._lock:
            if self._last is not None:
                then, last_left, last_right = self._last
                dt = now - then
                self._travel = (
                    self._travel[0] + (left + last_left) / 2.0 * dt,
                    self._travel[1] + (right + last_right) / 2.0 * dt,
                )
            self._last = (now, left, right)

    @classmethod
    def connect(cls, device: str = "", timeout: float = 5.0) -> AsebaNode:
        """Open ``device``, wait (at most ``timeout`` s) for a Thymio to describe itself, and keep its
        proximity and wheel speed variables refreshed. Raises :class:`UserError` with a hint."""
        stream = _open_stream(device, timeout)
        Connection = _thymiodirect()
        made: dict[str, Any] = {}
        ready = threading.Event()

        def serve() -> None:  # a daemon thread: its children (thymiodirect's reader) are daemons too
            loop = asyncio.new_event_loop()
            asyncio.set_event_loop(loop)
            loop.set_exception_handler(lambda loop, context: _failed_in_loop(stream, context))
            connection = Connection(stream, refreshing_rate=REFRESH, discover_rate=DISCOVER, loop=loop)
            connection.set_refreshing_coverage({PROX_VARIABLE, *SPEED_VARIABLES})
            made.update(connection=connection, loop=loop)
            ready.set()
            loop.run_forever()

        thread = threading.Thread(target=serve, name="aseba", daemon=True)
        thread.start()
        try:
            ready.wait(timeout)
            connection = made.get("connection")
            deadline = time.monotonic() + timeout
            if connection is None or not _wait(lambda: bool(connection.remote_node_set), stream, deadline):
                raise _no_thymio(device, timeout, stream, "answered")
            node = cls(connection, next(iter(connection.remote_node_set)), made["loop"], device, thread)
            if not _wait(node._has_variables, stream, time.monotonic() + timeout):
                raise _no_thymio(device, timeout, stream, "sent its variables")
        except BaseException:  # a UserError, or Ctrl-C while waiting: let go of the link
            if made.get("connection") is not None:
                made["connection"].shutdown()
            stream.close()
            raise
        node.set_motors(0, 0)
        return node

    def _has_variables(self) -> bool:
        remote = self.connection.remote_nodes.get(self.node_id)
        return remote is not None and bool(getattr(remote, "var_received", False))

    def _remote(self) -> Any:
        """The robot's variable cache; RobotLost when it has gone silent or the link failed."""
        connection = self.connection
        remote = connection.remote_nodes.get(self.node_id)
        error = getattr(connection.io, "failed", None) or connection.comm_error or connection.input_thread.comm_error
        if error is not None and not isinstance(error, TimeoutError):
            raise RobotLost(f"the connection to the Thymio on {self.device or 'USB'} failed: {error}")
        if remote is None or time.time() - remote.last_msg_time > LOST_AFTER:
            if connection.io.midway:  # our _Link: the reader's timer, as long, may not have ended yet
                raise RobotLost(f"the connection to the Thymio on {self.device or 'USB'} failed: {_CUT}")
            raise RobotLost(f"the Thymio on {self.device or 'USB'} stopped answering (nothing for {LOST_AFTER:g} s)")
        return remote

    def set_motors(self, left: int, right: int) -> None:
        """Send the motor targets without waiting; a broken link is said by the next read."""
        if self._closed:
            return
        try:
            for name, value in zip(TARGET_VARIABLES, (left, right), strict=True):
                self.connection.set_var(self.node_id, name, int(value) & 0xFFFF)
        except (OSError, KeyError):
            pass  # the link is gone: the next read says so (RobotLost)

    def read_prox(self) -> list[int]:
        """The latest ``prox.horizontal`` the robot sent, signed."""
        return [signed(v) for v in self._remote().get_var_array(PROX_VARIABLE)]

    def read_wheel_speeds(self) -> tuple[int, int]:
        """The latest measured wheel speeds the robot sent, signed (units)."""
        remote = self._remote()
        left, right = (signed(remote.get_var(name)) for name in SPEED_VARIABLES)
        return left, right

    def read_wheel_travel(self) -> tuple[float, float]:
        """Each wheel's travel since connecting (units x s), integrated as every refresh arrived."""
        self._remote()  # RobotLost when it has gone silent
        with self._lock:
            return self._travel

    def close(self) -> None:
        """Stop the motors, then the connection's threads and the stream (again: no effect)."""
        if self._closed:
            return
        self.set_motors(0, 0)
        self._closed = True
        connection = self.connection
        connection.io.stopping = True  # a message being received is given up
        connection.shutdown()  # its loops end within a read timeout or a refresh
        connection.input_thread.join(1.0)
        if self.loop.is_running():
            self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(1.0)
        if not self.loop.is_running():
            _finish(self.loop)
        connection.close()


def _wait(condition: Any, stream: _Link, deadline: float) -> bool:
    """Wait until ``condition()`` holds (True), the deadline passes or the link fails (False)."""
    while not condition():
        if stream.failed is not None or time.monotonic() > deadline:
            return False
        time.sleep(0.02)  # realtime: connecting, waiting for the robot
    return True


def _no_thymio(device: str, timeout: float, stream: _Link, what: str) -> UserError:
    """Why connecting to ``device`` failed: the link's failure, a node that is no Thymio, or silence."""
    where = device or "the serial port"
    if stream.failed is not None:
        return UserError(
            Problem(
                f"the link to {where} failed while connecting: {stream.failed}",
                hint="is it a Thymio (or the Playground's robot port)? Nothing else speaks Aseba there",
            )
        )
    refused = "; ".join(stream.gate.refused.values())
    return UserError(
        Problem(
            f"no Thymio {what} on {where} within {timeout:g} s" + (f" ({refused})" if refused else ""),
            hint="another Aseba node answered there: name the Thymio's device or port"
            if refused
            else "switch the robot on; a simulated one needs the Playground running",
        )
    )


def _failed_in_loop(stream: _Link, context: dict[str, Any]) -> None:
    """thymiodirect raised in its event loop (asyncio would print a traceback): the link has failed,
    which the next read says."""
    if stream.failed is None and not stream.stopping:
        error = context.get("exception")
        stream.failed = LinkError(f"thymiodirect failed: {error!r}" if error else str(context.get("message")))


def _finish(loop: asyncio.AbstractEventLoop) -> None:
    """Cancel and await the loop's pending tasks (else: "Task was destroyed"), then close it.

    thymiodirect's refresher stops the loop itself as it ends, so a stop may cut a run short
    (``Event loop stopped before Future completed``): run it again, a few times at most.
    """
    pending = asyncio.all_tasks(loop)
    for task in pending:
        task.cancel()
    if pending:  # gather() of nothing asks for the thread's current loop: after asyncio.run() there is none
        finished = asyncio.gather(*pending, return_exceptions=True)
        for _ in range(5):
            if finished.done():
                break
            with contextlib.suppress(RuntimeError):
                loop.run_until_complete(finished)
    loop.close()


def create_aseba(mission: MissionWorld, seed: int, options: AsebaOptions) -> ThymioRobot:
    """The ``aseba`` backend kind: a Thymio on ``device`` with the mission's robot model (``real``
    unless it names another than the course's)."""
    from thymio_bt.backends import robot_for

    model = robot_for(mission, "aseba")
    node = AsebaNode.connect(options.device, options.timeout)
    robot = ThymioRobot(node, model=model, placed=options.placed)
    robot.latency = options.latency
    return robot
