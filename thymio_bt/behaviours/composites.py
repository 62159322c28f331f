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

from typing import Any, Literal

import py_trees
from py_trees.common import ParallelPolicy
from pydantic import Field, field_validator

from thymio_bt.behaviours.control_node import ControlNode, ControlParams, refuse


class Sequence(ControlNode):
    """Run the children in order; fail at the first failure (resumes at the running child)."""

    yaml_name = "sequence"
    category = "composite"
    example = "e.g. 'sequence: [{MoveUntilWall: {}}, {TurnAngle: {angle: 90deg}}]'"

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> py_trees.behaviour.Behaviour:
        """A py_trees ``Sequence`` with memory."""
        return py_trees.composites.Sequence(name, memory=True, children=children)


class ReactiveSequence(ControlNode):
    """Like sequence, but start again from the first child every tick (conditions stay checked)."""

    yaml_name = "reactive_sequence"
    category = "composite"
    example = "e.g. 'reactive_sequence: [{WallAhead: {}}, {TurnAngle: {angle: 90deg}}]'"

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> py_trees.behaviour.Behaviour:
        """A py_trees ``Sequence`` without memory."""
        return py_trees.composites.Sequence(name, memory=False, children=children)


class Selector(ControlNode):
    """Try the children in order until one does not fail (resumes at the running child)."""

    yaml_name = "selector"
    category = "composite"
    example = "e.g. 'selector: [{WallAhead: {}}, {MoveDistance: {distance: 10cm}}]'"

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> py_trees.behaviour.Behaviour:
        """A py_trees ``Selector`` with memory."""
        return py_trees.composites.Selector(name, memory=True, children=children)


class ReactiveSelector(ControlNode):
    """Like selector, but re-try the higher-priority children every tick."""

    yaml_name = "reactive_selector"
    category = "composite"
    example = "e.g. 'reactive_selector: [{ObstacleAhead: {}}, {GoToPose: {goal: [1, 0, 0]}}]'"

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> py_trees.behaviour.Behaviour:
        """A py_trees ``Selector`` without memory."""
        return py_trees.composites.Selector(name, memory=False, children=children)


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
