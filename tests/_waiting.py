"""Waiting on another process without a fixed sleep: poll for what the test needs to have happened
(a run's log holding some ticks), with a deadline generous enough for a loaded machine, instead of
sleeping a guessed time that is too short under load and wasted when idle."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path


def wait_until(condition: Callable[[], bool], what: str, timeout: float = 60.0, every: float = 0.02) -> None:
    """Return once ``condition()`` holds, asked ``every`` s; fail the test saying ``what`` was awaited
    after ``timeout`` s (a safety net against a hang, never the claim: make it generous)."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"waited {timeout} s for {what}"
        time.sleep(every)  # realtime: polling another process


def ticks_logged(path: Path) -> int:
    """How many whole tick lines the JSON-lines run log ``path`` holds so far (it is written line by line).

    >>> import tempfile
    >>> log = Path(tempfile.mkdtemp()) / "r.jsonl"
    >>> ticks_logged(log)
    0
    >>> _ = log.write_text('{"kind":"header"}\\n{"kind":"tick","tick":1}\\n{"kind":"tick","ti')
    >>> ticks_logged(log)
    1
    """
    if not path.exists():
        return 0
    return sum(line.startswith('{"kind":"tick"') for line in path.read_text().split("\n")[:-1])
