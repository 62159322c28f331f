"""Runs as BT.CPP's Groot2 log (``.btlog``, FileLogger2's layout), for Groot2's log replay.

Little endian: ``BTCPP4-FileLogger2``, a protocol byte (1), the tree's BT.CPP XML (i32 length, then
the text, nodes with their ``_uid``), the start time (i64 µs), then one 9-byte record per status
change: µs since the start (6 bytes), the node's uid (u16), its new status (u8: 0 IDLE, 1 RUNNING,
2 SUCCESS, 3 FAILURE). Times are simulated, so the same run gives the same file; the start time is
0 (1970 in Groot2's clock).

Example:

>>> import tempfile
>>> from pathlib import Path
>>> from thymio_bt.logs.recording import Recorder
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> with tempfile.TemporaryDirectory() as folder:
...     recorder = Recorder(log_path=f"{folder}/run.btlog")
...     _ = recorder.finish(Run(load_mission("square")).run(on_tick=recorder))
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
from typing import IO

from thymio_bt.errors import UserError
from thymio_bt.logs.records import LogEnd, LogHeader, TickRecord

MAGIC = b"BTCPP4-FileLogger2"
PROTOCOL = 1
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
        from thymio_bt.mission import default_registry
        from thymio_bt.mission.btcpp import btcpp_tree

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
