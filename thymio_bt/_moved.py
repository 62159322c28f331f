"""Old module names (of the layouts before this one) still import, with a DeprecationWarning naming the new one.

``import thymio_bt.robot_model`` gives the very module ``thymio_bt.robot.model`` (the same object, so
its classes are the same classes), through a finder on :data:`sys.meta_path` that only answers for
the names in :data:`MOVED` and their submodules, and :data:`SPLIT`. An old module whose contents went
to several new ones (:data:`SPLIT`) is a module of its own holding their public names (the same
objects).
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
        "calibration": "sensor_tables",
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
        "docs": "analysis.node_docs",
        "pid": "robot.pid",
        "groot2": "btcpp.groot2",
        "yamlio": "inputs.yamlio",
        "reading": "inputs.reading",
        "units": "inputs.units",
        "fields": "inputs.fields",
        "validation": "inputs.validation",
        "behaviours.btcpp_nodes": "btcpp.runtime.nodes",
        "behaviours.btcpp_control": "btcpp.runtime.control",
        "behaviours.btcpp_decorators": "btcpp.runtime.decorators",
        "behaviours.btcpp_scripted": "btcpp.runtime.scripted",
        "behaviours.btcpp_script": "btcpp.runtime.script",
        "behaviours.btcpp_values": "btcpp.runtime.values",
        "mission.btcpp": "btcpp.export",
        "mission.xml_reader": "btcpp.xml_reader",
        "mission.xml_tree": "btcpp.xml_tree",
        "mission.xml_scope": "btcpp.xml_scope",
        "logs.btlog": "btcpp.btlog",
        "viz.groot2": "btcpp.groot2",
        "behaviours.control_node": "behaviours.flow.node",
        "behaviours.control": "behaviours.flow.primitives",
        "behaviours.composites": "behaviours.flow.composites",
        "behaviours.decorators": "behaviours.flow.decorators",
        "behaviours.ticking": "behaviours.flow.ticking",
        "behaviours.cellmap": "maze.cellmap",
        "behaviours.corridor": "robot.corridor",
        "behaviours.pid": "robot.pid",
        "mission.lint": "analysis.lint",
        "mission.tree_rules": "analysis.tree_rules",
        "mission.schema": "analysis.schema",
        "mission.node_docs": "analysis.node_docs",
        "mission.plan": "plan.model",
        "mission.registry": "plan.registry",
        "mission.unrun_plugins": "plan.unrun_plugins",
        "mission.checker": "mission.pass_base",
        "logs.records": "logs.entries",
        "robot.calibration": "sensor_tables",
        "cli.calibration": "cli.calibrating",
    }.items()
}
#: Old module name -> the new modules its contents went to (what a mission expects, the verdict on a run).
SPLIT: dict[str, tuple[str, ...]] = {
    f"thymio_bt.{old}": tuple(f"thymio_bt.{new}" for new in news)
    for old, news in {
        "expect": ("plan.expect", "run.verdict"),
        "mission.expect": ("plan.expect", "run.verdict"),
    }.items()
}


def new_name(name: str) -> str | None:
    """The module's name in the new layout, or None when ``name`` did not move (the longest moved
    name it starts with decides).

    >>> new_name("thymio_bt.sim.world")
    'thymio_bt.backends.sim.world'
    >>> new_name("thymio_bt.behaviours.btcpp_nodes")
    'thymio_bt.btcpp.runtime.nodes'
    >>> new_name("thymio_bt.mission") is None, new_name("thymio_bt.behaviours.base") is None
    (True, True)
    """
    if not name.startswith("thymio_bt."):
        return None
    parts = name.split(".")
    for end in range(len(parts), 1, -1):
        new = MOVED.get(".".join(parts[:end]))
        if new is not None:
            return ".".join([new, *parts[end:]])
    return None


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


class _Merged(importlib.abc.Loader):
    """Loads an old name as a module of its own holding the public names (``__all__``) of each new
    module it was split into (the same objects: a class from the old name is the new module's class)."""

    def __init__(self, targets: tuple[str, ...]) -> None:
        self.targets = targets

    def create_module(self, spec: ModuleSpec) -> ModuleType:
        warnings.warn(
            f"{spec.name} moved to {' and '.join(self.targets)}: import it from there",
            DeprecationWarning,
            stacklevel=2,
        )
        return ModuleType(spec.name, f"The names of {', '.join(self.targets)} (moved from {spec.name}).")

    def exec_module(self, module: ModuleType) -> None:
        names: list[str] = []
        for target in self.targets:
            new = importlib.import_module(target)
            module.__dict__.update({name: new.__dict__[name] for name in new.__all__})
            names.extend(new.__all__)
        module.__all__ = names  # type: ignore[attr-defined]


class MovedFinder(importlib.abc.MetaPathFinder):
    """Finds old module names and loads them as their new modules."""

    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        """A spec for an old name (:data:`MOVED`, :data:`SPLIT`), None for every other module."""
        if fullname in SPLIT:
            return importlib.util.spec_from_loader(fullname, _Merged(SPLIT[fullname]))
        target_name = new_name(fullname)
        if target_name is None:
            return None
        return importlib.util.spec_from_loader(fullname, _Alias(target_name))


def install() -> None:
    """Put the finder on :data:`sys.meta_path` once, first (it answers only for old names)."""
    if not any(isinstance(f, MovedFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, MovedFinder())  # first: before the path finder finds old.sub files
