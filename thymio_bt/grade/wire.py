"""The messages between the grader's side of a run and a submission's confined process: a 4-byte
length, then that many bytes of JSON (an object). One message each way per tick.

What the other side sends is read as untrusted: a message over :data:`MAX_MESSAGE` bytes, one that
is not a JSON object, or silence past a deadline is a :class:`WireError` (the run fails with it);
nothing is evaluated. JSON keeps ``inf`` readings (``Infinity``) and is what the rest of the grader
speaks; a tick's round trip (an observation out, a reply in) costs about 40 µs of encoding and
system calls (``benchmarks/README.md``).

Example (both ends in this process)::

    >>> import socket
    >>> a, b = socket.socketpair()
    >>> left, right = Link(a), Link(b)
    >>> left.send({"t": 0.1, "s": [float("inf"), 0.05]})
    >>> right.receive(deadline=None)
    {'t': 0.1, 's': [inf, 0.05]}
    >>> a.sendall(b"\\xff\\xff\\xff\\xff")       # a length no honest side sends
    >>> right.receive(deadline=None)
    Traceback (most recent call last):
    ...
    thymio_bt.grade.wire.WireError: the submission's process sent a message of 4294967295 bytes (at most 4194304)
"""

from __future__ import annotations

import json
import select
import socket
import struct
import threading
import time
from typing import Any

from thymio_bt.errors import ThymioBtError

#: the largest message either side may send (bytes): a tick's is ~200, a run's last (its node
#: statistics) a few kB
MAX_MESSAGE = 4 << 20
_LENGTH = struct.Struct(">I")


class WireError(ThymioBtError):
    """The other side broke the protocol: closed, too slow, too big, or not JSON."""


class Deadline(WireError):
    """The other side did not answer before the deadline."""


class Link:
    """One end of a connected stream socket carrying length-prefixed JSON objects."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self._buffer = bytearray()
        self._sending = threading.Lock()  # a watchdog thread may send too

    def send(self, message: dict[str, Any]) -> None:
        """Send one JSON object (a closed peer: :class:`WireError`)."""
        data = json.dumps(message, separators=(",", ":")).encode()
        try:
            with self._sending:
                self.sock.sendall(_LENGTH.pack(len(data)) + data)
        except OSError as exc:
            raise WireError(f"the submission's process is gone ({exc.strerror or exc})") from None

    def receive(self, deadline: float | None) -> dict[str, Any]:
        """The next JSON object, waiting at most until ``deadline`` (``time.monotonic()``; None:
        for ever)."""
        head = self._take(_LENGTH.size, deadline)
        (size,) = _LENGTH.unpack(head)
        if size > MAX_MESSAGE:
            raise WireError(f"the submission's process sent a message of {size} bytes (at most {MAX_MESSAGE})")
        body = self._take(size, deadline)
        try:
            message = json.loads(body)
        except (ValueError, RecursionError):
            raise WireError("the submission's process sent a message that is not JSON") from None
        if not isinstance(message, dict):
            raise WireError("the submission's process sent a message that is not a JSON object")
        return message

    def _take(self, size: int, deadline: float | None) -> bytes:
        while len(self._buffer) < size:
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([self.sock], [], [], left)[0]:
                    raise Deadline("the submission's process did not answer in time")
            try:
                data = self.sock.recv(max(1 << 16, size - len(self._buffer)))
            except OSError as exc:
                raise WireError(f"the submission's process is gone ({exc.strerror or exc})") from None
            if not data:
                raise WireError("the submission's process ended")
            self._buffer += data
        taken = bytes(self._buffer[:size])
        del self._buffer[:size]
        return taken

    def close(self) -> None:
        """Close this end."""
        self.sock.close()
