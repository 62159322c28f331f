"""Start a headless Aseba Playground on a world, and stop everything it started.

Traps measured on the Playground 1.6.99 and avoided here: the Playground needs a writable ``HOME``
(it writes a simulated SD card) and, for its D-Bus interface, a session bus of its own; a TCP
connect to probe its port can crash it, so readiness is read from ``/proc/net/tcp`` (the port in
LISTEN). The world's port is best 0: the Playground then binds a port the kernel picks, and
:attr:`Playground.port` is read from its own listening socket. A port chosen beforehand could be
taken by another program in the meantime, and the Playground, failing to bind it, runs on silently
with no port at all while the other program's socket looks like its own.

Nothing it starts outlives a Ctrl-C or a SIGTERM. While a Playground runs, either signal, when
nobody else handles it (a run's own handler does, from its first tick to its last), stops every
Playground first, then raises :class:`PlaygroundInterrupted` (a KeyboardInterrupt: the command
exits 130 or 143). Without that, a SIGTERM while it started (or before the run took over) killed
thymio-bt and left the Playground, its bus and its folder behind. A signal that comes while a
program is being started or stopped waits until it is recorded or gone. Started from the main
thread, the programs also get SIGTERM from the kernel when thymio-bt dies any other way (SIGKILL;
``setpriv --pdeathsig``).

With the Playground installed (``apt-get install aseba dbus``)::

    with Playground.start(world_text) as pg:      # a private bus, a temporary HOME
        pg.bus, pg.port                            # "unix:path=/tmp/.../bus", the robot's port

Example (how readiness is seen: a socket that listens, and the process it belongs to)::

    >>> import socket
    >>> server = socket.create_server(("127.0.0.1", 0))
    >>> port = server.getsockname()[1]
    >>> listening(port), port in listening_ports(os.getpid())
    (True, True)
    >>> server.close()
    >>> listening(port), port in listening_ports(os.getpid())
    (False, False)
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import IO, Any

from thymio_bt.errors import Problem, UserError

PLAYGROUND, DBUS = "asebaplayground", "dbus-daemon"
_INSTALL_HINT = "install the Playground: sudo apt-get install aseba dbus (Debian/Ubuntu)"


def _listeners() -> Iterator[tuple[int, str]]:
    """The TCP sockets in LISTEN, as (port, socket inode), from /proc/net/tcp*: connecting to probe
    them could crash the Playground."""
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            rows = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        for row in rows:
            fields = row.split()
            if fields[3] == "0A":
                yield int(fields[1].rsplit(":", 1)[1], 16), fields[9]


def listening(port: int) -> bool:
    """Whether a socket listens on ``port``."""
    return any(found == port for found, _ in _listeners())


def listening_ports(pid: int) -> list[int]:
    """The TCP ports the process ``pid`` listens on (sorted; none once it ended)."""
    inodes = set()
    with contextlib.suppress(OSError):  # the process ended
        for fd in Path(f"/proc/{pid}/fd").iterdir():
            with contextlib.suppress(OSError):  # a file closed meanwhile
                link = os.readlink(fd)
                if link.startswith("socket:["):
                    inodes.add(link[len("socket:[") : -1])
    return sorted({port for port, inode in _listeners() if inode in inodes})


class PlaygroundInterrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM while a Playground ran and nobody else handled it: raised once every
    Playground is stopped, to end the command as the signal would have.

    >>> PlaygroundInterrupted(signal.SIGTERM).exit_code      # the shell's code for the signal
    143
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        """130 after SIGINT, 143 after SIGTERM (as :class:`~thymio_bt.run.interrupts.Interrupted`)."""
        return 128 + self.signum


#: the signals that would end thymio-bt, and their handlers before any Playground
_SIGNALS: dict[int, Any] = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}


class _Guard:
    """SIGINT and SIGTERM while Playgrounds run (see the module docstring): the live Playgrounds, and
    the signal held back while one is being started or stopped."""

    def __init__(self) -> None:
        self.alive: list[Playground] = []
        self.holding = 0
        self.pending: int | None = None
        self.installed: set[int] = set()

    def handle(self, signum: int, frame: FrameType | None) -> None:
        """The signal handler: stop every Playground and raise, or hold the signal back."""
        if self.holding:  # checked first: a Playground being started may not be recorded yet
            self.pending = self.pending or signum
        elif not self.alive:  # all stopped; another handler put this one back on leaving: be the default
            signal.signal(signum, _SIGNALS[signum])
            self.installed.discard(signum)
            signal.raise_signal(signum)
        else:
            self._fire(signum)

    def _fire(self, signum: int) -> None:
        for playground in list(self.alive):
            playground.stop()
        raise PlaygroundInterrupted(signum)

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Hold signals back for the block; one that came is raised at its end (:meth:`check`)."""
        self.holding += 1
        try:
            yield
        finally:
            self.holding -= 1
        self.check()

    def check(self) -> None:
        """Act on a signal held back, once nothing holds it any more."""
        if self.pending is not None and not self.holding:
            signum, self.pending = self.pending, None
            self._fire(signum)

    def add(self, playground: Playground) -> None:
        """A Playground starts: handle the signals left at their defaults (:meth:`arm`)."""
        self.alive.append(playground)
        self.arm()

    def arm(self) -> None:
        """Handle the signals left at their defaults (from the main thread only): before a Playground's
        folder is made, so that a signal from then on is held, not the default that left it behind."""
        if threading.current_thread() is threading.main_thread():
            for sig, default in _SIGNALS.items():
                if signal.getsignal(sig) == default:
                    signal.signal(sig, self.handle)
                    self.installed.add(sig)

    def remove(self, playground: Playground) -> None:
        """A Playground stopped: after the last one, the defaults again where this handler still is."""
        if playground in self.alive:
            self.alive.remove(playground)
        if not self.alive and threading.current_thread() is threading.main_thread():
            for sig in list(self.installed):
                if signal.getsignal(sig) == self.handle:
                    signal.signal(sig, _SIGNALS[sig])
                    self.installed.discard(sig)


_GUARD = _Guard()


#: the longest path of a Unix socket (the bus's) that Linux takes (``sun_path``: 108 bytes with its NUL)
SOCKET_PATH = 107


def _short_tmp() -> str:
    """The temporary folder, or /tmp when the bus's socket in it would be too long (dbus-daemon then
    fails: "Socket name too long"; a pytest tmp_path as TMPDIR is that long)."""
    base = tempfile.gettempdir()
    room = len(os.fsencode(base)) + len("/thymio-bt-playground-12345678/bus")
    return base if room <= SOCKET_PATH else "/tmp"


def _orphan_proof(command: list[str]) -> list[str]:
    """``command`` made to end with thymio-bt (SIGTERM from the kernel when it dies), from the main
    thread only: the signal follows the thread that started it, and a worker thread may end first."""
    setpriv = shutil.which("setpriv")  # util-linux
    if setpriv is None or threading.current_thread() is not threading.main_thread():
        return command
    return [setpriv, "--pdeathsig", "TERM", "--", *command]


class Playground:
    """A running Playground and its private session bus (see the module docstring)."""

    def __init__(self, folder: Path, processes: list[subprocess.Popen[bytes]], bus: str) -> None:
        self.folder, self.processes, self.bus = folder, processes, bus
        self.port = 0  # the robot's port, once the Playground listens on it

    @classmethod
    def start(cls, world_text: str, timeout: float = 10.0, preload: Path | None = None) -> Playground:
        """Write the world (its robot's port best 0: see the module docstring), start a session bus and
        the Playground on it (with the library ``preload`` loaded into it: :mod:`.enki_fix`); wait
        until the Playground listens on a port, its robot's: :attr:`port`."""
        for program in (PLAYGROUND, DBUS):
            if shutil.which(program) is None:
                raise UserError(
                    Problem(f"the 'playground' backend needs {program}, which is not installed", hint=_INSTALL_HINT)
                )
        playground = None
        try:
            with _GUARD.held():  # the folder made and recorded, or neither
                _GUARD.arm()
                playground = cls(Path(tempfile.mkdtemp(prefix="thymio-bt-playground-", dir=_short_tmp())), [], "")
                playground.bus = f"unix:path={playground.folder / 'bus'}"
                _GUARD.add(playground)
            playground._launch(world_text, timeout, preload)
        except BaseException:
            if playground is not None:
                playground.stop()
            raise
        return playground

    def _launch(self, world_text: str, timeout: float, preload: Path | None) -> None:
        """Start the bus, then the Playground on it, waiting for each."""
        folder = self.folder
        (folder / "home").mkdir()
        (folder / "run").mkdir(mode=0o700)
        world = folder / "world.playground"
        world.write_text(world_text)
        with (folder / "playground.log").open("wb") as log:
            self._spawn([DBUS, "--session", "--nofork", f"--address={self.bus}"], log)
            self._wait(lambda: (folder / "bus").exists(), timeout, "its D-Bus session bus")
            env = {
                **os.environ,
                "HOME": str(folder / "home"),
                "XDG_RUNTIME_DIR": str(folder / "run"),
                "QT_QPA_PLATFORM": "offscreen",
                "DBUS_SESSION_BUS_ADDRESS": self.bus,
            }
            # the library is preloaded into the Playground only (``env`` sets it for the program it starts)
            lead = ["env", f"LD_PRELOAD={preload}"] if preload is not None else []
            self._spawn([*lead, PLAYGROUND, str(world)], log, env=env)
        self._wait(self._listens, timeout, "the robot's port")

    def _listens(self) -> bool:
        """Whether the Playground (started last; ``setpriv`` and ``env`` exec it) listens: its port recorded."""
        ports = listening_ports(self.processes[-1].pid)
        self.port = ports[0] if ports else 0
        return bool(ports)

    def _spawn(self, command: list[str], log: IO[bytes], env: dict[str, str] | None = None) -> None:
        """Start ``command`` in its own session (a Ctrl-C in the terminal is thymio-bt's to handle),
        recorded before a signal is acted on."""
        with _GUARD.held():
            self.processes.append(
                subprocess.Popen(
                    _orphan_proof(command),
                    cwd=self.folder,
                    env=env,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                )
            )

    def _wait(self, ready: object, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not ready():  # type: ignore[operator]
            for process in self.processes:
                if process.poll() is not None:
                    raise UserError(
                        Problem(
                            f"the Aseba Playground stopped while starting (exit {process.returncode}): "
                            f"{self._said()}",  # its folder, and the log in it, are removed next
                            hint=_INSTALL_HINT,
                        )
                    )
            if time.monotonic() > deadline:
                raise UserError(
                    Problem(
                        f"the Aseba Playground did not open {what} within {timeout:g} s: {self._said()}",
                        hint="a loaded machine may need more: --backend-opt timeout=30",
                    )
                )
            time.sleep(0.02)  # realtime: starting a program, not a simulation step

    def _said(self) -> str:
        """The last lines the bus and the Playground wrote, for an error message."""
        try:
            lines = (self.folder / "playground.log").read_text(errors="replace").strip().splitlines()
        except OSError:
            lines = []
        return " / ".join(lines[-3:])[-400:] or "it wrote nothing"

    def stop(self) -> None:
        """Stop every process it started (by PID, the Playground first) and remove its folder; a
        signal meanwhile (a second Ctrl-C) waits until that is done. Again: no effect."""
        with _GUARD.held():
            for process in reversed(self.processes):
                if process.poll() is None:
                    process.send_signal(signal.SIGTERM)
                    try:
                        process.wait(3.0)
                    except subprocess.TimeoutExpired:
                        process.kill()
                        process.wait()
            self.processes.clear()
            shutil.rmtree(self.folder, ignore_errors=True)
            _GUARD.remove(self)

    def __enter__(self) -> Playground:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
