"""Turn a validated :class:`NodePlan` into a py_trees tree bound to a robot :class:`Context`.

Every node's class comes from the registry: a robot behaviour is instantiated with its parameters,
a composite or decorator kind builds its py_trees node around the built children.
``substitutions`` replace nodes whose path (names from the root, joined by ``/``) matches a
glob pattern by a scripted stub, so a mission can be tested with parts of it replaced (like
BehaviorTree.CPP's substitution rules).

Example::

    >>> from thymio_bt.mission.loader import load_mission
    >>> list(node_paths(load_mission("maze_part1_2").tree))[:3]          # what substitutions match
    ['course', 'course/part 1', 'course/DeleteEntity']
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from fnmatch import fnmatchcase
from typing import Any

from py_trees.behaviour import Behaviour

from thymio_bt.behaviours import Context, ControlNode, ScriptedStub
from thymio_bt.errors import UserError, did_you_mean
from thymio_bt.plan.model import NodePlan
from thymio_bt.plan.registry import Registry, default_registry


def build_tree(
    plan: NodePlan,
    ctx: Context,
    registry: Registry | None = None,
    substitutions: Mapping[str, Any] | None = None,
    parent: str = "",
) -> Behaviour:
    """Instantiate the behaviours of ``plan`` (recursively) against ``ctx``. A substitution pattern
    that matches no node is a :class:`UserError` naming it (a misspelt path would test nothing)."""
    registry = registry or default_registry()
    if substitutions and not parent:
        paths = list(node_paths(plan))
        for pattern in substitutions:
            if not any(fnmatchcase(p, pattern) for p in paths):
                raise UserError(
                    f"substitution '{pattern}' matches no node of the tree "
                    f"(hint: {did_you_mean(pattern, paths)}; paths are node names joined by '/')"
                )
    path = f"{parent}/{plan.name}" if parent else plan.name
    for pattern, script in (substitutions or {}).items():
        if fnmatchcase(path, pattern):
            return ScriptedStub(plan.name, script, ctx)
    children = [build_tree(child, ctx, registry, substitutions, path) for child in plan.children]
    kind = plan.behaviour if plan.kind == "behaviour" else plan.kind
    assert kind is not None  # the planner names every behaviour node's behaviour
    cls = registry[kind]
    if issubclass(cls, ControlNode):
        return cls.instantiate(plan.name, plan.params, children, ctx)
    assert plan.params is not None
    return cls(plan.name, plan.params, ctx, blackboard_refs=plan.blackboard_refs)


def node_paths(plan: NodePlan, parent: str = "") -> Iterator[str]:
    """The path of every node of ``plan``, as substitution patterns match them."""
    path = f"{parent}/{plan.name}" if parent else plan.name
    yield path
    for child in plan.children:
        yield from node_paths(child, path)
