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

from typing import Any, ClassVar, Literal

import py_trees
from py_trees.common import ParallelPolicy
from pydantic import Field, field_validator

from thymio_bt.behaviours.flow.node import ControlNode, ControlParams, refuse


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
    def reactive(cls, doc: str, children: str) -> type[_Memory]:
        """The kind ``reactive_<name>``: this one without memory (only ``memory`` differs, so it is a
        call, not a class of its own). ``doc`` says what it does, ``children`` is an example list."""
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
            },
        )


class Sequence(_Memory):
    """Run the children in order; fail at the first failure (resumes at the running child)."""

    yaml_name = "sequence"
    example = "e.g. 'sequence: [{MoveUntilWall: {}}, {TurnAngle: {angle: 90deg}}]'"
    composite = py_trees.composites.Sequence


class Selector(_Memory):
    """Try the children in order until one does not fail (resumes at the running child)."""

    yaml_name = "selector"
    example = "e.g. 'selector: [{WallAhead: {}}, {MoveDistance: {distance: 10cm}}]'"
    composite = py_trees.composites.Selector


ReactiveSequence = Sequence.reactive(
    "Like sequence, but start again from the first child every tick (conditions stay checked).",
    "[{WallAhead: {}}, {TurnAngle: {angle: 90deg}}]",
)
ReactiveSelector = Selector.reactive(
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


class Parallel(ControlNode):
    """Tick every child each tick; succeed by the policy, fail as soon as one child fails."""

    yaml_name = "parallel"
    category = "composite"
    Params = ParallelParams
    example = "e.g. 'parallel: {policy: success_on_one, children: [...]}'"

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
