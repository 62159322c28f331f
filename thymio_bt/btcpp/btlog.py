"""Runs as BT.CPP's Groot2 log (``.btlog``, FileLogger2's layout), for Groot2's log replay.

Little endian: ``BTCPP4-FileLogger2``, a protocol byte (1), the tree's BT.CPP XML (i32 length, then
the text, nodes with their ``_uid``), the start time (i64 µs), then one 9-byte record per status
change: µs since the start (6 bytes), the node's uid (u16), its new status (u8: 0 IDLE, 1 RUNNING,
2 SUCCESS, 3 FAILURE). Times are simulated, so the same run gives the same file; the start time is
0 (1970 in Groot2's clock). :func:`read_btlog` reads one back (``thymio-bt view run.btlog``), with
:func:`with_poses` the robot from a log of the same run.

Example:

>>> import tempfile
>>> from pathlib import Path
>>> from thymio_bt.testing import recorded
>>> with tempfile.TemporaryDirectory() as folder:
...     _ = recorded("square", log_path=f"{folder}/run.btlog")
...     data = Path(f"{folder}/run.btlog").read_bytes()
>>> data[: len(MAGIC)], data[len(MAGIC)]
(b'BTCPP4-FileLogger2', 1)
>>> xml_length = struct.unpack_from("<i", data, len(MAGIC) + 1)[0]
>>> records = data[len(MAGIC) + 5 + xml_length + 8 :]
>>> len(records) % 9, struct.unpack_from("<HB", records, 6)  # first: MoveDistance (uid 3) RUNNING
(0, (3, 1))
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import IO, TYPE_CHECKING

from thymio_bt.enums import NODE_STATUSES, STATUS_LETTER
from thymio_bt.errors import Problem, UserError
from thymio_bt.logs import LogFormat
from thymio_bt.logs.entries import LogEnd, LogHeader, TickRecord, TreeNode

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording

MAGIC = b"BTCPP4-FileLogger2"
PROTOCOL = 1
#: the format, found through the ``thymio_bt.log_formats`` entry point (pyproject.toml) as any format
#: from outside the package is: ``logs`` sits below BT.CPP's room and names none of it
FORMAT = LogFormat(
    "btlog",
    "BT.CPP's FileLogger2 file, for Groot2's log replay (node status changes, no robot)",
    (".btlog",),
    "thymio_bt.btcpp.btlog:BtlogWriter",
    "thymio_bt.btcpp.btlog:read_btlog",
)
#: a log's status letter -> BT.CPP's NodeStatus
STATUS = {"-": 0, "R": 1, "S": 2, "F": 3}


class BtlogWriter:
    """Writes a run as a Groot2 log: one record per node status change."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file: IO[bytes] | None = path.open("wb")
        except OSError as exc:
            raise UserError(f"cannot write the log {path}: {exc}") from None
        self._uids: dict[str, int] = {}
        self._last: dict[str, str] = {}

    def header(self, header: LogHeader) -> None:
        """Write the file's head: the magic, the protocol and the tree as BT.CPP XML (its nodes numbered as
        BT.CPP numbers them: the records name those uids)."""
        from thymio_bt.btcpp.export import btcpp_tree
        from thymio_bt.plan.registry import default_registry

        assert self._file is not None
        nodes = header["tree"]
        tree = btcpp_tree(nodes, default_registry())
        self._uids = {n["path"]: tree.uids[n["uid"]] for n in nodes if n["uid"] in tree.uids}
        self._last = {n["path"]: "-" for n in nodes}
        xml = tree.xml.encode("utf-8")
        self._file.write(MAGIC + struct.pack("<Bi", PROTOCOL, len(xml)) + xml + struct.pack("<q", 0))

    def tick(self, record: TickRecord) -> None:
        """Write a record for each node whose status changed since the last tick."""
        assert self._file is not None
        stamp = round(record["t"] * 1e6)
        records = []
        for path, status in record.get("nodes", {}).items():
            if self._last.get(path) != status and path in self._uids:
                self._last[path] = status
                records.append(stamp.to_bytes(6, "little") + struct.pack("<HB", self._uids[path], STATUS[status]))
        self._file.write(b"".join(records))

    def end(self, end: LogEnd) -> None:
        """Nothing to add: a Groot2 log holds status changes only."""

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._file is not None:
            self._file.close()
            self._file = None


#: BT.CPP's NodeStatus -> a log's status letter (4, SKIPPED, is shown as IDLE: the node did not run)
LETTER = {**{code: STATUS_LETTER[name] for code, name in enumerate(NODE_STATUSES)}, 4: STATUS_LETTER["INVALID"]}
#: the root's last status letter -> how the run ended (RUNNING or IDLE: the log does not say)
ENDED = {STATUS_LETTER[name]: name for name in ("SUCCESS", "FAILURE")}
#: the tick rate a Groot2 log's record times are numbered at (thymio-bt's: it does not store one)
TICK_HZ = 10
RECORD = 9
#: the most elements a log's tree may expand to: BT.CPP's uids are 16 bits
MAX_NODES = 65535
NO_POSES = "this .btlog holds node statuses only, no robot (add --poses LOG, a log of the same run with poses)"


def read_btlog(path: Path) -> Recording:
    """Read a Groot2 log back: the tree from its XML (node paths as thymio-bt names them), and a sample
    per record time, each with every node's status then (``nodes``) and no pose. A file cut mid-record
    is read up to its last whole record (``header["damaged_at"]``: the byte where reading stopped).

    >>> import tempfile
    >>> from thymio_bt.testing import recorded
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = recorded("square", log_path=f"{folder}/run.btlog")
    ...     recording = read_btlog(Path(f"{folder}/run.btlog"))
    >>> first = recording.samples[0]
    >>> first["t"], first["tick"], first["pose"], first["nodes"]["four sides/side/MoveDistance"]
    (0.0, 1, None, 'R')
    """
    from thymio_bt.inputs.reading import read_bytes
    from thymio_bt.logs.recording import Recording
    from thymio_bt.maze import Maze

    data = read_bytes(path, "log")
    head = len(MAGIC) + 5
    if not data.startswith(MAGIC) or len(data) < head:
        raise UserError(
            Problem(
                "not a Groot2 log: it does not start with BTCPP4-FileLogger2",
                str(path),
                hint="a .btlog is written by thymio-bt run --log FILE.btlog or BT.CPP's FileLogger2",
            )
        )
    protocol, xml_length = struct.unpack_from("<Bi", data, len(MAGIC))
    if protocol != PROTOCOL or xml_length < 0 or head + xml_length + 8 > len(data):
        raise UserError(
            Problem(
                f"damaged Groot2 log head (protocol {protocol}, tree of {xml_length} bytes)",
                str(path),
                hint="only the records may be cut: write the log again",
            )
        )
    tree = btlog_tree(data[head : head + xml_length], str(path))
    paths = {node["uid"]: node["path"] for node in tree}
    statuses = dict.fromkeys(paths.values(), "-")
    header = LogHeader(mission=path.stem, tick_hz=TICK_HZ, tree=tree, note=NO_POSES)
    recording = Recording(maze=Maze(), mission=path.stem, header=header)
    start = head + xml_length + 8
    whole = start + (len(data) - start) // RECORD * RECORD
    last_stamp = -1
    for at in range(start, whole, RECORD):
        stamp = int.from_bytes(data[at : at + 6], "little")
        uid, status = struct.unpack_from("<HB", data, at + 6)
        if status not in LETTER or stamp < last_stamp:
            whole = at
            break
        if stamp != last_stamp:
            t = round(stamp / 1e6, 6)
            recording.samples.append({"t": t, "tick": round(t * TICK_HZ) + 1, "pose": None})
            last_stamp = stamp
        if uid in paths:
            statuses[paths[uid]] = LETTER[status]
        recording.samples[-1]["nodes"] = dict(statuses)
    if whole != len(data):
        header["damaged_at"] = whole
    last = recording.samples[-1] if recording.samples else {"t": 0.0, "tick": 0}
    root = ENDED.get(statuses[tree[0]["path"]], "UNKNOWN") if tree else "UNKNOWN"
    recording.end = LogEnd(
        status="INCOMPLETE" if whole != len(data) else root,
        sim_time=last["t"],
        final_pose=None,
        ticks=last["tick"],  # the tick of the last record: a .btlog stores status changes, not ticks
        records=(whole - start) // RECORD,
    )
    return recording


def btlog_tree(xml: bytes, file: str) -> list[TreeNode]:
    """The tree of a Groot2 log's XML as a log header's ``tree`` (pre-order, BT.CPP's ``_uid``s): each
    node's path is its ancestors' names and its own, as thymio-bt names a tree's nodes. An element
    without a ``name`` is named for its tag, as BT.CPP does, but a do-while loop's scaffolding (the
    unnamed elements inside a ``_thymio="repeat"``) is no node; a ``<SubTree>`` is the root of its
    ``<BehaviorTree>``, whose nodes follow it; an element with BT.CPP's pre/post-conditions is under a
    ``bt_conditions`` node of its name, as ``thymio-bt run mission.xml`` builds it."""
    from thymio_bt.btcpp.runtime.control import CONDITION_ATTRS
    from thymio_bt.btcpp.xml_tree import Element, element_roots

    roots = element_roots(xml, file, "log", hint="the log's tree is damaged")
    trees = {t.attrs.get("ID"): t for t in (roots[0].children if roots else []) if t.tag == "BehaviorTree"}
    main = roots[0].attrs.get("main_tree_to_execute") if roots else None
    if main not in trees:
        main = next(iter(trees), None)
    if main is None:
        raise UserError(Problem("the Groot2 log's tree has no <BehaviorTree>", file, hint="write the log again"))
    nodes: list[TreeNode] = []
    visits: list[Element] = []

    def visit(element: Element, parent: int | None, prefix: str, scaffold: bool, depth: int) -> None:
        uid = element.attrs.get("_uid")
        name = element.attrs.get("name")
        visits.append(element)  # a subtree used twice by a subtree used twice... doubles at each level
        if len(visits) > MAX_NODES:
            raise UserError(Problem(f"the Groot2 log's tree expands to more than {MAX_NODES} nodes", file))
        if depth > 64 or not (uid or "").isdigit():
            raise UserError(Problem(f"the Groot2 log's tree is damaged at <{element.tag}>", file, element.line))
        children = trees[element.attrs.get("ID")].children if element.tag == "SubTree" else element.children
        if element.tag == "SubTree" and element.attrs.get("ID") not in trees:
            raise UserError(Problem(f"the Groot2 log's tree has no <BehaviorTree> {element.attrs.get('ID')}", file))
        skipped = (name is None and scaffold) or element.tag == "SubTree"  # not a node of thymio-bt's tree
        if skipped:
            path, node = prefix, parent
        else:
            name = name or element.tag
            if any(k in CONDITION_ATTRS for k in element.attrs):
                prefix = f"{prefix}/{name}" if prefix else name
            path, node = (f"{prefix}/{name}" if prefix else name), int(uid or 0)
            nodes.append(TreeNode(uid=node, path=path, name=name, kind=element.tag, parent=parent))
        inner = element.attrs.get("_thymio") == "repeat" or (scaffold and skipped)
        for child in children:
            visit(child, node, path, inner, depth + 1)

    for element in trees[main].children:
        visit(element, None, "", False, 0)
    return nodes


def with_poses(statuses: Recording, poses: Recording) -> Recording:
    """One run from two logs of it: the tree and its statuses from ``statuses`` (a Groot2 log's), the
    robot, the maze, the signals and the events from ``poses`` (a log of the same run with poses),
    aligned by simulated time: each tick of ``poses`` gets the statuses of the last record at or before it."""
    from dataclasses import replace

    idle = dict.fromkeys((n["path"] for n in statuses.header["tree"]), "-")
    samples: list[TickRecord] = []
    at = -1
    for sample in poses.samples:
        while at + 1 < len(statuses.samples) and statuses.samples[at + 1]["t"] <= sample["t"] + 1e-9:
            at += 1
        samples.append({**sample, "nodes": statuses.samples[at]["nodes"] if at >= 0 else idle})
    header: LogHeader = {**poses.header, "tree": statuses.header["tree"]}
    return replace(poses, samples=samples, header=header)
