"""Ctrl-C and SIGTERM as a request that the run loop honours at its next tick.

A signal arriving in the middle of a physics step or of a write must not leave a half-updated world,
a robot driving on, or a report unwritten. So the handler only notes the signal; :class:`~thymio_bt.
runner.Run` and :func:`~thymio_bt.run.sweep.sweep` look at it once per tick (or per result), stop the
robot, and end with status ``FAILURE`` and code ``INTERRUPTED``, their report and log complete.

A tick that never ends (a plugin's endless loop inside ``step()``, a blocking call) never reaches
that check. So a second signal raises :class:`Interrupted` (a :class:`KeyboardInterrupt`) at once,
out of whatever the main thread is running: the run loop catches it, stops the motors, and ends the
run the same way (code ``INTERRUPTED``, the stuck node named, report and log complete); outside a
run loop it ends the command with the first signal's exit code.

Example (a Ctrl-C before the first tick: the run ticks once, then ends):

>>> import os, signal
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> with Interrupts() as interrupts:
...     os.kill(os.getpid(), signal.SIGINT)  # noted by the handler, not raised
...     result = Run(load_mission("maze_bonus")).run(interrupts=interrupts)
>>> result.status, result.code, result.ticks, result.reason
('FAILURE', 'INTERRUPTED', 1, 'interrupted by SIGINT at 0.0 s')
>>> interrupts.name, interrupts.exit_code  # the CLI exits with that code
('SIGINT', 130)
"""

from __future__ import annotations

import signal
import threading
from types import FrameType, TracebackType
from typing import Any

#: the signals handled, with the shell's exit codes for them (128 + the signal's number)
SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(KeyboardInterrupt):
    """A second signal, raised from the handler into the code the main thread was running.

    >>> exc = Interrupted(signal.SIGTERM)
    >>> exc.name, exc.exit_code
    ('SIGTERM', 143)
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def name(self) -> str:
        """The name of the signal that ended the command first (``"SIGINT"``, ``"SIGTERM"``)."""
        return signal.Signals(self.signum).name

    @property
    def exit_code(self) -> int:
        """130 after SIGINT, 143 after SIGTERM."""
        return 128 + self.signum


class Interrupts:
    """While entered (in the main thread), notes SIGINT/SIGTERM in :attr:`signal` instead of dying."""

    def __init__(self) -> None:
        self.signal: int | None = None
        self._previous: dict[int, Any] = {}

    @property
    def name(self) -> str:
        """The signal's name (``"SIGINT"``, ``"SIGTERM"``), or "" before any."""
        return signal.Signals(self.signal).name if self.signal else ""

    @property
    def exit_code(self) -> int:
        """130 after SIGINT, 143 after SIGTERM, as a shell reports a process those signals ended."""
        return 128 + (self.signal or 0)

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.signal is not None:  # asked twice: stop now, whatever is running (a stuck tick)
            raise Interrupted(self.signal)  # the first signal's: it decides the exit code
        self.signal = signum

    def __enter__(self) -> Interrupts:
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)
        self._previous.clear()
