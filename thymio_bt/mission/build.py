"""Turn a validated :class:`NodePlan` into a py_trees tree bound to a robot :class:`Context`.

``substitutions`` replace nodes whose path (names from the root, joined by ``/``) matches a
glob pattern by a scripted stub, so a mission can be tested with parts of it replaced (like
BehaviorTree.CPP's substitution rules).
"""

from __future__ import annotations

from fnmatch import fnmatchcase
from typing import Any, Mapping

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import OneShotPolicy, ParallelPolicy, Status

from ..behaviours import Context, RepeatUntil, ScriptedStub, SimTimeout
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
    name, o = plan.name, plan.options
    kind = plan.kind
    if kind == "behaviour":
        assert plan.behaviour and plan.params is not None
        cls = registry[plan.behaviour]
        return cls(name, plan.params, ctx, blackboard_refs=plan.blackboard_refs)
    if kind in ("sequence", "reactive_sequence"):
        return py_trees.composites.Sequence(name, memory=kind == "sequence", children=children)
    if kind in ("selector", "reactive_selector"):
        return py_trees.composites.Selector(name, memory=kind == "selector", children=children)
    if kind == "parallel":
        policy = (ParallelPolicy.SuccessOnAll(synchronise=o["synchronise"]) if o["policy"] == "success_on_all"
                  else ParallelPolicy.SuccessOnOne())
        return py_trees.composites.Parallel(name, policy=policy, children=children)
    child = children[0]
    if kind == "repeat":
        if o.get("until"):
            return RepeatUntil(name, body=child, condition=children[1])
        return py_trees.decorators.Repeat(name=name, child=child, num_success=o["times"])
    if kind == "retry":
        return py_trees.decorators.Retry(name=name, child=child, num_failures=o["times"])
    if kind == "timeout":
        return SimTimeout(name, child, duration=o["seconds"], clock=ctx.now)
    if kind == "invert":
        return py_trees.decorators.Inverter(name=name, child=child)
    if kind == "force_success":
        return py_trees.decorators.FailureIsSuccess(name=name, child=child)
    if kind == "force_failure":
        return py_trees.decorators.SuccessIsFailure(name=name, child=child)
    if kind == "until":
        status = Status.SUCCESS if o["status"] == "success" else Status.FAILURE
        return py_trees.decorators.Condition(name=name, child=child, status=status)
    if kind == "guard":
        condition = children[1]

        def check() -> bool:
            for _ in condition.tick():
                pass
            return condition.status == Status.SUCCESS

        return py_trees.decorators.EternalGuard(name=name, child=child, condition=check)
    if kind == "one_shot":
        policy = (OneShotPolicy.ON_SUCCESSFUL_COMPLETION if o["on"] == "success" else OneShotPolicy.ON_COMPLETION)
        return py_trees.decorators.OneShot(name=name, child=child, policy=policy)
    raise ValueError(f"unknown node kind {kind!r}")
