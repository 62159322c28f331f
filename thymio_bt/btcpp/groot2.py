"""Watch a running mission in Groot2: BT.CPP's Groot2Publisher protocol (version 2) over ZeroMQ.

``thymio-bt run MISSION --realtime 1 --groot2 [PORT]`` serves, on 127.0.0.1 only, a REP socket on
PORT (default 1667, as BT.CPP) and a PUB socket on PORT+1. Every request's first frame is 6 bytes
(u8 protocol 2, u8 type, u32 id); every reply's first frame echoes them and adds the tree's 16-byte
id. Served: ``T`` the tree as ``thymio-bt tree --btcpp`` writes it (ports, ``_uid``s,
TreeNodesModel), ``S`` the status of every node (u16 uid, u8 status; a node reset to IDLE reads
10 + the status it had), ``B`` the blackboard as msgpack (``{"MainTree": {key: value}}``; every
blackboard when no name is asked), ``D`` the hooks (none), and ``A``/``X`` (remove or disable
hooks: nothing to do). Breakpoints and recording answer ``error``, as a
publisher without them does. Needs ``thymio-bt[groot2]`` (pyzmq, msgpack).

Example (a run served on a free port, then asked for its statuses as Groot2 asks):

>>> import socket, zmq
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> with socket.socket() as probe:
...     _ = probe.bind(("127.0.0.1", 0))
...     port = probe.getsockname()[1]
>>> server = Groot2Server(port)
>>> result = Run(load_mission("square")).run(on_tick=server)  # with --realtime 1 from the CLI
>>> groot2 = server.context.socket(zmq.REQ)
>>> groot2.setsockopt(zmq.RCVTIMEO, 2000)
>>> _ = groot2.connect(f"tcp://127.0.0.1:{port}")
>>> groot2.send(struct.pack("<BBI", PROTOCOL, ord("S"), 7))  # protocol, request type, request id
>>> head, statuses = groot2.recv_multipart()
>>> head[:6] == struct.pack("<BBI", 2, ord("S"), 7), len(head)  # echoed, then the tree's id
(True, 22)
>>> [struct.unpack_from("<HB", statuses, i) for i in range(0, len(statuses), 3)]  # (uid, 2 = SUCCESS)
[(1, 2), (2, 2), (3, 2), (4, 2)]
>>> groot2.close()
>>> server.close()
"""

from __future__ import annotations

import json
import struct
import threading
import uuid
from typing import TYPE_CHECKING, Any

from thymio_bt.enums import NODE_STATUSES
from thymio_bt.errors import UserError
from thymio_bt.logs.entries import jsonable

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from thymio_bt.logs.recording import WatchedRun

PROTOCOL = 2
DEFAULT_PORT = 1667
_STATUS = {name: code for code, name in enumerate(NODE_STATUSES)}


def _zmq() -> tuple[Any, Any]:
    try:
        import msgpack
        import zmq
    except ImportError:
        raise UserError("the Groot2 monitor needs pyzmq and msgpack (hint: pip install 'thymio-bt[groot2]')") from None
    return zmq, msgpack


class Groot2Server:
    """An ``on_tick`` hook that serves the tree and its statuses to Groot2 from a background thread."""

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1") -> None:
        self.zmq, self.msgpack = _zmq()
        self.context = self.zmq.Context()
        self.server = self.context.socket(self.zmq.REP)
        self.publisher = self.context.socket(self.zmq.PUB)
        for socket in (self.server, self.publisher):
            socket.setsockopt(self.zmq.LINGER, 0)
        try:
            self.server.bind(f"tcp://{host}:{port}")
            self.publisher.bind(f"tcp://{host}:{port + 1}")
        except self.zmq.ZMQError as exc:
            self.context.destroy()
            raise UserError(
                f"cannot serve Groot2 on {host}:{port}-{port + 1}: {exc} (hint: --groot2 with another port)"
            ) from None
        self.server.setsockopt(self.zmq.RCVTIMEO, 100)
        self.tree_id = uuid.uuid4().bytes
        self.lock = threading.Lock()
        self.xml = ""
        self.uids: list[tuple[int, Behaviour]] = []
        self.idle = b""  # the status records of the nodes BT.CPP counts that we do not run
        self.status = b""
        self.blackboard: dict[str, Any] = {}
        self.running = True
        self.thread = threading.Thread(target=self._serve, name="groot2", daemon=True)

    def __call__(self, run: WatchedRun) -> None:
        """Take the tree's statuses and the blackboard after a tick (the first call maps the tree's
        nodes to their BT.CPP uids and starts serving)."""
        if not self.uids:
            from thymio_bt.btcpp.export import mission_btcpp, mission_nodes
            from thymio_bt.logs.entries import walk

            tree = mission_btcpp(run.mission)  # as `tree --btcpp` writes it: ports, settings, BT.CPP's uids
            self.xml = tree.xml
            nodes, _, _ = mission_nodes(run.mission)
            # the plan and the built tree walk in the same pre-order; a <SubTree> node shows its root's
            # status; a do-while loop's scaffolding (no node of ours) is said IDLE, as every node's
            # status is in BT.CPP's reply.
            # strict=False: a display hook must not end the run if a tree were built otherwise than planned
            for plan_node, node in zip(nodes, walk(run.root), strict=False):
                if plan_node["uid"] in tree.wrappers:
                    self.uids.append((tree.wrappers[plan_node["uid"]], node))
                if plan_node["uid"] in tree.uids:
                    self.uids.append((tree.uids[plan_node["uid"]], node))
            ours = {uid for uid, _ in self.uids}
            self.idle = b"".join(struct.pack("<HB", uid, 0) for uid in range(1, tree.size + 1) if uid not in ours)
            self.previous = {uid: 0 for uid, _ in self.uids}
            self.thread.start()
        import py_trees

        records = []
        for uid, node in self.uids:
            status = _STATUS[node.status.name]
            shown = 10 + self.previous[uid] if status == 0 and self.previous[uid] else status
            self.previous[uid] = status
            records.append(struct.pack("<HB", uid, shown))
        storage = py_trees.blackboard.Blackboard.storage
        with self.lock:
            self.status = b"".join(records) + self.idle
            self.blackboard = {"MainTree": {k.lstrip("/"): jsonable(v) for k, v in storage.items()}}

    def _serve(self) -> None:
        zmq = self.zmq
        while self.running:
            try:
                frames = self.server.recv_multipart()
            except zmq.Again:
                continue
            except zmq.ZMQError:
                return
            self.server.send_multipart(self._answer(frames))

    def _answer(self, frames: list[bytes]) -> list[bytes]:
        """The reply to one request: a malformed one (a short header, a names frame that is not UTF-8,
        anything this code fails on) is answered ``error``, and the server goes on serving."""
        try:
            return self._reply(frames)
        except Exception:  # a request this server cannot read: say so, keep the thread alive
            return [b"error"]

    def _reply(self, frames: list[bytes]) -> list[bytes]:
        """The reply to a well-formed request (``error`` for an unknown protocol or kind)."""
        head = frames[0]
        if len(head) != 6:
            return [b"error"]
        protocol, kind = head[0], chr(head[1])
        reply = [head + self.tree_id]
        with self.lock:
            if protocol != PROTOCOL:
                return [b"error"]
            if kind == "T":
                reply.append(self.xml.encode())
            elif kind == "S":
                reply.append(self.status)
            elif kind == "B":
                names = [n for n in frames[1].decode().split(";") if n] if len(frames) > 1 else []
                shown = {n: self.blackboard.get(n, {}) for n in names} if names else self.blackboard
                reply.append(self.msgpack.packb(shown))
            elif kind == "D":
                reply.append(json.dumps([]).encode())
            elif kind not in ("A", "X"):
                return [b"error"]
        return reply

    def close(self) -> None:
        """Stop serving and release the ports."""
        self.running = False
        if self.thread.is_alive():
            self.thread.join(timeout=1.0)
        self.context.destroy(linger=0)
