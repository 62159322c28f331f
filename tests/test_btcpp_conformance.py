"""BT.CPP 4 itself (behaviortreepy) beside thymio-bt's BT.CPP nodes on thousands of generated trees
of built-ins over scripted leaves: the same leaves ticked in the same order, the same RUNNING
leaves halted, the same status at the same tick (#33). BT.CPP is driven by tickOnce()."""

import random

import pytest
from _btcpp_trees import (
    leaf_scripts,
    random_dense_tree,
    random_scripted_tree,
    random_tree,
    run_btcpp,
    run_btcpp_xml,
    scripted_document,
)
from _require import module
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.btcpp.runtime import decorators as bd
from thymio_bt.btcpp.runtime import nodes as bn

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


SCRIPTED_TREES = 3000


def build_scripted(node, calls, log, ctx):
    """thymio-bt's tree for a generated tree with scripts and pre/post-conditions."""
    from thymio_bt.btcpp.runtime import scripted as bs

    ident = node[0]
    if ident in ("Script", "ScriptCondition"):
        cls = bs.Script if ident == "Script" else bs.ScriptCondition
        built = cls(ident, cls.Params(code=node[1]), ctx)
    elif ident in ("AlwaysSuccess", "AlwaysFailure"):
        cls = bs.AlwaysSuccess if ident == "AlwaysSuccess" else bs.AlwaysFailure
        built = cls(ident, cls.Params(), ctx)
    elif ident == "Leaf":
        built = Leaf(node[2], node[1], calls, log)
    elif ident in ("RunOnce", "Precondition", "Switch2"):
        children = [build_scripted(child, calls, log, ctx) for child in node[2]]
        ports = node[1]
        if ident == "RunOnce":
            built = bd.RunOnce(ident, children[0], ports["then_skip"] == "true")
        elif ident == "Precondition":
            built = bs.Precondition(ident, children[0], bs.parse(ports["if"]), Status[ports["else"]])
        else:
            built = bs.Switch(ident, children, ports["variable"], [ports["case_1"], ports["case_2"]])
    else:
        children = [build_scripted(child, calls, log, ctx) for child in node[2]]
        built = build((ident, node[1], [("Leaf", "S", f"_{i}") for i in range(len(children))]), calls, log)
        for child in children:  # the generated children in place of the placeholders
            child.parent = built
        built.children[:] = children
        if isinstance(built, bd.BtDecorator):
            built.decorated = children[0]
    if len(node) > 3:
        from thymio_bt.btcpp.runtime.control import CONDITION_ATTRS

        scripts = {CONDITION_ATTRS[k]: bs.parse(v) for k, v in node[3].items()}
        built = bs.Conditioned(built.name, built, scripts)
    return built


def run_scripted_here(node, ticks):
    """thymio-bt's trace of a scripted tree (after ``v := 0; h := 0``) and its final v and h."""
    from types import SimpleNamespace

    from py_trees.blackboard import Blackboard

    from thymio_bt.btcpp.runtime import scripted as bs

    Blackboard.storage.clear()
    ctx = SimpleNamespace(robot=SimpleNamespace(exists=lambda: False), now=lambda: 0.0, collision_count=lambda: 0)
    calls, log = {}, []
    init = bs.Script("init", bs.Script.Params(code="v := 0; h := 0"), ctx)
    root = bn.Sequence("root", [init, build_scripted(node, calls, log, ctx)])
    trace = []
    for _ in range(ticks):
        try:
            tick(root)
            status = root.status.name
        except bn.NeverYields:
            raise
        except RuntimeError:  # as BT.CPP refuses it
            status = "ERROR"
        trace.append((tuple(log), status))
        log.clear()
        if status != "RUNNING":
            break
    board = {key: float(Blackboard.storage["/" + key]) for key in ("v", "h")}
    Blackboard.storage.clear()
    return trace, board


def scripted_difference(bt, tree, seed=None):
    """None when BT.CPP and thymio-bt run the scripted ``tree`` alike, else what differs; "never"
    when thymio-bt stops a tick that never yields (BT.CPP's tickOnce() would not return: not run there)."""
    try:
        got = run_scripted_here(tree, TICKS)
    except bn.NeverYields:
        return "never"
    expected = run_btcpp_xml(bt, scripted_document(tree), leaf_scripts(tree), TICKS)
    return None if expected == got else (seed, scripted_document(tree), expected, got)


def scripted_differences(bt, generator, seeds):
    """The differences over the trees ``generator`` makes from ``seeds``, and how many never yield."""
    results = [scripted_difference(bt, generator(random.Random(seed)), seed) for seed in seeds]
    return [r for r in results if r not in (None, "never")], results.count("never")


@pytest.mark.parametrize("chunk", range(3))
def test_generated_trees_with_scripts_and_conditions_run_as_in_behaviortree_cpp(chunk):
    bt = module("behaviortreepy")
    seeds = range(chunk * SCRIPTED_TREES // 3, (chunk + 1) * SCRIPTED_TREES // 3)
    differences, never = scripted_differences(bt, random_scripted_tree, seeds)
    assert not differences, (len(differences), differences[:1])
    assert never < SCRIPTED_TREES // 100


DENSE_TREES = 2000


@pytest.mark.parametrize("chunk", range(2))
def test_trees_dense_in_conditions_run_as_in_behaviortree_cpp(chunk):
    """Small trees with conditions on half their nodes, RunOnce, Precondition and Switch2: a skipped
    branch under IfThenElse/WhileDoElse left RUNNING, then halted with its _onHalted (#33)."""
    bt = module("behaviortreepy")
    seeds = range(chunk * DENSE_TREES // 2, (chunk + 1) * DENSE_TREES // 2)
    differences, never = scripted_differences(bt, random_dense_tree, seeds)
    assert not differences, (len(differences), differences[:1])
    assert never < DENSE_TREES // 100


#: the scripted seeds that differed before #33's fixes (found among 0..40000 of each generator):
#: IfThenElse/WhileDoElse halted themselves (IDLE) after a SKIPPED branch, where BT.CPP only resets
#: their children and stays RUNNING, so a later halt runs their _onHalted
REGRESSIONS = [
    *((random_scripted_tree, seed) for seed in (7625, 10018, 15296, 16578, 17850, 39149)),
    *((random_dense_tree, seed) for seed in (2846, 5058, 6567, 12810)),
]
#: a pre-condition's status (_failureIf...) is the status of the node it is on: a leaf ticked again
#: un-reset (a WhileDoElse's condition) returns it without running
REGRESSIONS_CONDITIONED = [(random_scripted_tree, s) for s in (6270, 19793, 35855, 38670)]


@pytest.mark.parametrize(("generator", "seed"), [*REGRESSIONS, *REGRESSIONS_CONDITIONED])
def test_seeds_that_differed_run_as_in_behaviortree_cpp(generator, seed):
    bt = module("behaviortreepy")
    assert scripted_difference(bt, generator(random.Random(seed)), seed) is None


#: hand-written trees for what no generated seed met
SEQUENCE_KEEPS_SKIPPED_COUNT = (  # BT.CPP's Sequence keeps skipped_count_ after a FAILURE: ticked
    "WhileDoElse",  # again un-reset (a WhileDoElse's condition), it counts on: all skipped, SKIPPED
    {},
    [
        ("Sequence", {}, [("AlwaysSuccess", "", "", {"_skipIf": "true"}), ("Leaf", "FS", "L1")]),
        ("Leaf", "S", "L2"),
        ("Leaf", "R", "L3"),
    ],
)
FORCED_STATUS_STAYS = (  # L1 is FAILURE by _failureIf: re-ticked un-reset, it is FAILURE again
    "WhileDoElse",  # without running (a stateful action), and its _onFailure runs again
    {},
    [
        ("Leaf", "S", "L1", {"_failureIf": "v == 0", "_onFailure": "h += 1"}),
        ("Leaf", "S", "L2"),
        ("Leaf", "RRS", "L3"),
    ],
)


@pytest.mark.parametrize(
    "tree",
    [
        pytest.param(SEQUENCE_KEEPS_SKIPPED_COUNT, id="sequence-keeps-skipped-count"),
        pytest.param(FORCED_STATUS_STAYS, id="forced-status-stays"),
    ],
)
def test_hand_written_trees_run_as_in_behaviortree_cpp(tree):
    bt = module("behaviortreepy")
    assert scripted_difference(bt, tree) is None
