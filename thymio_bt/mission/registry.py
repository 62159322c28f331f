"""The node registry: YAML name → node class and its pydantic parameter model.

Robot behaviours, conditions, composites and decorators are all registered here, so validation,
``thymio-bt behaviours``, the JSON Schema and the docs read from one place. Users add their own
nodes (a :class:`RobotBehaviour` or a :class:`ControlNode`) through the ``thymio_bt.behaviours``
entry-point group, or a ``plugins:`` list in a mission (``module:Class``, or a ``.py`` file path
relative to the mission).

Example::

    registry = default_registry()
    cls = registry["MoveUntilWall"]
    cls.Params.model_fields["distance"].default   # 0.05
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from thymio_bt.behaviours import BUILTIN, CONTROL, ControlNode, RobotBehaviour
from thymio_bt.errors import Problem, UserError

ENTRY_POINT_GROUP = "thymio_bt.behaviours"


Node = type[RobotBehaviour] | type[ControlNode]


def is_node(cls: Any) -> bool:
    """Whether ``cls`` can be registered: a robot behaviour or a composite/decorator kind."""
    return (
        inspect.isclass(cls) and issubclass(cls, (RobotBehaviour, ControlNode)) and bool(getattr(cls, "Params", None))
    )


class Registry:
    """A mapping from YAML names to node classes."""

    def __init__(self, classes: tuple[Node, ...] = ()) -> None:
        self._classes: dict[str, Node] = {}
        #: the .py plugin files loaded (a mission's sources, e.g. for a sweep's cache key)
        self.plugin_files: list[Path] = []
        for cls in classes:
            self.register(cls)

    def register(self, cls: Node) -> None:
        """Add a node class; its ``yaml_name`` (or class name) is the YAML name."""
        if not is_node(cls):
            raise TypeError(f"{cls!r} is not a RobotBehaviour or ControlNode subclass")
        name = cls.yaml_name or cls.__name__
        existing = self._classes.get(name)
        if existing is not None and existing is not cls:
            raise ValueError(f"two nodes are named '{name}': {existing.__module__} and {cls.__module__}")
        if not cls.yaml_name:
            cls.yaml_name = name
        self._classes[name] = cls

    def copy(self) -> Registry:
        other = Registry()
        other._classes = dict(self._classes)
        other.plugin_files = list(self.plugin_files)
        return other

    def __getitem__(self, name: str) -> Node:
        return self._classes[name]

    def __contains__(self, name: object) -> bool:
        return name in self._classes

    def __iter__(self) -> Iterator[str]:
        return iter(self._classes)

    def items(self) -> Iterator[tuple[str, Node]]:
        return iter(self._classes.items())

    def behaviours(self) -> Iterator[tuple[str, type[RobotBehaviour]]]:
        """The robot behaviours and conditions (no composites or decorators)."""
        return ((n, c) for n, c in self._classes.items() if issubclass(c, RobotBehaviour))

    def control(self, category: str) -> Iterator[tuple[str, type[ControlNode]]]:
        """The composites (``category="composite"``) or decorators."""
        return ((n, c) for n, c in self._classes.items() if issubclass(c, ControlNode) and c.category == category)

    def load_plugin(self, ref: str, base_dir: Path, where: tuple[str, int, int], run: bool = True) -> None:
        """Import ``module:Class``, ``module`` or ``file.py`` and register its behaviours; with
        ``run=False``, register stand-ins for them without running any of the plugin's code."""
        file, line, col = where
        target, _, attr = ref.partition(":")
        if not run:
            self._declare_plugin(ref, base_dir, where)
            return
        try:
            if target.endswith(".py"):
                path = (base_dir / target).resolve()
                if not path.is_file():
                    raise UserError(
                        Problem(
                            f"plugin file not found: {target}",
                            file,
                            line,
                            col,
                            hint="plugin paths are relative to the mission file",
                        )
                    )
                self.plugin_files.append(path)
                name = f"thymio_bt_plugin_{abs(hash(str(path)))}"
                module = sys.modules.get(name)
                if module is None:
                    spec = importlib.util.spec_from_file_location(name, path)
                    assert spec and spec.loader
                    module = importlib.util.module_from_spec(spec)
                    sys.modules[name] = module
                    spec.loader.exec_module(module)
            else:
                module = importlib.import_module(target)
        except UserError:
            raise
        except Exception as exc:  # the plugin's own import error: report it, do not crash
            raise UserError(
                Problem(
                    f"cannot import plugin '{ref}': {type(exc).__name__}: {exc}",
                    file,
                    line,
                    col,
                    hint="check the module name, or give a .py path relative to the mission",
                )
            ) from None
        if attr:
            cls = getattr(module, attr, None)
            if cls is None:
                raise UserError(Problem(f"plugin '{target}' has no attribute '{attr}'", file, line, col))
            candidates = [cls]
        else:
            candidates = [
                c
                for _, c in inspect.getmembers(module, inspect.isclass)
                if is_node(c) and c.__module__ == module.__name__
            ]
            if not candidates:
                raise UserError(
                    Problem(f"plugin '{ref}' defines no RobotBehaviour or ControlNode subclass", file, line, col)
                )
        for cls in candidates:
            try:
                self.register(cls)
            except (TypeError, ValueError) as exc:
                raise UserError(Problem(f"plugin '{ref}': {exc}", file, line, col)) from None

    def _declare_plugin(self, ref: str, base_dir: Path, where: tuple[str, int, int]) -> None:
        """Stand-ins for the nodes of plugin ``ref``, found by reading its source, not running it."""
        from thymio_bt.mission.unrun_plugins import plugin_node_names, stand_in

        file, line, col = where
        target, _, attr = ref.partition(":")
        if attr:
            names = [attr]
        else:
            if target.endswith(".py"):
                path: Path | None = (base_dir / target).resolve()
                if not path.is_file():
                    raise UserError(
                        Problem(
                            f"plugin file not found: {target}",
                            file,
                            line,
                            col,
                            hint="plugin paths are relative to the mission file",
                        )
                    )
                self.plugin_files.append(path)
            else:
                spec = importlib.util.find_spec(target) if "." not in target else None
                path = Path(spec.origin) if spec and spec.origin and spec.origin.endswith(".py") else None
                if path is None:
                    raise UserError(
                        Problem(
                            f"cannot find plugin '{ref}' without importing it",
                            file,
                            line,
                            col,
                            hint="name its class (module:Class), or check with --plugins",
                        )
                    )
            try:
                names = plugin_node_names(path)
            except SyntaxError as exc:
                raise UserError(
                    Problem(f"plugin {target}: invalid Python: {exc.msg}", str(path), exc.lineno or 0, exc.offset or 0)
                ) from None
        for name in names:
            if name not in self._classes:
                self._classes[name] = stand_in(name)


def _entry_point_classes() -> list[Any]:
    from importlib.metadata import entry_points

    classes = []
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            classes.append(ep.load())
        except Exception as exc:  # a broken third-party plugin must not break thymio-bt
            print(f"warning: behaviour plugin '{ep.name}' failed to load: {exc}", file=sys.stderr)
    return classes


_DEFAULT: Registry | None = None


def default_registry() -> Registry:
    """The built-in behaviours plus those installed through the entry-point group."""
    global _DEFAULT
    if _DEFAULT is None:
        registry = Registry((*BUILTIN, *CONTROL))
        for cls in _entry_point_classes():
            try:
                registry.register(cls)
            except (TypeError, ValueError) as exc:
                print(f"warning: behaviour plugin {cls!r} ignored: {exc}", file=sys.stderr)
        _DEFAULT = registry
    return _DEFAULT
