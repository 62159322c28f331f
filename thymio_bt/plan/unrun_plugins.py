r"""Plugins named by a mission, known without running their code.

``thymio-bt validate`` and ``tree`` read missions that may come from anyone; importing their
``plugins:`` would run that code. So those commands read a ``.py`` plugin with :mod:`ast` only: each
class deriving from a thymio-bt node class becomes a stand-in node of the same YAML name. Its
parameter names are read from its ``Params`` model's source when that can be followed (the model's
fields, and its bases' when they are the file's own classes or thymio-bt's), so a misspelt one is
found; the values, and every parameter of a model that cannot be followed, are accepted unchecked
(``--plugins`` asks for the real import, and the full check).

Example::

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     plugin = Path(folder) / "spin.py"
    ...     _ = plugin.write_text("import os; os.abort()\nclass Spin(RobotBehaviour):\n    yaml_name = 'SpinInPlace'")
    ...     plugin_nodes(plugin, {})                           # read, never run: no abort
    {'SpinInPlace': None}
    >>> stand_in("SpinInPlace").Params(speed=3, side="left").model_extra   # any parameters, unchecked
    {'speed': 3, 'side': 'left'}
    >>> source = "class P(BehaviourParams):\n    rate: float = 1\nclass Spin(RobotBehaviour):\n    Params = P"
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     plugin = Path(folder) / "spin.py"
    ...     _ = plugin.write_text(source)
    ...     plugin_nodes(plugin, {"BehaviourParams": ["timeout"]})   # the names its Params declares
    {'Spin': ['rate', 'timeout']}
    >>> with tempfile.TemporaryDirectory() as folder:                   # plugins: [spin.py:Spin]
    ...     plugin = Path(folder) / "spin.py"
    ...     _ = plugin.write_text(source + "\nclass Fast(Spin):\n    yaml_name = 'FastSpin'")
    ...     plugin_nodes(plugin, {"BehaviourParams": []}, only="Fast")   # by its YAML name
    {'FastSpin': ['rate']}
    >>> sorted(stand_in("Spin", ["rate", "timeout"]).Params.model_fields)
    ['rate', 'timeout']
"""

from __future__ import annotations

import ast
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

from py_trees.common import Status
from pydantic import BaseModel, ConfigDict, create_model

from thymio_bt.behaviours import RobotBehaviour
from thymio_bt.behaviours.base import UnrunPlugin
from thymio_bt.inputs.reading import read_text

#: base classes that make a plugin class a node
NODE_BASES = ("RobotBehaviour", "ConditionBehaviour", "ControlNode")


class UncheckedParams(BaseModel):
    """Any parameters: a plugin that was not imported cannot say which it takes."""

    model_config = ConfigDict(extra="allow")


def plugin_nodes(
    path: Path,
    known_params: Mapping[str, Collection[str]],
    known_nodes: Mapping[str, str] | None = None,
    only: str | None = None,
) -> dict[str, list[str] | None]:
    """The node classes of a plugin file, read from its syntax tree, never run: YAML name -> its
    parameter names, None when its ``Params`` cannot be followed in the source. ``known_params``:
    the fields of the models the file may derive from (``BehaviourParams``, a built-in's);
    ``known_nodes``: node classes the file may derive from -> the name of their ``Params``;
    ``only``: the class a ``module:Class`` plugin names, the only one given (by its YAML name)."""
    tree = _parse(path)
    nodes = {"RobotBehaviour": "BehaviourParams", "ConditionBehaviour": "BehaviourParams", **(known_nodes or {})}
    models = {c.name: c for c in ast.walk(tree) if isinstance(c, ast.ClassDef)}
    memo: dict[str, set[str] | None] = {}
    found: dict[str, list[str] | None] = {}
    for name, cls in _node_classes(tree, nodes):
        params = _assigned_name(cls, "Params")
        if params is None:  # inherited: from the first base that is a node class
            params = next((nodes[b] for b in map(_base_name, cls.bases) if b in nodes), "")
        nodes[cls.name] = params
        if only is None or cls.name == only:
            fields = _fields(params, models, known_params, memo) if params else None
            found[name] = sorted(fields) if fields is not None else None
    return found


def _parse(path: Path) -> ast.Module:
    """The syntax tree of a plugin file; one Python cannot parse is a ``SyntaxError``."""
    source = read_text(path, "plugin")
    try:
        return ast.parse(source, str(path))
    except (RecursionError, MemoryError, ValueError) as exc:  # nested past the parser's stack, a NUL byte
        why = "a NUL byte" if isinstance(exc, ValueError) else "nested too deeply to parse"
        raise SyntaxError(why, (str(path), 1, 1, None)) from None


def _node_classes(tree: ast.Module, known: Collection[str]) -> list[tuple[str, ast.ClassDef]]:
    """(YAML name, class) of the node classes of ``tree``: deriving from a thymio-bt base, a ``known``
    node class or a node class the file defined before."""
    bases, found = {*NODE_BASES, *known}, []
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef) and any(_base_name(b) in bases for b in node.bases):
            bases.add(node.name)
            found.append((_yaml_name(node) or node.name, node))
    return found


#: how many bases deep a parameter model is followed: deeper, it is not (a hostile file's chain of
#: thousands, which would otherwise follow Python's recursion limit, which a test runner may raise)
MAX_BASES = 500


def _fields(
    name: str,
    models: Mapping[str, ast.ClassDef],
    known: Mapping[str, Collection[str]],
    memo: dict[str, set[str] | None],
    depth: int = 0,
) -> set[str] | None:
    """The field names of the parameter model ``name``: a known model's, or a class of the file's own
    fields and its bases'; None when something cannot be followed (a base neither known nor the
    file's, a ``model_config`` that may take extra keys, an alias: the YAML keys are then others).
    ``memo``: the models followed so far, each once (a hostile file's cycles and diamonds included);
    a model more than :data:`MAX_BASES` bases deep is not followed (whatever the recursion limit)."""
    if name in memo:
        return memo[name]
    if depth > MAX_BASES:
        return None
    memo[name] = None  # while it is followed: a cycle back to it cannot be followed
    cls = models.get(name)
    if cls is None:
        memo[name] = set(known[name]) if name in known else None
        return memo[name]
    if any(isinstance(t, ast.Name) and t.id == "model_config" for s in cls.body for t in _assigned(s)):
        return None
    if any(isinstance(k, ast.keyword) and k.arg and "alias" in k.arg for k in ast.walk(cls)):
        return None
    own = {
        s.target.id
        for s in cls.body
        if isinstance(s, ast.AnnAssign)
        and isinstance(s.target, ast.Name)
        and "ClassVar" not in ast.unparse(s.annotation)
    }
    for base in map(_base_name, cls.bases):
        inherited = set() if base == "BaseModel" else _fields(base, models, known, memo, depth + 1)
        if inherited is None:
            return None
        own |= inherited
    memo[name] = own
    return own


def _assigned(stmt: ast.stmt) -> list[ast.expr]:
    """What a statement of a class body assigns to (``x = ...`` or ``x: T = ...``), else nothing."""
    if isinstance(stmt, ast.Assign):
        return stmt.targets
    return [stmt.target] if isinstance(stmt, ast.AnnAssign) else []


def _targets(stmt: ast.Assign) -> list[str]:
    """The plain names an assignment assigns to."""
    return [t.id for t in stmt.targets if isinstance(t, ast.Name)]


def _assigned_name(cls: ast.ClassDef, attr: str) -> str | None:
    """The name a class body assigns to ``attr`` (``Params = SpinParams``: ``SpinParams``), if any."""
    for stmt in cls.body:
        if isinstance(stmt, ast.Assign) and attr in _targets(stmt):
            return _base_name(stmt.value) or "?"  # '?': assigned something that is not a name
    return None


def stand_in(name: str, params: Sequence[str] | None = None) -> type[UnrunPlugin]:
    """A node class standing for the plugin node ``name`` (never ticked: validate and tree only);
    ``params``: its parameter names when the plugin's source says them (their values stay unchecked)."""

    def step(self: RobotBehaviour) -> Status:
        raise RuntimeError(f"{name} is a stand-in: its plugin was not imported")

    model: type[BaseModel] = UncheckedParams
    checked = "its parameters are not checked"
    if params is not None:
        fields: dict[str, Any] = {p: (Any, None) for p in params}
        model = create_model(f"{name}Params", __config__=ConfigDict(extra="forbid"), **fields)
        checked = "its parameters' names are checked, not their values"
    return type(
        name,
        (UnrunPlugin,),
        {
            "__doc__": f"{name}, from a plugin that was not imported ({checked}).",
            "yaml_name": name,
            "Params": model,
            "step": step,
        },
    )


def _base_name(node: ast.expr) -> str:
    """The name a class is written with: ``RobotBehaviour`` for ``bt.RobotBehaviour`` too."""
    return node.attr if isinstance(node, ast.Attribute) else node.id if isinstance(node, ast.Name) else ""


def _yaml_name(cls: ast.ClassDef) -> str | None:
    """The string a class body assigns to ``yaml_name``, if it does."""
    for stmt in cls.body:
        if (
            isinstance(stmt, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == "yaml_name" for t in stmt.targets)
            and isinstance(stmt.value, ast.Constant)
            and isinstance(stmt.value.value, str)
        ):
            return stmt.value.value
    return None
