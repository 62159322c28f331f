"""Aseba messages as they arrive on a link, checked before thymiodirect sees them.

thymiodirect 0.1.2 trusts its peer: a message it cannot decode kills its reader thread with a
traceback, one from a node that never said it was present (or a description out of order) raises
in its event loop, and a ``VARIABLES`` message past the node's memory silently resizes its copy. A
link (:class:`~thymio_bt.backends.real.aseba.AsebaNode`'s) therefore cuts the byte stream into whole
messages itself and lets a :class:`Gate` judge each one:

- passed: what thymiodirect handles, from a node that announced itself, in the order of the handshake;
- dropped: what it may ignore (another node's or another program's traffic, a message type it does
  not use, a description nobody asked for again);
- refused with :class:`LinkError` (the run ends: the robot is lost, with this reason): a message
  longer than Aseba allows (:data:`MAX_PAYLOAD`, garbage on the line), one that does not decode,
  variables past the node's memory;
- a node without the variables the link needs is no Thymio: all it sends is dropped, and
  :attr:`Gate.refused` says why (for the error that no Thymio answered).

Example (a node that announces itself, then one that never did, then a device UUID of 3 bytes)::

    >>> gate = Gate({"prox.horizontal": 7})
    >>> gate.admits(1, NODE_PRESENT, b"\\x05\\x00"), gate.admits(9, VARIABLES, b"\\x00\\x00\\x05\\x00")
    (True, False)
    >>> gate.admits(1, DEVICE_INFO, b"\\x01\\x03abc")
    Traceback (most recent call last):
    ...
    thymio_bt.backends.real.frames.LinkError: node 1 sent a malformed message (0x900d, 5 bytes: ...)
"""

from __future__ import annotations

import struct
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from thymio_bt.errors import ThymioBtError

#: the longest payload an Aseba message has (bytes): ASEBA_MAX_EVENT_ARG_SIZE, 258 words, in Aseba's
#: ``common/consts.h``; a longer one is not Aseba (garbage, or another protocol on the port)
MAX_PAYLOAD = 2 * 258
#: a message's header: its payload's length, its source node and its type, 16-bit little-endian each
HEADER = struct.Struct("<HHH")
#: a node's variables are addressed by 16-bit words
MEMORY = 0x10000
#: nodes listened to at most; more on one link is garbage, not a robot
MAX_NODES = 16

DESCRIPTION, VARIABLE_DESCRIPTION, EVENT_DESCRIPTION, NATIVE_DESCRIPTION = 0x9000, 0x9001, 0x9002, 0x9003
VARIABLES, EXECUTION_STATE_CHANGED, NODE_PRESENT, DEVICE_INFO = 0x9005, 0x900A, 0x900C, 0x900D
#: below this, a message is a user event (``emit`` in the robot's program)
FIRST_ASEBA_ID = 0x8000


class LinkError(ConnectionError, ThymioBtError):
    """The peer sent what no Thymio sends: the link cannot be trusted any more."""


@dataclass
class _Node:
    """What a node has told about itself so far."""

    counts: tuple[int, int, int] | None = None  # its description's variables, events, native functions
    variables: int = 0  # how many of each were described since
    events: int = 0
    natives: int = 0
    names: dict[str, int] = field(default_factory=dict)  # variable sizes by name
    size: int = 0  # words of variables described so far


class Gate:
    """Judges each message of a link: pass, drop or :class:`LinkError` (see the module docstring).

    ``required``: the variables (name: size in words) a node must have. A node without them is no
    Thymio: its last variable description is dropped (so thymiodirect never polls it), and so is all
    it sends next; :attr:`refused` says why, by node.
    """

    def __init__(self, required: Mapping[str, int]) -> None:
        self.required = dict(required)
        self.nodes: dict[int, _Node] = {}
        self.refused: dict[int, str] = {}

    def admits(self, source: int, kind: int, payload: bytes) -> bool:
        """Whether thymiodirect may see this message (True) or it is dropped (False); LinkError when it
        shows the peer is no Aseba node (or the line carries garbage)."""
        if source in self.refused:
            return False
        if kind == NODE_PRESENT:
            self._decode(source, kind, payload)
            if source not in self.nodes and len(self.nodes) < MAX_NODES:
                self.nodes[source] = _Node()
            return source in self.nodes
        node = self.nodes.get(source)
        if node is None:
            return False  # a node that never announced itself: another program's traffic on a switch
        if kind in (DEVICE_INFO, EXECUTION_STATE_CHANGED) or kind < FIRST_ASEBA_ID:
            self._decode(source, kind, payload)
            return True
        if kind == DESCRIPTION:
            return self._description(node, source, payload)
        if kind in (VARIABLE_DESCRIPTION, EVENT_DESCRIPTION, NATIVE_DESCRIPTION):
            return self._part(node, source, kind, payload)
        if kind == VARIABLES:
            return self._variables(node, source, payload)
        return False  # a message type thymiodirect does not use (errors, breakpoints, requests)

    def _description(self, node: _Node, source: int, payload: bytes) -> bool:
        if node.counts is not None:
            return False  # described already (another program asked): its variables must not count twice
        message = self._decode(source, DESCRIPTION, payload)
        node.counts = (message.num_named_var, message.num_local_events, message.num_native_fun)
        return node.counts[0] > 0 or self._has_required(node, source)

    def _part(self, node: _Node, source: int, kind: int, payload: bytes) -> bool:
        """A variable, event or native function of the description: after it, never more than it said."""
        if node.counts is None:
            return False  # the end of a description another program asked for, before we listened
        message = self._decode(source, kind, payload)
        wanted_variables, wanted_events, wanted_natives = node.counts
        if kind == EVENT_DESCRIPTION:
            node.events += 1
            return node.events <= wanted_events
        if kind == NATIVE_DESCRIPTION:
            node.natives += 1
            return node.natives <= wanted_natives
        if node.variables >= wanted_variables:
            return False
        node.variables += 1
        node.size += message.var_size
        node.names[message.var_name] = message.var_size
        if node.size > MEMORY:
            raise LinkError(f"node {source} described {node.size} words of variables (Aseba addresses {MEMORY})")
        return node.variables < wanted_variables or self._has_required(node, source)

    def _has_required(self, node: _Node, source: int) -> bool:
        """Whether the node, all its variables described, has the required ones; refused if not."""
        for name, size in self.required.items():
            if node.names.get(name) != size:
                self.refused[source] = f"node {source} is no Thymio II: it has no variable {name} of {size} words"
                return False
        return True

    def _variables(self, node: _Node, source: int, payload: bytes) -> bool:
        if node.counts is None or node.variables < node.counts[0]:
            return False  # an answer to another program, before thymiodirect knows where they go
        message = self._decode(source, VARIABLES, payload)
        end = message.var_offset + len(message.var_data)
        if end > node.size:
            raise LinkError(f"node {source} sent variables up to word {end} of its {node.size}")
        return True

    @staticmethod
    def _decode(source: int, kind: int, payload: bytes) -> Any:
        """The message as thymiodirect decodes it; LinkError when that fails (it would, in its thread)."""
        from thymiodirect.message import Message

        message = Message(kind, source, payload)
        try:
            message.decode()
        except (IndexError, ValueError) as exc:  # UnicodeDecodeError is a ValueError
            raise LinkError(
                f"node {source} sent a malformed message (0x{kind:04x}, {len(payload)} byte"
                f"{'' if len(payload) == 1 else 's'}: {exc})"
            ) from None
        return message
