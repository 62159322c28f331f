"""Start a headless Aseba Playground on a world, and stop everything it started.

Traps measured on the Playground 1.6.99 and avoided here: the Playground needs a writable ``HOME``
(it writes a simulated SD card) and, for its D-Bus interface, a session bus of its own; a TCP
connect to probe its port can crash it, so readiness is read from ``/proc/net/tcp`` (the port in
LISTEN); it binds every interface, so the port is a free one.

With the Playground installed (``apt-get install aseba dbus``)::

    with Playground.start(world_text, port) as pg:      # a private bus, a temporary HOME
        pg.bus                                           # "unix:path=/tmp/.../bus"

Example (the port it is given, and how its readiness is seen)::

    >>> port = free_port()
    >>> 1024 <= port < 65536, listening(port)
    (True, False)
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path

from thymio_bt.errors import Problem, UserError

PLAYGROUND, DBUS = "asebaplayground", "dbus-daemon"
_INSTALL_HINT = "install the Playground: sudo apt-get install aseba dbus (Debian/Ubuntu)"


def free_port() -> int:
    """A TCP port nobody listens on now (the Playground binds it a moment later)."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def listening(port: int) -> bool:
    """Whether a socket listens on ``port`` (read from /proc/net/tcp*: connecting could crash the Playground)."""
    want = f":{port:04X}"
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            rows = Path(table).read_text().splitlines()[1:]
        except OSError:
            continue
        if any(row.split()[1].endswith(want) and row.split()[3] == "0A" for row in rows):
            return True
    return False


class Playground:
    """A running Playground and its private session bus (see the module docstring)."""

    def __init__(self, folder: Path, processes: list[subprocess.Popen[bytes]], bus: str, port: int) -> None:
        self.folder, self.processes, self.bus, self.port = folder, processes, bus, port

    @classmethod
    def start(cls, world_text: str, port: int, timeout: float = 10.0) -> Playground:
        """Write the world, start a session bus and the Playground on it; wait for the robot's port."""
        for program in (PLAYGROUND, DBUS):
            if shutil.which(program) is None:
                raise UserError(
                    Problem(f"the 'playground' backend needs {program}, which is not installed", hint=_INSTALL_HINT)
                )
        folder = Path(tempfile.mkdtemp(prefix="thymio-bt-playground-"))
        (folder / "home").mkdir()
        (folder / "run").mkdir(mode=0o700)
        world = folder / "world.playground"
        world.write_text(world_text)
        bus = f"unix:path={folder / 'bus'}"
        log = (folder / "playground.log").open("wb")
        processes: list[subprocess.Popen[bytes]] = []
        playground = cls(folder, processes, bus, port)
        try:
            processes.append(
                subprocess.Popen(
                    [DBUS, "--session", "--nofork", f"--address={bus}"],
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                )
            )
            playground._wait(lambda: (folder / "bus").exists(), timeout, "its D-Bus session bus")
            env = {
                **os.environ,
                "HOME": str(folder / "home"),
                "XDG_RUNTIME_DIR": str(folder / "run"),
                "QT_QPA_PLATFORM": "offscreen",
                "DBUS_SESSION_BUS_ADDRESS": bus,
            }
            processes.append(
                subprocess.Popen(
                    [PLAYGROUND, str(world)],
                    cwd=folder,
                    env=env,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                )
            )
            playground._wait(lambda: listening(port), timeout, f"the robot's port {port}")
        except BaseException:
            playground.stop()
            raise
        return playground

    def _wait(self, ready: object, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not ready():  # type: ignore[operator]
            for process in self.processes:
                if process.poll() is not None:
                    raise UserError(
                        Problem(
                            f"the Aseba Playground stopped while starting (exit {process.returncode}); "
                            f"its output: {self.folder / 'playground.log'}",
                            hint=_INSTALL_HINT,
                        )
                    )
            if time.monotonic() > deadline:
                raise UserError(
                    Problem(
                        f"the Aseba Playground did not open {what} within {timeout:g} s",
                        hint=f"its output: {self.folder / 'playground.log'}",
                    )
                )
            time.sleep(0.02)  # realtime: starting a program, not a simulation step

    def stop(self) -> None:
        """Stop every process it started (by PID, the Playground first) and remove its folder."""
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

    def __enter__(self) -> Playground:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
