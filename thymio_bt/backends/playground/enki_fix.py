"""The Aseba Playground's sensors, corrected: Debian's Enki 1.6.99 keeps stale ray values.

Enki makes each Thymio proximity reading from three rays. Since enki commit 5d36c42 its
``IRSensor::init`` no longer clears the rays' values at each step (it fills an empty range), so a
ray that stops seeing a wall keeps its last value, and the next time another ray of that sensor
sees anything the stale value is added in: a reading of a wall that is not there, that moves with
the robot (it stopped ``maze_bonus`` 8 cm short of its dead end), and 0 m glints at wall ends in
every run. Upstream fixed it in 7dbaa0b (enki-community/enki#68, 2021); Debian's ``libenki2
1:1.6.99`` predates that. :func:`enki_fix` builds a small library (``enki_fix.cpp``) that the
Playground preloads to run the fixed ``init``; it needs ``g++`` and Enki's headers (Debian:
``apt-get install g++ libenki-dev``) and is built once per machine into the user's cache.

Measured on the Playground: front readings under 1.2 cm (the robot never comes that close) fell
from 12 to 0 in a ``maze_part1_2`` run and from 48-92 to 1 in a ``maze_bonus`` run.

Example (what a machine without the build's needs is told to install)::

    >>> HINT
    'sudo apt-get install g++ libenki-dev'
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

#: the correction's source, shipped beside this module
SOURCE = Path(__file__).with_name("enki_fix.cpp")
#: the Enki header the correction is compiled against (Debian's libenki-dev)
HEADER = Path("/usr/include/enki/interactions/IRSensor.h")
#: how to get what the build needs
HINT = "sudo apt-get install g++ libenki-dev"


def _cache() -> Path:
    """Where the built library is kept: ``$XDG_CACHE_HOME/thymio-bt`` (``~/.cache/thymio-bt``)."""
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "thymio-bt"


def enki_fix() -> tuple[Path | None, str]:
    """The library that corrects the Playground's Enki (built the first time), or ``(None, why)``
    when it cannot be built here."""
    compiler = shutil.which("g++")
    if compiler is None or not HEADER.exists():
        missing = "g++" if compiler is None else f"Enki's headers ({HEADER})"
        return None, f"cannot correct it without {missing}"
    key = hashlib.sha256(SOURCE.read_bytes() + HEADER.read_bytes()).hexdigest()[:16]
    library = _cache() / f"enki_fix-{key}.so"
    if library.exists():
        return library, ""
    library.parent.mkdir(parents=True, exist_ok=True)
    # built beside its final name and renamed: two runs starting at once never load half a file
    handle, partial = tempfile.mkstemp(suffix=".so", dir=library.parent)
    os.close(handle)
    try:
        built = subprocess.run(
            [compiler, "-shared", "-fPIC", "-O2", "-o", partial, str(SOURCE), "-ldl"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        if built.returncode != 0:
            last = (built.stderr.strip().splitlines() or ["no message"])[-1]
            return None, f"cannot correct it: g++ failed ({last})"
        os.replace(partial, library)
    finally:
        Path(partial).unlink(missing_ok=True)
    return library, ""


__all__ = ["HINT", "enki_fix"]
