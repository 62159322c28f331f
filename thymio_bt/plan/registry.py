"""The node registry: YAML name → node class and its pydantic parameter model.

Robot behaviours, conditions, composites and decorators are all registered here, so validation,
``thymio-bt behaviours``, the JSON Schema and the docs read from one place. A built-in node's module
is imported when a mission first names it (:data:`~thymio_bt.plan.builtin_nodes.BUILTIN_NODES` says
where each is), so a run imports only its own nodes; what lists every node imports them all. Users add their own
nodes (a :class:`RobotBehaviour` or a :class:`ControlNode`) through the ``thymio_bt.behaviours``
entry-point group, or a ``plugins:`` list in a mission (``module:Class``, or a ``.py`` file path
relative to the mission).

Example::

    >>> registry = default_registry()
    >>> registry["MoveUntilWall"].Params.model_fields["distance"].default
    0.05
    >>> registry["sequence"].category, "NoSuchNode" in registry
    ('composite', False)
    >>> Registry(lazy={"Stop": "thymio_bt.behaviours.motion:Stop"}).get("Stop").__name__   # imported now
    'Stop'
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from thymio_bt.behaviours import ControlNode, RobotBehaviour
from thymio_bt.errors import Problem, UserError
from thymio_bt.named import named
from thymio_bt.plan.builtin_nodes import BUILTIN_NODES

ENTRY_POINT_GROUP = "thymio_bt.behaviours"


Node = type[RobotBehaviour] | type[ControlNode]


def is_node(cls: Any) -> bool:
    """Whether ``cls`` can be registered: a robot behaviour or a composite/decorator kind."""
    return inspect.isclass(cls) and issubclass(cls, (RobotBehaviour, ControlNode)) and bool(cls.Params)


class Registry:
    """A mapping from YAML names to node classes; ``lazy``: nodes known by name and ``"module:attr"``
    (see :mod:`thymio_bt.plan.builtin_nodes`), imported when first looked up."""

    def __init__(self, classes: tuple[Node, ...] = (), lazy: Mapping[str, str] | None = None) -> None:
        #: YAML name -> its class, or where it is while not yet imported
        self._classes: dict[str, Node | str] = dict(lazy or {})
        #: the .py plugin files loaded (a mission's sources, e.g. for a sweep's cache key)
        self.plugin_files: list[Path] = []
        #: every plugin a mission named (``module:Class``, ``module`` or ``file.py``) and where, loaded or not
        self.plugins: list[tuple[str, tuple[str, int, int]]] = []
        for cls in classes:
            self.register(cls)

    def register(self, cls: Node) -> None:
        """Add a node class; its ``yaml_name`` (or class name) is the YAML name."""
        name = _checked_name(cls)
        existing = self.get(name)
        if existing is not None and existing is not cls:
            raise ValueError(f"two nodes are named '{name}': {existing.__module__} and {cls.__module__}")
        self._classes[name] = cls

    def copy(self) -> Registry:
        """A registry of the same nodes, to which a mission's plugins can be added."""
        other = Registry()
        other._classes = dict(self._classes)
        other.plugin_files = list(self.plugin_files)
        other.plugins = list(self.plugins)
        return other

    def __getitem__(self, name: str) -> Node:
        cls = self.get(name)
        if cls is None:
            raise KeyError(name)
        return cls

    def get(self, name: str) -> Node | None:
        """The node class called ``name`` (its module imported now if it was not), None when there is none."""
        found = self._classes.get(name)
        if isinstance(found, str):
            found = self._classes[name] = _imported(name, found)
        return found

    def __contains__(self, name: object) -> bool:
        return name in self._classes

    def __iter__(self) -> Iterator[str]:
        """The YAML names, none of their modules imported."""
        return iter(self._classes)

    def items(self) -> Iterator[tuple[str, Node]]:
        """(YAML name, node class) of every node, in the order they were registered (all imported)."""
        self.import_all()
        return iter(self._classes.items())  # type: ignore[arg-type]  # every value a class now

    def import_all(self) -> None:
        """Import every node's module now: a process about to fork children whose missions may name
        any node (the grader, its sandboxes' zygote) hands each child all of them warm."""
        for name in list(self._classes):
            self.get(name)

    def behaviours(self) -> Iterator[tuple[str, type[RobotBehaviour]]]:
        """The robot behaviours and conditions (no composites or decorators)."""
        return ((n, c) for n, c in self.items() if issubclass(c, RobotBehaviour))

    def control(self, category: str) -> Iterator[tuple[str, type[ControlNode]]]:
        """The composites (``category="composite"``) or decorators."""
        return ((n, c) for n, c in self.items() if issubclass(c, ControlNode) and c.category == category)

    def load_plugin(self, ref: str, base_dir: Path, where: tuple[str, int, int], run: bool = True) -> None:
        """Import ``module:Class``, ``module`` or ``file.py`` and register its behaviours; with
        ``run=False``, register stand-ins for them without running any of the plugin's code."""
        self.plugins.append((ref, where))
        if not run:
            self._declare_plugin(ref, base_dir, where)
            return
        module = self._import_plugin(ref, base_dir, where)
        for cls in _plugin_classes(module, ref, where):
            try:
                self.register(cls)
            except (TypeError, ValueError) as exc:
                raise UserError(Problem(f"plugin '{ref}': {exc}", *where)) from None

    def _import_plugin(self, ref: str, base_dir: Path, where: tuple[str, int, int]) -> ModuleType:
        """The module of plugin ``ref``, imported; its own import error is a :class:`UserError`."""
        target = ref.partition(":")[0]
        try:
            if target.endswith(".py"):
                return _import_file(self._plugin_file(target, base_dir, where))
            return importlib.import_module(target)
        except UserError:
            raise
        except BaseException as exc:  # the plugin's own import error, sys.exit and Ctrl-C too: report it
            try:
                said = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
            except Exception:  # an exception whose str() fails: its type says enough
                said = type(exc).__name__
            raise UserError(
                Problem(
                    f"cannot import plugin '{ref}': {said}",
                    *where,
                    hint="check the module name, or give a .py path relative to the mission",
                )
            ) from None

    def _plugin_file(self, target: str, base_dir: Path, where: tuple[str, int, int]) -> Path:
        """The ``.py`` plugin file ``target`` (relative to ``base_dir``), recorded among the plugin files."""
        path = (base_dir / target).resolve()
        if not path.is_file():
            raise UserError(
                Problem(
                    f"plugin file not found: {target}",
                    *where,
                    hint="plugin paths are relative to the mission file",
                )
            )
        self.plugin_files.append(path)
        return path

    def _declare_plugin(self, ref: str, base_dir: Path, where: tuple[str, int, int]) -> None:
        """Stand-ins for the nodes of plugin ``ref``, found by reading its source, not running it."""
        from thymio_bt.behaviours.base import BehaviourParams
        from thymio_bt.plan.unrun_plugins import plugin_nodes, stand_in

        target, _, attr = ref.partition(":")
        if target.endswith(".py"):
            path: Path | None = self._plugin_file(target, base_dir, where)
        else:
            path = _source(ref, where, needed=not attr)
        nodes: dict[str, list[str] | None] = {}
        if path is not None:
            classes = [cls for _, cls in self.items()]
            models = {c.Params.__name__: list(c.Params.model_fields) for c in classes}
            try:
                nodes = plugin_nodes(
                    path,
                    {**models, "BehaviourParams": list(BehaviourParams.model_fields)},
                    {c.__name__: c.Params.__name__ for c in classes},
                    only=attr or None,
                )
            except SyntaxError as exc:
                raise UserError(
                    Problem(f"plugin {target}: invalid Python: {exc.msg}", str(path), exc.lineno or 0, exc.offset or 0)
                ) from None
        # a class the source does not show as a node (imported from elsewhere, made at run time):
        # its class name, its parameters unchecked
        for name, params in (nodes or {attr: None}).items():
            if name not in self._classes:
                self._classes[name] = stand_in(name, params)


def _checked_name(cls: Any) -> str:
    """The YAML name of node class ``cls`` (its ``yaml_name``, or class name), once it is checked to be one."""
    if not is_node(cls):
        raise TypeError(f"{cls!r} is not a RobotBehaviour or ControlNode subclass")
    name: str = cls.yaml_name or cls.__name__
    if "name" in cls.Params.model_fields:
        raise ValueError(
            f"node '{name}' has a parameter called 'name', which a mission can never set: 'name:' is the "
            "node's label in the tree; call it what it names (e.g. entity, as DeleteEntity does)"
        )
    return name


def _imported(name: str, where: str) -> Node:
    """The node class called ``name``, imported from ``where`` (``"module:attr"``: the class, or a tuple
    of classes holding it); a table that says otherwise than the class is a ``LookupError``."""
    found = named(where)
    for cls in found if isinstance(found, tuple) else (found,):
        if _checked_name(cls) == name:
            return cls
    raise LookupError(f"no node called '{name}' in {where}")


def _import_file(path: Path) -> ModuleType:
    """The module of a ``.py`` plugin file, run once per process (a name of its own in ``sys.modules``);
    one whose code raised is forgotten, as Python's import does, so the next load raises again rather
    than hand out a half-run module."""
    name = f"thymio_bt_plugin_{abs(hash(str(path)))}"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec and spec.loader
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    return module


def _source(ref: str, where: tuple[str, int, int], needed: bool = True) -> Path | None:
    """The ``.py`` file of the plugin module ``ref``, found without importing it (a top-level module
    only); None when it cannot be and is not ``needed`` (a ``module:Class`` names its class)."""
    target = ref.partition(":")[0]
    spec = importlib.util.find_spec(target) if "." not in target else None
    if spec and spec.origin and spec.origin.endswith(".py"):
        return Path(spec.origin)
    if not needed:
        return None
    raise UserError(
        Problem(
            f"cannot find plugin '{ref}' without importing it",
            *where,
            hint="name its class (module:Class), or check with --plugins",
        )
    )


def _plugin_classes(module: ModuleType, ref: str, where: tuple[str, int, int]) -> list[Any]:
    """The node classes plugin ``ref`` names: its ``Class``, or every node class its module defines."""
    target, _, attr = ref.partition(":")
    if attr:
        cls = getattr(module, attr, None)
        if cls is None:
            raise UserError(Problem(f"plugin '{target}' has no attribute '{attr}'", *where))
        return [cls]
    candidates = [
        c for _, c in inspect.getmembers(module, inspect.isclass) if is_node(c) and c.__module__ == module.__name__
    ]
    if not candidates:
        raise UserError(Problem(f"plugin '{ref}' defines no RobotBehaviour or ControlNode subclass", *where))
    return candidates


def _entry_point_classes() -> list[Any]:
    """The node classes installed packages declare in the entry-point group (a broken one is a warning)."""
    from importlib.metadata import entry_points

    classes = []
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            classes.append(ep.load())
        except Exception as exc:  # a broken third-party plugin must not break thymio-bt
            print(f"warning: behaviour plugin '{ep.name}' failed to load: {exc}", file=sys.stderr)
    return classes


_DEFAULT: Registry | None = None


def control_kind(name: str, registry: Registry | None = None) -> type[ControlNode] | None:
    """The composite or decorator class called ``name`` in ``registry`` (default: the default
    registry), whose facts the tools read; None for a behaviour or a name it lacks.

    >>> control_kind("reactive_selector").symbol, control_kind("MoveUntilWall")
    ('[o]', None)
    """
    cls = (registry or default_registry()).get(name)
    return cls if isinstance(cls, type) and issubclass(cls, ControlNode) else None


def default_registry() -> Registry:
    """The built-in behaviours plus those installed through the entry-point group."""
    global _DEFAULT
    if _DEFAULT is None:
        registry = Registry(lazy=BUILTIN_NODES)
        for cls in _entry_point_classes():
            try:
                registry.register(cls)
            except (TypeError, ValueError) as exc:
                print(f"warning: behaviour plugin {cls!r} ignored: {exc}", file=sys.stderr)
        _DEFAULT = registry
    return _DEFAULT
