"""A bounded look at a bag before a library reads it: what ``rosbags`` would trust and should not.

A rosbag2 folder may hold a FIFO where its ``.mcap`` should be (reading it blocks for ever), and an
MCAP chunk declares the size it decompresses to, which the reader allocates before it checks
anything: a 1 kB file may claim 1.5 GiB. So every file of a bag is checked to be a regular file, and
the MCAP records are walked by their headers alone (opcode and length, a seek each; a chunk's
declared size read from its first 24 bytes), refusing a chunk past :data:`CHUNK_LIMIT` or a bag
whose chunks add up past :data:`TOTAL_LIMIT`, before any of it is decompressed. A chunk may also lie:
``rosbags`` decompresses it whole before comparing sizes (3.1 GB for 48 kB of zstd declaring 460 kB),
so a compressed chunk is first unpacked here as a stream, 1 MiB at a time and counted, never kept,
and refused as soon as it passes what it declares.

>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> bomb = folder / "bomb.mcap"
>>> chunk = struct.pack("<QQQI", 0, 0, 3 << 29, 0) + struct.pack("<I", 4) + b"zstd" + struct.pack("<Q", 0)
>>> _ = bomb.write_bytes(MAGIC + bytes([CHUNK]) + struct.pack("<Q", len(chunk)) + chunk)
>>> check_bag(bomb)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: .../bomb.mcap: a chunk of the bag unpacks to 1536 MiB, past the 64 MiB ...
>>> bomb.unlink(); folder.rmdir()
"""

from __future__ import annotations

import io
import stat
import struct
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any, BinaryIO, cast

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import LIMITS, MB

#: an MCAP file's first 8 bytes
MAGIC = b"\x89MCAP0\r\n"
#: MCAP record opcodes this walk acts on
FOOTER, CHUNK = 0x02, 0x06
#: the most one chunk may unpack to (thymio-bt writes chunks of about 1 MiB)
CHUNK_LIMIT = 64 * MB
#: the most all chunks of a bag may unpack to: a log's own cap
TOTAL_LIMIT = LIMITS["log"]
#: the most files a rosbag2 folder may hold (thymio-bt writes two: metadata.yaml and one .mcap)
MAX_FILES = 64


def check_bag(path: Path) -> None:
    """Refuse a bag (an ``.mcap`` file or a rosbag2 folder) that would hang or exhaust memory."""
    files = _bag_files(path) if path.is_dir() else [path]
    total = 0
    for file in files:
        if file.suffix == ".mcap":
            total += _mcap_unpacked_size(file)
            if total > TOTAL_LIMIT:
                raise _refuse(file, f"the bag unpacks to more than {TOTAL_LIMIT // MB} MiB, a log's cap")


def _bag_files(folder: Path) -> list[Path]:
    """The files of a rosbag2 folder, each checked to be a regular file (never opened otherwise)."""
    entries = []
    for count, entry in enumerate(sorted(folder.iterdir()), 1):
        if count > MAX_FILES:
            raise _refuse(folder, f"more than {MAX_FILES} files: not a bag thymio-bt wrote")
        mode = entry.lstat().st_mode
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file (a FIFO, a device, a socket or a link)"
            raise _refuse(entry, f"{entry.name} in the bag is {kind}")
        entries.append(entry)
    return entries


def _mcap_unpacked_size(file: Path) -> int:
    """What the chunks of one MCAP file declare they unpack to, walking record headers only."""
    size = file.stat().st_size
    total = 0
    with open(file, "rb") as stream:
        if stream.read(len(MAGIC)) != MAGIC:
            return 0  # not MCAP: the reader says so in its own words
        offset = len(MAGIC)
        try:
            while offset + 9 <= size:
                stream.seek(offset)
                opcode, length = struct.unpack("<BQ", stream.read(9))
                if opcode == FOOTER:
                    break
                if opcode == CHUNK and length >= 40:
                    total += _chunk_size(file, stream, offset + 9 + length)
                offset += 9 + length
        except struct.error:  # cut short: the reader says so in its own words
            pass
    return total


def _chunk_size(file: Path, stream: BinaryIO, end: int) -> int:
    """The size a chunk (its header at the stream's position) unpacks to, checked without keeping it."""
    unpacked = struct.unpack("<QQQI", stream.read(28))[2]
    if unpacked > CHUNK_LIMIT:
        raise _refuse(
            file,
            f"a chunk of the bag unpacks to {unpacked // MB} MiB, past the {CHUNK_LIMIT // MB} MiB "
            "a log chunk may hold",
        )
    (name_length,) = struct.unpack("<I", stream.read(4))
    compression = stream.read(min(name_length, 16))
    stream.seek(stream.tell() + name_length - len(compression))
    (packed,) = struct.unpack("<Q", stream.read(8))
    opener = _STREAMS.get(compression)
    if opener is not None:
        source = _Slice(stream, min(packed, end - stream.tell()))
        real = 0
        try:
            with opener(source) as reader:
                while piece := reader.read(MB):
                    real += len(piece)
                    if real > unpacked:
                        break
        except Exception:  # a damaged stream: the reader refuses it in its own words, bounded
            return unpacked
        if real > unpacked:
            raise _refuse(file, f"a {compression.decode()} chunk unpacks to more than the {unpacked} bytes it declares")
    return unpacked


class _Slice(io.RawIOBase):
    """``length`` bytes of ``stream`` from its position, as a file a decompressor reads."""

    def __init__(self, stream: BinaryIO, length: int) -> None:
        self.stream, self.left = stream, max(length, 0)

    def readable(self) -> bool:
        """It is read."""
        return True

    def readinto(self, buffer: Any) -> int:
        """Fill ``buffer`` from the slice; 0 at its end."""
        data = self.stream.read(min(len(buffer), self.left))
        self.left -= len(data)
        buffer[: len(data)] = data
        return len(data)


def _zstd(source: io.RawIOBase) -> Any:
    import zstandard

    return zstandard.ZstdDecompressor().stream_reader(cast(IO[bytes], source), read_across_frames=True)


def _lz4(source: io.RawIOBase) -> Any:
    import lz4.frame

    return lz4.frame.open(source, "rb")


#: compressions MCAP names, and how to read one as a stream (none: the records are stored as they are)
_STREAMS: dict[bytes, Callable[[io.RawIOBase], Any]] = {b"zstd": _zstd, b"lz4": _lz4}


def _refuse(path: Path, message: str) -> UserError:
    return UserError(Problem(message, str(path), hint="bags are written by thymio-bt run --log FILE.mcap"))
