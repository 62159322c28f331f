"""The ``thymio-bt`` command line (click). Heavy imports live inside the commands that need them.

Exit codes: 0 success, 1 mission FAILURE or time limit, 2 user error (one clear message, no traceback).

The command group :func:`main` and what the commands share are in :mod:`thymio_bt.cli.app`; each
family of commands has its module, imported here so that ``main`` has them all:
:mod:`~thymio_bt.cli.running` (``run``), :mod:`~thymio_bt.cli.logs` (``replay``, ``export``),
:mod:`~thymio_bt.cli.comparing` (``compare``),
:mod:`~thymio_bt.cli.sweeps` (``sweep``), :mod:`~thymio_bt.cli.inspection` (``validate``, ``tree``,
``behaviours``, ``backends``, ``schema``), :mod:`~thymio_bt.cli.mazes` (``maze import``,
``maze export``), :mod:`~thymio_bt.cli.calibrating` (``calibrate``), :mod:`~thymio_bt.cli.grading`
(``grade``), :mod:`~thymio_bt.cli.linting` (``lint``), :mod:`~thymio_bt.cli.serving` (``serve ros2``),
:mod:`~thymio_bt.cli.viewing` (``view``) and :mod:`~thymio_bt.cli.checking` (``check``).

Example::

    >>> sorted(main.commands)  # doctest: +NORMALIZE_WHITESPACE
    ['backends', 'behaviours', 'calibrate', 'check', 'compare', 'export', 'grade', 'lint', 'maze', 'palette',
     'replay', 'run', 'schema', 'serve', 'sweep', 'tree', 'validate', 'view']
"""

from __future__ import annotations

from thymio_bt.cli.app import POSITIVE, main
from thymio_bt.cli.calibrating import calibrate_command
from thymio_bt.cli.checking import check
from thymio_bt.cli.comparing import compare
from thymio_bt.cli.grading import grade
from thymio_bt.cli.inspection import backends_command, behaviours, schema, tree, validate
from thymio_bt.cli.linting import lint
from thymio_bt.cli.logs import export, replay
from thymio_bt.cli.mazes import maze, maze_export, maze_import
from thymio_bt.cli.pictures import PICTURE_SUFFIXES
from thymio_bt.cli.running import run
from thymio_bt.cli.serving import serve, serve_ros2
from thymio_bt.cli.sweeps import sweep
from thymio_bt.cli.viewing import view

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
