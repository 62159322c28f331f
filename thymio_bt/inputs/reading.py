"""Reading the files a user names: regular files only, up to a size, each refusal one clear message.

A mission, maze, world, include or log given as a folder, a FIFO (which would block for ever) or a
device (``/dev/zero``, which never ends) is refused at once, before it is opened; so is a file past
the cap of its kind, which keeps memory and time bounded whatever is passed in.

Example::

    >>> from thymio_bt.data import MISSIONS
    >>> read_text(MISSIONS / "square.yaml", "mission").splitlines()[0]
    '# yaml-language-server: $schema=../schema/mission.schema.json'
    >>> read_text("/dev/zero", "mission")                    # it would never end: refused unopened
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: /dev/zero: the mission /dev/zero is not a regular file ...
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from thymio_bt.errors import Problem, UserError

KB, MB = 1 << 10, 1 << 20
#: the largest file of each kind read (bytes). The course's biggest mission is 2 kB, its biggest maze
#: 3 kB (a 300 x 300 grid maze is 0.5 MB and loads in 2 s), its biggest Gazebo world 75 kB; a
#: 256 kB mission takes about 3 s to check. A run's JSON-lines log is about 1 kB per tick.
LIMITS = {
    "mission": 256 * KB,
    "include": 256 * KB,
    "assignment": 256 * KB,
    "plugin": 1 * MB,
    "maze": 1 * MB,
    "world": 8 * MB,
    "log": 512 * MB,
    "report": 512 * MB,
}


def read_bytes(path: str | Path, what: str) -> bytes:
    """The content of the regular file ``path`` of kind ``what`` (a key of :data:`LIMITS`)."""
    path = Path(path)
    limit = LIMITS[what]
    info = check_regular(path, what)
    if info.st_size > limit:
        raise _too_big(path, what, limit)
    try:
        with open(path, "rb") as file:
            data = file.read(limit + 1)  # it may have grown since stat
    except OSError as exc:
        raise UserError(Problem(f"cannot read the {what} {path}: {exc.strerror or exc}", str(path))) from None
    if len(data) > limit:
        raise _too_big(path, what, limit)
    return data


def check_regular(path: Path, what: str, folder_ok: bool = False) -> os.stat_result:
    """Refuse, without opening it, a ``path`` that is missing, a FIFO, a device or a socket (or a
    folder, unless ``folder_ok``: a rosbag2 bag is one)."""
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise UserError(
            Problem(
                f"{what} file not found: {path}",
                str(path),
                hint="check the path; relative paths start from the current directory",
            )
        ) from None
    except OSError as exc:
        raise UserError(Problem(f"cannot read the {what} {path}: {exc.strerror or exc}", str(path))) from None
    if stat.S_ISDIR(info.st_mode) and not folder_ok:
        raise UserError(
            Problem(f"the {what} {path} is a folder, not a file", str(path), hint=f"name a {what} file inside it")
        )
    if not (stat.S_ISREG(info.st_mode) or stat.S_ISDIR(info.st_mode)):
        raise UserError(
            Problem(
                f"the {what} {path} is not a regular file (a FIFO, a device or a socket)",
                str(path),
                hint=f"save the {what} to a file first",
            )
        )
    return info


def read_text(path: str | Path, what: str) -> str:
    """:func:`read_bytes` decoded as UTF-8 (a binary file is a clear error, with the byte's place)."""
    data = read_bytes(path, what)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise UserError(
            Problem(
                f"the {what} is not UTF-8 text (byte 0x{data[exc.start]:02x})",
                str(path),
                line,
                exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1,
                hint=f"is this a {what} file? save it as UTF-8 text",
            )
        ) from None


def _too_big(path: Path, what: str, limit: int) -> UserError:
    """The error for a file of kind ``what`` past its cap of ``limit`` bytes."""
    cap = f"{limit // MB} MB" if limit >= MB else f"{limit // KB} kB"
    return UserError(
        Problem(
            f"the {what} {path} is larger than the {cap} cap for {what} files",
            str(path),
            hint=f"a {what} this large is not one thymio-bt can use; check the file",
        )
    )
