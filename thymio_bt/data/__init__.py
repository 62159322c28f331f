"""The files shipped inside the package: the course's mazes, the example missions, the course's
assignments (``thymio-bt grade``), the schemas.

In a checkout, ``mazes``, ``missions``, ``assignments`` and ``schema`` here are links to the top-level folders; a wheel
carries copies. Either way they are found through :mod:`importlib.resources`, so ``maze:
two_parts_maze`` and ``thymio-bt run maze_part1_2`` work from any folder.

Example::

    from thymio_bt.data import MAZES
    sorted(p.stem for p in MAZES.glob("*.yaml"))   # ['arena', 'maze_6x6', ...]
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

#: the shipped maze files, missions and mission schema
MAZES = Path(str(files(__name__) / "mazes"))
MISSIONS = Path(str(files(__name__) / "missions"))
ASSIGNMENTS = Path(str(files(__name__) / "assignments"))
SCHEMA = Path(str(files(__name__) / "schema" / "mission.schema.json"))
