r"""Plugins named by a mission, known without running their code.

``thymio-bt validate`` and ``tree`` read missions that may come from anyone; importing their
``plugins:`` would run that code. So those commands read a ``.py`` plugin with :mod:`ast` only: each
class deriving from a thymio-bt node class becomes a stand-in node of the same YAML name, whose
parameters are accepted unchecked (``--plugins`` asks for the real import, and the full check).

Example::

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     plugin = Path(folder) / "spin.py"
    ...     _ = plugin.write_text("import os; os.abort()\nclass Spin(RobotBehaviour):\n    yaml_name = 'SpinInPlace'")
    ...     plugin_node_names(plugin)                          # read, never run: no abort
    ['SpinInPlace']
    >>> stand_in("SpinInPlace").Params(speed=3, side="left").model_extra   # any parameters, unchecked
    {'speed': 3, 'side': 'left'}
"""

from __future__ import annotations

import ast
from collections.abc import Collection
from pathlib import Path

from py_trees.common import Status
from pydantic import BaseModel, ConfigDict

from thymio_bt.behaviours import RobotBehaviour
from thymio_bt.inputs.reading import read_text

#: base classes that make a plugin class a node
NODE_BASES = ("RobotBehaviour", "ConditionBehaviour", "ControlNode")


class UncheckedParams(BaseModel):
    """Any parameters: a plugin that was not imported cannot say which it takes."""

    model_config = ConfigDict(extra="allow")


def plugin_node_names(path: Path, known: Collection[str] = ()) -> list[str]:
    """The YAML names of the node classes a plugin file defines, read from its syntax tree: classes
    deriving from a thymio-bt base, from a ``known`` node class (``WallFollow``) or from a node
    class the file defined before."""
    source = read_text(path, "plugin")
    try:
        tree = ast.parse(source, str(path))
    except (RecursionError, MemoryError, ValueError) as exc:  # nested past the parser's stack, a NUL byte
        why = "a NUL byte" if isinstance(exc, ValueError) else "nested too deeply to parse"
        raise SyntaxError(why, (str(path), 1, 1, None)) from None
    bases, names = {*NODE_BASES, *known}, []
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef) and any(_base_name(b) in bases for b in node.bases):
            bases.add(node.name)
            names.append(_yaml_name(node) or node.name)
    return names


def stand_in(name: str) -> type[RobotBehaviour]:
    """A node class standing for the plugin node ``name`` (never ticked: validate and tree only)."""

    def step(self: RobotBehaviour) -> Status:
        raise RuntimeError(f"{name} is a stand-in: its plugin was not imported")

    return type(
        name,
        (RobotBehaviour,),
        {
            "__doc__": f"{name}, from a plugin that was not imported (its parameters are not checked).",
            "yaml_name": name,
            "Params": UncheckedParams,
            "step": step,
            "unrun_plugin": True,
        },
    )


def _base_name(base: ast.expr) -> str:
    """The name a base class is written with: ``RobotBehaviour`` for ``bt.RobotBehaviour`` too."""
    return base.attr if isinstance(base, ast.Attribute) else base.id if isinstance(base, ast.Name) else ""


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
