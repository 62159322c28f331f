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

from thymio_bt.cli.app import COMMANDS, POSITIVE, main

#: the command functions not named as their command (``thymio-bt backends`` is ``backends_command``)
_RENAMED = {"backends": "backends_command", "calibrate": "calibrate_command"}
#: what else the package hands out: sub-commands and a constant, with their modules
_ALSO = {"PICTURE_SUFFIXES": "pictures", "maze_export": "mazes", "maze_import": "mazes", "serve_ros2": "serving"}
#: the module of each name the package hands out, read when first asked for: every command's
#: function, in its module of :data:`~thymio_bt.cli.app.COMMANDS`, and the names above
_FROM: dict[str, str] = {_RENAMED.get(command, command): module for command, module in COMMANDS.items()} | _ALSO


def __getattr__(name: str) -> Any:
    """A command function of :data:`_FROM`, its module imported now."""
    if name not in _FROM:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_FROM[name]}"), name)


__all__ = ["POSITIVE", "main"]
__all__ += sorted(_FROM)  # the names of the table above

if __name__ == "__main__":
    main()
