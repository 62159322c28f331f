"""Ctrl-C and SIGTERM as a request that the run loop honours at its next tick.

A signal arriving in the middle of a physics step or of a write must not leave a half-updated world,
a robot driving on, or a report unwritten. So the handler only notes the signal; :class:`~thymio_bt.
runner.Run` and :func:`~thymio_bt.run.sweep.sweep` look at it once per tick (or per result), stop the
robot, and end with status ``FAILURE`` and code ``INTERRUPTED``, their report and log complete.

A tick that never ends (a plugin's endless loop inside ``step()``, a blocking call) never reaches
that check. So when the main thread has not looked at the signal within a grace period (:data:`GRACE`
seconds, or ``THYMIO_BT_INTERRUPT_GRACE``), or when a second signal comes first, :class:`Interrupted`
(a :class:`KeyboardInterrupt`) is raised at once, out of whatever the main thread is running: the run
loop catches it, stops the motors, and ends the run the same way (code ``INTERRUPTED``, the stuck node
named, report and log complete); outside a run loop it ends the command with the first signal's exit
code. One SIGTERM thus ends a stuck run before a process manager's SIGKILL (Docker's comes 10 s later),
which would leave a real Thymio driving its last command.

Example (a Ctrl-C before the first tick: the run ticks once, then ends):

>>> import os, signal
>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> with Interrupts() as interrupts:
...     os.kill(os.getpid(), signal.SIGINT)  # noted by the handler, not raised
...     result = Run(load_mission("maze_bonus")).run(interrupts=interrupts)
>>> result.status, result.code, result.ticks, result.reason
(<RunStatus.FAILURE: 'FAILURE'>, <FailureCode.INTERRUPTED: 'INTERRUPTED'>, 1, 'interrupted by SIGINT at 0.0 s')
>>> interrupts.name, interrupts.exit_code  # the CLI exits with that code
('SIGINT', 130)
"""

from __future__ import annotations

import _thread
import contextlib
import math
import os
import signal
import threading
from collections.abc import Mapping
from types import FrameType, TracebackType
from typing import Any

from thymio_bt.errors import UserError

#: the signals handled, with the shell's exit codes for them (128 + the signal's number)
SIGNALS = (signal.SIGINT, signal.SIGTERM)

#: seconds the main thread has, after the first signal, to look at it before its tick is broken into
GRACE = 2.0

#: the environment variable that sets the grace period (seconds, >= 0; 0 breaks in at once)
GRACE_VARIABLE = "THYMIO_BT_INTERRUPT_GRACE"


def grace_setting(environ: Mapping[str, str] = os.environ) -> float:
    """The grace period the environment sets (:data:`GRACE_VARIABLE`), else :data:`GRACE`.

    >>> grace_setting({}), grace_setting({GRACE_VARIABLE: "0.5"})
    (2.0, 0.5)
    >>> grace_setting({GRACE_VARIABLE: "2s"})
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: THYMIO_BT_INTERRUPT_GRACE=2s: expected seconds, a number >= 0 (hint: ...)
    """
    text = environ.get(GRACE_VARIABLE, "").strip()
    if not text:
        return GRACE
    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not (math.isfinite(seconds) and seconds >= 0):
        raise UserError(f"{GRACE_VARIABLE}={text}: expected seconds, a number >= 0 (hint: {GRACE_VARIABLE}={GRACE:g})")
    return seconds


class Interrupted(KeyboardInterrupt):
    """A tick broken into, raised from the handler into the code the main thread was running: by a
    second signal, or ``grace`` seconds after the first one (when the main thread never looked at it).

    >>> exc = Interrupted(signal.SIGTERM)
    >>> exc.name, exc.exit_code, exc.how
    ('SIGTERM', 143, 'a second signal stopped it')
    >>> Interrupted(signal.SIGINT, grace=2.0).how
    'stopped 2 s after the signal'
    """

    def __init__(self, signum: int, grace: float | None = None) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        self.grace = grace

    @property
    def name(self) -> str:
        """The name of the signal that ended the command first (``"SIGINT"``, ``"SIGTERM"``)."""
        return signal.Signals(self.signum).name

    @property
    def exit_code(self) -> int:
        """130 after SIGINT, 143 after SIGTERM."""
        return 128 + self.signum

    @property
    def how(self) -> str:
        """What broke in, in a report's words."""
        return "a second signal stopped it" if self.grace is None else f"stopped {self.grace:g} s after the signal"


class Interrupts:
    """While entered (in the main thread), notes SIGINT/SIGTERM in :attr:`signal` instead of dying.

    Reading :attr:`signal` (or :attr:`name`, :attr:`exit_code`) in the main thread tells the handler that
    the main thread is not stuck: the tick it was in has ended, so nothing is broken into. ``grace``
    defaults to :func:`grace_setting`, read when entered (a :class:`UserError` there when it is wrong)."""

    def __init__(self, grace: float | None = None) -> None:
        self._grace_given = grace
        #: the grace period (s); until entered, the default's (the environment is read when entered)
        self.grace = GRACE if grace is None else grace
        self._signal: int | None = None
        self._previous: dict[int, Any] = {}
        self._main: int | None = None  # the main thread's id, once the handlers are ours
        self._heard: Any = None  # the lock the watchdog waits on (a _thread lock) while armed
        self._watch_lock = _thread.allocate_lock()  # held by the watchdog while it breaks in
        self._late = False  # the watchdog broke in: the next signal is its own
        self._closing = False

    @property
    def signal(self) -> int | None:
        """The first signal's number, or None; read in the main thread, it disarms the watchdog."""
        if self._heard is not None and threading.get_ident() == self._main:
            self._disarm()
        return self._signal

    @property
    def name(self) -> str:
        """The signal's name (``"SIGINT"``, ``"SIGTERM"``), or "" before any."""
        signum = self.signal
        return signal.Signals(signum).name if signum else ""

    @property
    def exit_code(self) -> int:
        """130 after SIGINT, 143 after SIGTERM, as a shell reports a process those signals ended."""
        return 128 + (self.signal or 0)

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self._signal is None:
            self._signal = signum
            self._arm()
            return
        late, self._late = self._late, False
        if late and self._closing:
            return  # the watchdog's signal, as the command leaves the handled stretch: too late
        # asked twice, or not heard in time: stop now, whatever is running (a stuck tick), once
        self._disarm()
        raise Interrupted(self._signal, self.grace if late else None)  # the first signal decides the code

    def _disarm(self) -> None:
        """Tell the watchdog not to break in (it ends at once)."""
        heard, self._heard = self._heard, None
        if heard is not None:
            with contextlib.suppress(RuntimeError):  # released already (the handler ran in between)
                heard.release()

    def _arm(self) -> None:
        """Start the watchdog: it breaks in unless the main thread reads :attr:`signal` within the grace.
        It is a bare ``_thread``: started from the signal handler, it must not take ``threading``'s
        locks, which the interrupted main thread may be holding."""
        if self._main is None:
            return
        heard = _thread.allocate_lock()
        heard.acquire()
        self._heard = heard
        _thread.start_new_thread(self._watch, (heard,))

    def _watch(self, heard: Any) -> None:
        if heard.acquire(timeout=self.grace):  # realtime: the tick is stuck, only the wall clock moves
            return  # the main thread looked at the signal in time
        with self._watch_lock:
            if self._heard is heard and not self._closing and self._main is not None and self._signal:
                self._late = True
                _break_in(self._main, self._signal)

    def __enter__(self) -> Interrupts:
        self._closing = False
        if self._grace_given is None:
            self.grace = grace_setting()
        if threading.current_thread() is threading.main_thread():
            self._main = threading.get_ident()
            for sig in SIGNALS:
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self._closing = True
        with self._watch_lock:  # a watchdog breaking in right now has sent its signal: ours ignores it
            self._heard = None
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)
        self._previous.clear()
        self._main = None


def _break_in(thread: int, signum: int) -> None:
    """Deliver ``signum`` to ``thread`` (the main one): a blocking call there (a sleep, a lock wait)
    returns early, so the handler runs; without ``pthread_kill`` (Windows), Python's own simulation."""
    kill = getattr(signal, "pthread_kill", None)
    if kill is not None:
        kill(thread, signum)
    else:
        _thread.interrupt_main(signal.Signals(signum))
