"""The composites of the mission language: sequence, selector (each plain or reactive) and parallel.

Written ``sequence: [A, B]`` or ``sequence: {name: legs, children: [A, B]}``.

- ``sequence`` ticks its children in order and remembers the running one (py_trees' memory
  sequence, BehaviorTree.CPP's SequenceWithMemory); it fails as soon as a child fails.
- ``reactive_sequence`` starts again from the first child every tick, so earlier conditions are
  checked again while a later child runs (BehaviorTree.CPP's ReactiveSequence).
- ``selector`` tries children in order until one does not fail (BehaviorTree.CPP's Fallback, with
  memory); ``reactive_selector`` re-tries the higher-priority children every tick.
- ``parallel`` ticks every child each tick; ``policy: success_on_all`` (default) succeeds when all
  have, ``success_on_one`` when one has; any failure fails it.
"""

from __future__ import annotations

import collections.abc
from collections.abc import Mapping
from typing import Any, ClassVar, Literal

import py_trees
from py_trees.common import ParallelPolicy
from pydantic import BaseModel, Field, field_validator

from thymio_bt.behaviours.flow.node import ControlNode, ControlParams, F, S, refuse


class _Memory(ControlNode):
    """A py_trees sequence or selector: ``memory`` resumes at the running child, without it every
    tick starts again from the first child (a reactive composite)."""

    category = "composite"
    #: the py_trees composite built, and whether it remembers the running child
    composite: ClassVar[type[py_trees.composites.Sequence] | type[py_trees.composites.Selector]]
    memory: ClassVar[bool] = True

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> py_trees.behaviour.Behaviour:
        """The py_trees composite, with or without memory."""
        return cls.composite(name, memory=cls.memory, children=children)

    @classmethod
    def without_memory(cls, btcpp_id: str, doc: str, children: str) -> type[_Memory]:
        """The kind ``reactive_<name>``: this one without memory (only ``memory`` differs, so it is a
        call, not a class of its own), BT.CPP's ``btcpp_id``. ``doc`` says what it does, ``children``
        is an example list."""
        name = f"reactive_{cls.yaml_name}"
        return type(
            f"Reactive{cls.__name__}",
            (cls,),
            {
                "__doc__": doc,
                "__module__": cls.__module__,
                "yaml_name": name,
                "example": f"e.g. '{name}: {children}'",
                "memory": False,
                "reactive": True,
                "symbol": f"[{cls.symbol[1:-1]}]",
                "btcpp_id": btcpp_id,
            },
        )


class Sequence(_Memory):
    """Run the children in order; fail at the first failure (resumes at the running child)."""

    yaml_name = "sequence"
    example = "e.g. 'sequence: [{MoveUntilWall: {}}, {TurnAngle: {angle: 90deg}}]'"
    composite = py_trees.composites.Sequence
    family, symbol, btcpp_id = "sequence", "{-}", "Sequence"


class Selector(_Memory):
    """Try the children in order until one does not fail (resumes at the running child)."""

    yaml_name = "selector"
    example = "e.g. 'selector: [{WallAhead: {}}, {MoveDistance: {distance: 10cm}}]'"
    composite = py_trees.composites.Selector
    family, symbol, btcpp_id = "selector", "{o}", "Fallback"


ReactiveSequence = Sequence.without_memory(
    "ReactiveSequence",
    "Like sequence, but start again from the first child every tick (conditions stay checked).",
    "[{WallAhead: {}}, {TurnAngle: {angle: 90deg}}]",
)
ReactiveSelector = Selector.without_memory(
    "ReactiveFallback",
    "Like selector, but re-try the higher-priority children every tick.",
    "[{ObstacleAhead: {}}, {GoToPose: {goal: [1, 0, 0]}}]",
)


class ParallelParams(ControlParams):
    """When a parallel succeeds, and whether children that succeeded are ticked again."""

    policy: Literal["success_on_all", "success_on_one"] = Field(
        "success_on_all", description="success_on_all (every child must succeed) or success_on_one"
    )
    synchronise: bool = Field(True, description="with success_on_all: children that succeeded are not ticked again")

    @field_validator("policy", mode="before")
    @classmethod
    def _known_policy(cls, value: Any) -> Any:
        if value not in ("success_on_all", "success_on_one"):
            raise refuse(f"unknown parallel policy '{value}'", cls.model_fields["policy"].description or "")
        return value

    @field_validator("synchronise", mode="before")
    @classmethod
    def _boolean(cls, value: Any) -> Any:
        if not isinstance(value, bool):
            raise refuse("synchronise must be true or false")
        return value


def _on_one(params: BaseModel) -> bool:
    """Whether a parallel's parameters say ``success_on_one``."""
    return isinstance(params, ParallelParams) and params.policy == "success_on_one"


class Parallel(ControlNode):
    """Tick every child each tick; succeed by the policy, fail as soon as one child fails."""

    yaml_name = "parallel"
    category = "composite"
    Params = ParallelParams
    example = "e.g. 'parallel: {policy: success_on_one, children: [...]}'"
    family, symbol, btcpp_id = "parallel", "/_/", "Parallel"

    @classmethod
    def ends(cls, params: BaseModel, children: collections.abc.Sequence[frozenset[str]]) -> frozenset[str]:
        """SUCCESS when every child (``success_on_one``: one) can succeed; FAILURE when one can fail."""
        win = any if _on_one(params) else all
        return frozenset(
            ({S} if win(S in got for got in children) else set())
            | ({F} if any(F in got for got in children) else set())
        )

    @classmethod
    def may_stop(cls, params: BaseModel, children: collections.abc.Sequence[frozenset[str]], index: int) -> bool:
        """When another child can fail, or (``success_on_one``) succeed."""
        one = _on_one(params)
        return any(F in got or (one and S in got) for i, got in enumerate(children) if i != index)

    @classmethod
    def to_btcpp(cls, params: Mapping[str, Any]) -> dict[str, Any]:
        """BT.CPP's counts: one success (``success_on_one``) or all (-1), one failure."""
        ports = {"success_count": 1 if params.get("policy") == "success_on_one" else -1, "failure_count": 1}
        return ports if params.get("synchronise", True) else {**ports, "synchronise": False}

    @classmethod
    def from_btcpp(cls, ports: Mapping[str, Any]) -> dict[str, Any]:
        """The policy from BT.CPP's ``success_count`` (1: success on one)."""
        params = {k: v for k, v in ports.items() if k not in ("success_count", "failure_count")}
        one = str(ports.get("success_count", -1)) == "1"
        return {"policy": "success_on_one" if one else "success_on_all", **params}

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> py_trees.behaviour.Behaviour:
        """A py_trees ``Parallel`` with the policy (synchronised, for success on all, by default)."""
        policy = (
            ParallelPolicy.SuccessOnAll(synchronise=params.synchronise)
            if params.policy == "success_on_all"
            else ParallelPolicy.SuccessOnOne()
        )
        return py_trees.composites.Parallel(name, policy=policy, children=children)


#: The composites, in the order docs list them.
COMPOSITES: tuple[type[ControlNode], ...] = (Sequence, ReactiveSequence, Selector, ReactiveSelector, Parallel)
