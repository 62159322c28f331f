"""A fake Thymio II for the Aseba link's tests: a server on 127.0.0.1 that speaks just enough Aseba
(the handshake, the variables, the motor targets), then sends what a test asks for."""

import socket
import struct
import threading

NODE = 1
LIST_NODES, GET_NODE_DESCRIPTION, GET_VARIABLES, SET_VARIABLES = 0xA011, 0xA010, 0xA00B, 0xA00C
DESCRIPTION, VARIABLE_DESCRIPTION, NATIVE_DESCRIPTION, VARIABLES = 0x9000, 0x9001, 0x9003, 0x9005
NODE_PRESENT, DEVICE_INFO = 0x900C, 0x900D
#: a Thymio II's variables the link uses (name, size in words), in memory order
THYMIO = (
    ("prox.horizontal", 7),
    ("motor.left.target", 1),
    ("motor.right.target", 1),
    ("motor.left.speed", 1),
    ("motor.right.speed", 1),
)


def frame(message_id: int, payload: bytes, source: int = NODE) -> bytes:
    """One Aseba message: payload length, source node and type (16-bit little-endian), then the payload."""
    return struct.pack("<HHH", len(payload), source, message_id) + payload


def words(*values: int) -> bytes:
    """16-bit little-endian words."""
    return struct.pack(f"<{len(values)}H", *values)


def text(value: str | bytes) -> bytes:
    """An Aseba string: its length in a byte, then its bytes."""
    data = value.encode() if isinstance(value, str) else value
    return bytes([len(data)]) + data


def conn_open(conn: socket.socket) -> bool:
    """Read what ``conn`` has (waiting at most its timeout); False once the peer closed it."""
    try:
        return conn.recv(4096) != b""
    except TimeoutError:
        return True


class FakeThymio:
    """A Thymio II on a free loopback port. It answers LIST_NODES, GET_NODE_DESCRIPTION (unless
    ``describe`` is false) and GET_VARIABLES (its wheels turn at their targets), and sends
    ``hostile`` once, after the link set ``after`` motor targets (0: at once, in the handshake; 1:
    once connected, since the link stops the motors as its connection's last step and a run or a
    calibration begins: an event, not a time). ``then`` says what it does next: ``serve`` on, fall
    ``silent`` (the connection kept open), or ``close``.

    :attr:`log` records in order every pair of motor targets the link set, and the marks a test puts
    in between (:meth:`mark`): what the robot was told before and after something the test did."""

    def __init__(
        self,
        hostile: bytes = b"",
        after: int = 1,
        then: str = "serve",
        variables: tuple[tuple[str, int], ...] = THYMIO,
        describe: bool = True,
    ) -> None:
        self.hostile, self.after, self.then = hostile, after, then
        self.variables, self.describe = variables, describe
        self.memory = [0] * sum(size for _, size in variables)
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.sent_hostile = threading.Event()
        self.log: list[tuple[str, int, int]] = []  # ("targets", left, right) or (mark, 0, 0), in order
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    @property
    def device(self) -> str:
        """The ``--backend-opt device=`` of this robot."""
        return f"tcp:127.0.0.1:{self.port}"

    def _serve(self) -> None:
        self.server.settimeout(30)
        try:
            conn, _ = self.server.accept()
        except OSError:
            return
        with conn:
            conn.settimeout(0.02)
            try:
                self._talk(conn)
            except OSError:  # the link hung up on us: what some tests want
                return

    def _talk(self, conn: socket.socket) -> None:
        buffer = b""
        while True:
            told = sum(kind == "targets" for kind, _, _ in self.log)
            if self.hostile and told >= self.after and not self.sent_hostile.is_set():
                conn.sendall(self.hostile)
                self.sent_hostile.set()
                if self.then == "close":
                    conn.shutdown(socket.SHUT_WR)  # the link reads the end of the stream...
                    while conn_open(conn):  # ...and what it still sends is read: no reset instead
                        pass
                    return
            try:
                data = conn.recv(4096)
            except TimeoutError:
                continue
            if not data:
                return
            buffer += data
            while len(buffer) >= 6:
                length, _, message_id = struct.unpack("<HHH", buffer[:6])
                if len(buffer) < 6 + length:
                    break
                payload, buffer = buffer[6 : 6 + length], buffer[6 + length :]
                replies = list(self._answer(message_id, payload))
                if not (self.then == "silent" and self.sent_hostile.is_set()):
                    conn.sendall(b"".join(replies))

    def _answer(self, message_id: int, payload: bytes):
        if message_id == LIST_NODES:
            yield frame(NODE_PRESENT, words(5))
        elif message_id == GET_NODE_DESCRIPTION and self.describe:
            yield frame(DESCRIPTION, text("thymio-II") + words(5, 1000, 32, 1000, len(self.variables), 0, 1))
            for name, size in self.variables:
                yield frame(VARIABLE_DESCRIPTION, words(size) + text(name))
            yield frame(NATIVE_DESCRIPTION, text("_system.reboot") + text("reboot") + words(0))
        elif message_id == SET_VARIABLES:  # recorded even when silent: what the link last told the robot
            _, offset, *values = struct.unpack(f"<{len(payload) // 2}H", payload)
            self.memory[offset : offset + len(values)] = values
            if self._has("motor.left.target") and self._has("motor.right.target"):
                self.log.append(("targets", self.target("left"), self.target("right")))
            for side in ("left", "right"):
                if self._has(f"motor.{side}.target") and self._has(f"motor.{side}.speed"):
                    self.memory[self._offset(f"motor.{side}.speed")] = self.memory[self._offset(f"motor.{side}.target")]
        elif message_id == GET_VARIABLES:
            _, offset, count = struct.unpack("<3H", payload)
            yield frame(VARIABLES, words(offset, *self.memory[offset : offset + count]))

    def _has(self, name: str) -> bool:
        return any(other == name for other, _ in self.variables)

    def _offset(self, name: str) -> int:
        offset = 0
        for other, size in self.variables:
            if other == name:
                return offset
            offset += size
        raise KeyError(name)

    def target(self, side: str) -> int:
        """The last motor target the link set on ``side`` (left, right), signed."""
        word = self.memory[self._offset(f"motor.{side}.target")]
        return word - 0x10000 if word >= 0x8000 else word

    def mark(self, label: str) -> None:
        """Put ``label`` in :attr:`log` here: what the link sets from now on comes after it."""
        self.log.append((label, 0, 0))

    def targets_since(self, label: str) -> list[tuple[int, int]]:
        """The motor targets (left, right) the link set after the mark ``label``, in order."""
        at = self.log.index((label, 0, 0))
        return [(left, right) for kind, left, right in self.log[at + 1 :] if kind == "targets"]

    def close(self) -> None:
        """Stop listening and let the connection's thread read what the link sent before it hung up,
        so what this robot recorded (targets, :attr:`log`) is final once the link's process ended:
        without the wait, a stop sent just before exiting could still sit unread in the socket."""
        self.server.close()
        self.thread.join(timeout=10)
