"""Files the user asked for: ``-`` is standard output, a file is written whole or not at all.

Every command that writes (``--report``, ``sweep --out``, ``schema -o``, ``maze import -o``, ``tree -o``,
``export -o`` (its log writers write a staged file), ``grade``'s outputs and site, pictures) goes through
here, so that the same promises hold everywhere:

- the target is checked *before* any work starts (its folder exists and is writable, and it is not
  a FIFO, a device or a folder), so a 200-run sweep does not fail at the end;
- the text goes to a temporary file in the target's folder, renamed over the target only once
  complete: a full disk or a crash never leaves half a report or a ``*.tmp`` behind;
- the message says which path was actually written;
- a new file's permissions follow the umask (as ``open()``'s would), a replaced file keeps its own;
- a name the command chose by default (:meth:`Output.by_default`: ``tree square.yaml --png`` writes
  ``square.png``) never replaces an existing file: the command is refused before any work, its hint
  saying how to name the file to replace it. Only a name the user gave replaces a file.

Example:

>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> out = Output(folder / "run.json", "--report")  # checked now, before the run
>>> out.write_text('{"status": "SUCCESS"}')  # atomically; "-" would print it instead
>>> sorted(p.name for p in folder.iterdir()), (folder / "run.json").read_text()
(['run.json'], '{"status": "SUCCESS"}')
>>> Output(folder, "--report")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: --report ...: is a folder (hint: give a file name, e.g. .../out.json)
>>> Output(folder / "missing" / "run.json", "--report")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: --report .../run.json: the folder ... does not exist (hint: mkdir -p ...)
>>> Output.by_default(folder / "run.json", "--output")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
thymio_bt.errors.UserError: .../run.json exists, and a file named by default is never replaced (hint: -o ...)
>>> (folder / "run.json").unlink(); folder.rmdir()
"""

from __future__ import annotations

import os
import secrets
import shutil
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from thymio_bt.errors import UserError

STDOUT = "-"


class Output:
    """One file the user named for ``option`` (``-`` = standard output), checked when created."""

    __slots__ = ("path", "option")

    def __init__(self, path: Path | str, option: str, stdout_ok: bool = True) -> None:
        self.path = Path(path)
        self.option = option
        if self.is_stdout and not stdout_ok:
            raise UserError(f"{option} cannot write to standard output (hint: give a file name)")
        if not self.is_stdout:
            check_writable(self.path, option)

    @classmethod
    def by_default(cls, path: Path | str, option: str) -> Output:
        """The output at ``path``, a name the command chose because ``option`` was not given: refused
        when a file (or anything) is there already, since the user never asked to replace it."""
        path = Path(path)
        if path.exists() or path.is_symlink():
            raise UserError(
                f"{path} exists, and a file named by default is never replaced "
                f"(hint: {_short(option)} {path} replaces it; or {_short(option)} OTHER{path.suffix})"
            )
        return cls(path, option, stdout_ok=False)

    @property
    def is_stdout(self) -> bool:
        """Whether the user named ``-``, standard output."""
        return str(self.path) == STDOUT

    def __str__(self) -> str:
        return "standard output" if self.is_stdout else str(self.path)

    def write_text(self, text: str) -> None:
        """Print ``text`` (for ``-``) or replace the file with it atomically."""
        if self.is_stdout:
            sys.stdout.write(text)
            sys.stdout.flush()
            return
        with self.staged() as tmp:
            tmp.write_text(text, encoding="utf-8")

    @contextmanager
    def staged(self) -> Iterator[Path]:
        """A temporary path (same folder and suffix) to write; renamed over the target on success,
        removed on any failure. A write error becomes a UserError naming the target."""
        tmp: Path | None = None
        try:
            fd, name = tempfile.mkstemp(
                prefix=f".{self.path.stem}.", suffix=f".tmp{self.path.suffix}", dir=self.path.parent
            )
            os.close(fd)
            tmp = Path(name)
            yield tmp
            os.chmod(tmp, _mode_for(self.path))
            os.replace(tmp, self.path)
        except OSError as exc:
            raise UserError(f"cannot write {self.path}: {exc.strerror or exc}") from None
        finally:
            if tmp is not None:
                tmp.unlink(missing_ok=True)

    @contextmanager
    def staged_folder(self) -> Iterator[Path]:
        """A path for a new folder beside the target (not made yet: the writer makes it), renamed
        to the target once written, removed on any failure. A target that exists is refused."""
        if self.path.exists():
            raise UserError(f"{self.option} {self.path}: exists (hint: remove it, or give another path)")
        tmp = self.path.with_name(f".{self.path.name}-{secrets.token_hex(4)}-staged")  # no suffix, as the target
        try:
            yield tmp
            os.rename(tmp, self.path)
        except OSError as exc:
            raise UserError(f"cannot write {self.path}: {exc.strerror or exc}") from None
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


def _short(option: str) -> str:
    """``-o`` for ``--output`` (what the commands' help shows first), else the option itself."""
    return "-o" if option == "--output" else option


def _mode_for(path: Path) -> int:
    """The permissions a written file gets: those of the file it replaces, else what the umask
    allows of rw-rw-rw- (as ``open()`` would give; the temporary file itself is private, 0600)."""
    try:
        return path.stat().st_mode & 0o777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def check_writable(path: Path, option: str) -> None:
    """Refuse, before any work, a target that cannot be written or must not be replaced."""
    if path.is_dir():
        raise UserError(
            f"{option} {path}: is a folder (hint: give a file name, e.g. {path / 'out'}{path.suffix or '.json'})"
        )
    if path.exists() and not path.is_file():
        raise UserError(
            f"{option} {path}: not a regular file (a FIFO or a device); refusing to replace it "
            f"(hint: write to a regular file)"
        )
    folder = path.parent
    if not folder.is_dir():
        raise UserError(f"{option} {path}: the folder {folder} does not exist (hint: mkdir -p {folder})")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise UserError(f"{option} {path}: the folder {folder} is not writable (hint: choose another folder)")
    try:  # the system may still refuse (a read-only or virtual file system such as /proc): try it now
        fd, probe = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".probe", dir=folder)
    except OSError as exc:
        raise UserError(
            f"{option} {path}: cannot create a file in {folder}: {exc.strerror or exc} (hint: choose another folder)"
        ) from None
    os.close(fd)
    os.unlink(probe)


def make_folder(path: Path, option: str, example: str) -> None:
    """Make the output folder ``path`` (and its parents) before any work, or refuse it with a
    :class:`UserError` naming ``option``; ``example`` says what to give instead.

    >>> import tempfile
    >>> file = Path(tempfile.mkdtemp()) / "f"; _ = file.write_text("")
    >>> make_folder(file, "--html", "pages/")
    Traceback (most recent call last):
    thymio_bt.errors.UserError: --html .../f: not a folder (hint: give a folder, e.g. pages/)
    """
    if path.exists() and not path.is_dir():
        raise UserError(f"{option} {path}: not a folder (hint: give a folder, e.g. {example})")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"{option} {path}: cannot make the folder: {exc.strerror or exc}") from None
