"""Old module names (before the 0.2 layout) still import, with a DeprecationWarning naming the new one.

``import thymio_bt.robot_model`` gives the very module ``thymio_bt.robot.model`` (the same object, so
its classes are the same classes), through a finder on :data:`sys.meta_path` that only answers for
the names in :data:`MOVED` and their submodules.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

#: Old module name -> new module name (a package's submodules follow it).
MOVED: dict[str, str] = {
    f"thymio_bt.{old}": f"thymio_bt.{new}"
    for old, new in {
        "robot_model": "robot.model",
        "robot_profile": "robot.profile",
        "calibration": "robot.calibration",
        "calibrate": "robot.calibrate",
        "placement": "robot.placement",
        "sim": "backends.sim",
        "real": "backends.real",
        "playground": "backends.playground",
        "ros2": "backends.ros2",
        "runner": "run.runner",
        "interrupts": "run.interrupts",
        "phases": "run.phases",
        "sweep": "run.sweep",
        "matrix": "run.matrix",
        "distributed": "run.distributed",
        "recording": "logs.recording",
        "expect": "mission.expect",
        "btcpp": "mission.btcpp",
        "docs": "mission.node_docs",
        "pid": "behaviours.pid",
        "groot2": "viz.groot2",
        "yamlio": "inputs.yamlio",
        "reading": "inputs.reading",
        "units": "inputs.units",
        "fields": "inputs.fields",
        "validation": "inputs.validation",
    }.items()
}


def new_name(name: str) -> str | None:
    """The module's name in the new layout, or None when ``name`` did not move.

    >>> new_name("thymio_bt.sim.world")
    'thymio_bt.backends.sim.world'
    >>> new_name("thymio_bt.mission") is None
    True
    """
    if not name.startswith("thymio_bt."):
        return None
    head, dot, rest = name.partition(".")[2].partition(".")
    new = MOVED.get(f"thymio_bt.{head}")
    return None if new is None else new + dot + rest


class _Alias(importlib.abc.Loader):
    """Loads an old name as the new module itself; the import system's bookkeeping of the old name
    (it sets ``__spec__``) is undone, so the module keeps its own spec."""

    def __init__(self, target: str) -> None:
        self.target = target
        self.spec: ModuleSpec | None = None

    def create_module(self, spec: ModuleSpec) -> ModuleType:
        warnings.warn(f"{spec.name} moved to {self.target}: import it from there", DeprecationWarning, stacklevel=2)
        module = importlib.import_module(self.target)
        self.spec = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self.spec


class MovedFinder(importlib.abc.MetaPathFinder):
    """Finds old module names and loads them as their new modules."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        """A spec for an old name (:data:`MOVED`), None for every other module."""
        target_name = new_name(fullname)
        if target_name is None:
            return None
        return importlib.util.spec_from_loader(fullname, _Alias(target_name))


def install() -> None:
    """Put the finder on :data:`sys.meta_path` once, first (it answers only for old names)."""
    if not any(isinstance(f, MovedFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, MovedFinder())  # first: before the path finder finds old.sub files
