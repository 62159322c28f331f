"""The YAML sequences and selectors and their BT.CPP twins (docs/btcpp.md, "Why two nodes for one
name"): on random children, the parent's status and how often each child is ticked are the same tick
for tick; what differs is the children's statuses once the parent completes (py_trees' keep theirs,
which the run report follows to the node that failed; BT.CPP's are reset to IDLE)."""

from __future__ import annotations

import random

import py_trees
import pytest
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours.flow import composites
from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.btcpp.runtime import control
from thymio_bt.btcpp.runtime import nodes as bn

S, F, R = Status.SUCCESS, Status.FAILURE, Status.RUNNING


class Scripted(Behaviour):
    """A child that returns its script's statuses in turn, and counts its ticks."""

    def __init__(self, name: str, script: list[Status]) -> None:
        super().__init__(name)
        self.script, self.ticks = script, 0

    def update(self) -> Status:
        self.ticks += 1
        return self.script[(self.ticks - 1) % len(self.script)]


#: YAML kind -> BT.CPP node of its twin
TWINS = {
    "sequence": bn.Sequence,
    "reactive_sequence": bn.ReactiveSequence,
    "selector": bn.Fallback,
    "reactive_selector": bn.ReactiveFallback,
}


def _yaml_kind(name: str) -> type:
    return next(kind for kind in composites.COMPOSITES if kind.yaml_name == name)


@pytest.mark.parametrize("name", TWINS)
def test_a_yaml_composite_and_its_btcpp_twin_tick_their_children_alike(name: str) -> None:
    kind = _yaml_kind(name)
    assert any(k.like is kind and k.make(name, [], {}, None).__class__ is TWINS[name] for k in control.BTCPP_CONTROL)
    rng = random.Random(name)
    reset_apart = 0
    for _ in range(300):
        scripts = [[rng.choice([S, F, R, R]) for _ in range(rng.randint(1, 5))] for _ in range(rng.randint(1, 4))]
        ours = kind.build("ours", kind.Params(), [Scripted(f"c{i}", s) for i, s in enumerate(scripts)], None)
        theirs = TWINS[name]("theirs", [Scripted(f"c{i}", s) for i, s in enumerate(scripts)])
        assert isinstance(ours, py_trees.composites.Composite)
        apart = False
        for _ in range(12):
            tick(ours)
            tick(theirs)
            assert ours.status == theirs.status
            assert [c.ticks for c in ours.children] == [c.ticks for c in theirs.children]
            apart |= [c.status for c in ours.children] != [c.status for c in theirs.children]
        reset_apart += apart
    assert reset_apart > 100  # the difference that keeps them two nodes
