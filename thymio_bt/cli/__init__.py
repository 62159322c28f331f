"""The ``thymio-bt`` command line (click). Heavy imports live inside the commands that need them.

Exit codes: 0 success, 1 mission FAILURE or time limit, 2 user error (one clear message, no traceback).

The command group :func:`main` and what the commands share are in :mod:`thymio_bt.cli.app`; each
family of commands has its module, imported when one of its commands is asked for (``app.COMMANDS``),
so that ``thymio-bt run`` does not load the grader or asyncio:
:mod:`~thymio_bt.cli.running` (``run``), :mod:`~thymio_bt.cli.logs` (``replay``, ``export``),
:mod:`~thymio_bt.cli.comparing` (``compare``),
:mod:`~thymio_bt.cli.sweeps` (``sweep``), :mod:`~thymio_bt.cli.inspection` (``validate``, ``tree``,
``palette``, ``behaviours``, ``backends``, ``schema``), :mod:`~thymio_bt.cli.mazes` (``maze import``,
``maze export``), :mod:`~thymio_bt.cli.calibrating` (``calibrate``), :mod:`~thymio_bt.cli.grading`
(``grade``), :mod:`~thymio_bt.cli.linting` (``lint``), :mod:`~thymio_bt.cli.serving` (``serve ros2``),
:mod:`~thymio_bt.cli.viewing` (``view``) and :mod:`~thymio_bt.cli.checking` (``check``). What
several commands share has modules of its own: :mod:`~thymio_bt.cli.pictures` (the plots and
animations of ``run`` and ``replay``) and :mod:`~thymio_bt.cli.option_values` (the backend and the
coverage that shared options ask for). The commands' functions below are read from their modules
the same way, when first read.

Example::

    >>> main.list_commands(None)  # doctest: +NORMALIZE_WHITESPACE
    ['backends', 'behaviours', 'calibrate', 'check', 'compare', 'export', 'grade', 'lint', 'maze', 'palette',
     'replay', 'run', 'schema', 'serve', 'sweep', 'tree', 'validate', 'view']
"""

from __future__ import annotations

import importlib
from typing import Any

from thymio_bt.cli.app import POSITIVE, main

#: the module of each command function (and constant) this package hands out, read when first asked for
_FROM: dict[str, str] = {
    "PICTURE_SUFFIXES": "pictures",
    "backends_command": "inspection",
    "behaviours": "inspection",
    "calibrate_command": "calibrating",
    "check": "checking",
    "compare": "comparing",
    "export": "logs",
    "grade": "grading",
    "lint": "linting",
    "maze": "mazes",
    "maze_export": "mazes",
    "maze_import": "mazes",
    "replay": "logs",
    "run": "running",
    "schema": "inspection",
    "serve": "serving",
    "serve_ros2": "serving",
    "sweep": "sweeps",
    "tree": "inspection",
    "validate": "inspection",
    "view": "viewing",
}


def __getattr__(name: str) -> Any:
    """A command function of :data:`_FROM`, its module imported now."""
    if name not in _FROM:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_FROM[name]}"), name)


__all__ = [
    "PICTURE_SUFFIXES",
    "POSITIVE",
    "backends_command",
    "behaviours",
    "calibrate_command",
    "check",
    "compare",
    "export",
    "grade",
    "lint",
    "main",
    "maze",
    "maze_export",
    "maze_import",
    "replay",
    "run",
    "schema",
    "serve",
    "serve_ros2",
    "sweep",
    "tree",
    "validate",
    "view",
]

if __name__ == "__main__":
    main()
