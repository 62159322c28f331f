"""The messages between the grader's side of a run and a submission's confined process: a 4-byte
length, then that many bytes: a JSON object (the orders, a run's start and end, a slow tick), or a
tick's frame (one each way per tick): a fixed binary part (:data:`OBSERVATION`, :data:`REPLY` and
its drive commands) and, only when there is any, a JSON object for the rare rest (the entity
requests, events, the running node, a failure). A binary frame costs a tenth of the JSON one to
write and to read (``benchmarks/README.md``).

What the other side sends is read as untrusted: a message over :data:`MAX_MESSAGE` bytes, one that
is not a JSON object, a frame of the wrong size, a drive command that is not finite, or silence
past a deadline is a :class:`WireError` (the run fails with it); nothing is evaluated.

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

A tick's reply, written by the submission's process and read, checked, by the grader::

    >>> read_reply(reply_frame("RUNNING", [(0.1, 0.0)], {}))
    ('RUNNING', [(0.1, 0.0)], {})
    >>> read_reply(reply_frame("FAILURE", [], {"f": ["root/Bad", "FAILED", "no wall"]}))
    ('FAILURE', [], {'f': ['root/Bad', 'FAILED', 'no wall']})
    >>> read_reply(reply_frame("RUNNING", [(float("nan"), 0.0)], {}))
    Traceback (most recent call last):
    ...
    thymio_bt.grade.wire.WireError: the submission's process sent a drive command that is not two finite numbers
"""

from __future__ import annotations

import json
import math
import select
import socket
import struct
import threading
import time
from typing import Any

from thymio_bt.enums import NODE_STATUSES
from thymio_bt.errors import ThymioBtError

#: the largest message either side may send (bytes): a tick's is ~200, a run's last (its node
#: statistics) a few kB
MAX_MESSAGE = 4 << 20
_LENGTH = struct.Struct(">I")
#: a tick's observation, grader to submission: tag ``O``, the clock, whether the robot exists,
#: whether its odometry and its proximity ranges are known, the odometry ``x, y, yaw``, the 7 ranges
#: (``SENSOR_NAMES`` order, inf: nothing in range), the measured and the commanded ``linear,
#: angular``, the collisions so far; then the served entity requests as JSON, if any
OBSERVATION = struct.Struct("<cd???3d7d4dQ")
#: a tick's reply head, submission to grader: tag ``R``, the root's status (:data:`STATUSES`), how
#: many drive commands (:data:`DRIVE` each) follow; then a JSON object of the rest, if any
REPLY = struct.Struct("<cBH")
DRIVE = struct.Struct("<2d")
#: at most this many drive commands a tick (each is applied, as a tree in the grader's process would)
MAX_DRIVES = 16
STATUSES = NODE_STATUSES
_STATUS_CODES = {name: code for code, name in enumerate(STATUSES)}


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
        self.send_frame(_json(message))

    def send_frame(self, data: bytes) -> None:
        """Send one message as it is written (a tick's frame, or JSON)."""
        try:
            with self._sending:
                self.sock.sendall(_LENGTH.pack(len(data)) + data)
        except OSError as exc:
            raise WireError(f"the submission's process is gone ({exc.strerror or exc})") from None

    def receive(self, deadline: float | None) -> dict[str, Any]:
        """The next JSON object, waiting at most until ``deadline`` (``time.monotonic()``; None:
        for ever)."""
        return read_json(self.receive_frame(deadline))

    def receive_frame(self, deadline: float | None) -> bytes:
        """The next message as it was written (see :func:`is_json`), waiting at most until
        ``deadline``."""
        head = self._take(_LENGTH.size, deadline)
        (size,) = _LENGTH.unpack(head)
        if size > MAX_MESSAGE:
            raise WireError(f"the submission's process sent a message of {size} bytes (at most {MAX_MESSAGE})")
        return self._take(size, deadline)

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


def _json(message: Any) -> bytes:
    return json.dumps(message, separators=(",", ":")).encode()


def is_json(frame: bytes) -> bool:
    """Whether a message is a JSON object (else a tick's frame: they start with a letter tag)."""
    return frame[:1] == b"{"


def read_json(frame: bytes) -> dict[str, Any]:
    """A message read as a JSON object (anything else: :class:`WireError`)."""
    try:
        message = json.loads(frame)
    except (ValueError, RecursionError):
        raise WireError("the submission's process sent a message that is not JSON") from None
    if not isinstance(message, dict):
        raise WireError("the submission's process sent a message that is not a JSON object")
    return message


def observation_frame(values: tuple[Any, ...], served: list[list[Any]]) -> bytes:
    """A tick's observation: :data:`OBSERVATION`'s fields after its tag, and the served requests."""
    return OBSERVATION.pack(b"O", *values) + (_json(served) if served else b"")


def read_observation(frame: bytes) -> tuple[tuple[Any, ...], list[list[Any]]]:
    """A tick's observation (from the grader): its fields after the tag, and the served requests."""
    fixed = frame[: OBSERVATION.size]
    rest = frame[OBSERVATION.size :]
    return OBSERVATION.unpack(fixed)[1:], json.loads(rest) if rest else []


def reply_frame(status: str, drives: list[tuple[float, float]], rest: dict[str, Any]) -> bytes:
    """A tick's reply: the root's status, the drive commands given this tick, the rest (JSON)."""
    head = REPLY.pack(b"R", _STATUS_CODES[status], len(drives))
    return b"".join([head, *(DRIVE.pack(*drive) for drive in drives), _json(rest) if rest else b""])


def read_reply(frame: bytes) -> tuple[str, list[tuple[float, float]], dict[str, Any]]:
    """A tick's reply (untrusted): its status, drive commands (finite numbers) and the rest (a JSON
    object, not checked further); a frame of another shape is a :class:`WireError`."""
    if len(frame) < REPLY.size:
        raise WireError("the submission's process sent a tick's reply that is too short")
    tag, code, count = REPLY.unpack_from(frame)
    end = REPLY.size + count * DRIVE.size
    if tag != b"R" or code >= len(STATUSES) or len(frame) < end:
        raise WireError("the submission's process sent a tick's reply of the wrong shape")
    drives = list(DRIVE.iter_unpack(frame[REPLY.size : end]))
    if not all(math.isfinite(a) and math.isfinite(b) for a, b in drives):
        raise WireError("the submission's process sent a drive command that is not two finite numbers")
    return STATUSES[code], drives, read_json(frame[end:]) if len(frame) > end else {}
