"""BT.CPP 4 itself (behaviortreepy) beside thymio-bt's BT.CPP nodes on thousands of generated trees
of built-ins over scripted leaves: the same leaves ticked in the same order, the same RUNNING
leaves halted, the same status at the same tick (#33). BT.CPP is driven by tickOnce()."""

import random

import pytest
from _btcpp_trees import random_tree, run_btcpp
from _require import module
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours import btcpp_decorators as bd
from thymio_bt.behaviours import btcpp_nodes as bn
from thymio_bt.behaviours.ticking import tick

TICKS = 15
TREES = 8000


class Leaf(Behaviour):
    """A leaf that returns its script's next status each time it is ticked (the last one repeats)."""

    def __init__(self, name, script, calls, log):
        super().__init__(name=name)
        self.script, self.calls, self.log = script, calls, log

    def update(self):
        index = self.calls.get(self.name, 0)
        self.calls[self.name] = index + 1
        self.log.append(("t", self.name))
        code = self.script[min(index, len(self.script) - 1)]
        return {"S": Status.SUCCESS, "F": Status.FAILURE, "R": Status.RUNNING}[code]

    def terminate(self, new_status):
        if new_status is Status.INVALID and self.status is Status.RUNNING:
            self.log.append(("h", self.name))


def build(node, calls, log):
    """thymio-bt's tree of BT.CPP nodes for a generated tree."""
    if node[0] == "Leaf":
        return Leaf(node[2], node[1], calls, log)
    ident, ports, children = node
    kids = [build(child, calls, log) for child in children]
    if ident == "Parallel":
        return bn.Parallel(ident, kids, ports["success_count"], ports["failure_count"])
    if ident == "ParallelAll":
        return bn.ParallelAll(ident, kids, ports["max_failures"])
    if ident == "Repeat":
        return bd.Repeat(ident, kids[0], ports["num_cycles"])
    if ident == "RetryUntilSuccessful":
        return bd.RetryUntilSuccessful(ident, kids[0], ports["num_attempts"])
    cls = getattr(bn, ident, None) or getattr(bd, ident)
    return cls(ident, kids[0]) if issubclass(cls, bd.BtDecorator) else cls(ident, kids)


def run_here(node, ticks):
    """thymio-bt's trace, as :func:`run_btcpp` writes BT.CPP's."""
    calls, log = {}, []
    root = build(node, calls, log)
    trace = []
    for _ in range(ticks):
        tick(root)
        trace.append((tuple(log), root.status.name))
        log.clear()
        if root.status is not Status.RUNNING:
            break
    return trace


@pytest.mark.parametrize("chunk", range(6))
def test_generated_trees_tick_as_in_behaviortree_cpp(chunk):
    bt = module("behaviortreepy")
    differences = []
    for seed in range(chunk * TREES // 6, (chunk + 1) * TREES // 6):
        tree = random_tree(random.Random(seed))
        expected, got = run_btcpp(bt, tree, TICKS), run_here(tree, TICKS)
        if expected != got:
            differences.append((seed, tree, expected, got))
    assert not differences, differences[:1]
