"""Threads a run leaves behind: a plugin that starts a thread that is not a daemon (and never ends
it) would keep the process alive after its report, as Python waits for such threads when it exits.

:func:`end_despite_threads`, called as a command is about to exit, arranges that the process ends
anyway: if those threads are still running once the interpreter shuts down (after a short grace), it
warns, naming them, and ends the process with the command's exit code.

Example (nothing is left here, so nothing is arranged)::

    >>> leftover_threads()
    []
    >>> end_despite_threads(0)
    False
"""

from __future__ import annotations

import os
import sys
import threading
import time
from pathlib import Path

#: how long (wall-clock seconds) the leftover threads get to end by themselves at shutdown
GRACE = 1.0


def leftover_threads() -> list[threading.Thread]:
    """The live threads, other than the main thread, that are not daemons: Python waits for them."""
    main = threading.main_thread()
    return [t for t in threading.enumerate() if t is not main and not t.daemon and t.is_alive()]


def end_despite_threads(code: int) -> bool:
    """If non-daemon threads are alive, arrange for the interpreter's shutdown to end the process with
    ``code`` when they are still alive then (after :data:`GRACE`), with a warning naming them; whether
    something was arranged."""
    if not leftover_threads() or not _thymio_bt_process():
        return False  # a command run inside another program (a test's CliRunner) leaves it its exit
    # threading's own exit hooks run before it joins the threads: the last moment to end anyway
    threading._register_atexit(_end_now, code)  # type: ignore[attr-defined]
    return True


def _thymio_bt_process() -> bool:
    """Whether this process is the ``thymio-bt`` command (its script, ``python -m thymio_bt`` or
    ``python -m thymio_bt.cli``)."""
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    return Path(sys.argv[0]).name == "thymio-bt" or getattr(spec, "name", "") in _MAIN_MODULES


#: the modules that run the command under ``python -m``
_MAIN_MODULES = ("thymio_bt.__main__", "thymio_bt.cli.__main__")


def _end_now(code: int) -> None:
    """At shutdown: wait for the leftover threads for :data:`GRACE` s, then warn and end the process."""
    deadline = time.monotonic() + GRACE  # realtime: after the run, before the process ends
    for thread in leftover_threads():
        thread.join(max(0.0, deadline - time.monotonic()))  # realtime
    left = leftover_threads()
    if not left:
        return
    names = ", ".join(f"'{t.name}'" for t in left)
    sys.stdout.flush()
    sys.stderr.write(
        f"warning: {len(left)} thread(s) still running after the command ({names}), started by a plugin? "
        f"ending the process anyway\n"
    )
    sys.stderr.flush()
    os._exit(code)


__all__ = ["GRACE", "end_despite_threads", "leftover_threads"]
