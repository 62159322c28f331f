"""Turn a validated :class:`NodePlan` into a py_trees tree bound to a robot :class:`Context`.

Every node's class comes from the registry: a robot behaviour is instantiated with its parameters,
a composite or decorator kind builds its py_trees node around the built children.
``substitutions`` replace nodes whose path (names from the root, joined by ``/``) matches a
glob pattern by a scripted stub, so a mission can be tested with parts of it replaced (like
BehaviorTree.CPP's substitution rules).
"""

from __future__ import annotations

from fnmatch import fnmatchcase
from typing import Any, Mapping

from py_trees.behaviour import Behaviour

from ..behaviours import Context, ControlNode, ScriptedStub
from .plan import NodePlan
from .registry import Registry, default_registry


def build_tree(plan: NodePlan, ctx: Context, registry: Registry | None = None,
               substitutions: Mapping[str, Any] | None = None, parent: str = "") -> Behaviour:
    """Instantiate the behaviours of ``plan`` (recursively) against ``ctx``."""
    registry = registry or default_registry()
    path = f"{parent}/{plan.name}" if parent else plan.name
    for pattern, script in (substitutions or {}).items():
        if fnmatchcase(path, pattern):
            return ScriptedStub(plan.name, script, ctx)
    children = [build_tree(child, ctx, registry, substitutions, path) for child in plan.children]
    cls = registry[plan.behaviour if plan.kind == "behaviour" else plan.kind]
    if issubclass(cls, ControlNode):
        node = cls.build(plan.name, plan.params, children, ctx)
        node.yaml_name = cls.yaml_name            # what logs and exports call it
        return node
    assert plan.params is not None
    return cls(plan.name, plan.params, ctx, blackboard_refs=plan.blackboard_refs)
