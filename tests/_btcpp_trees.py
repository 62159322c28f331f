"""Random trees of BT.CPP built-ins over scripted leaves, run by BT.CPP itself (behaviortreepy) and by
thymio-bt's BT.CPP nodes, each run written as the same per-tick trace (#33)."""

import random

#: BT.CPP node ID -> (min children, max children, ports maker)
CONTROLS = {
    "Sequence": (1, 4, None),
    "SequenceWithMemory": (1, 4, None),
    "ReactiveSequence": (1, 3, None),
    "Fallback": (1, 4, None),
    "ReactiveFallback": (1, 3, None),
    "Parallel": (1, 4, "parallel"),
    "ParallelAll": (1, 4, "parallel_all"),
    "IfThenElse": (2, 3, None),
    "WhileDoElse": (2, 3, None),
    "Inverter": (1, 1, None),
    "ForceSuccess": (1, 1, None),
    "ForceFailure": (1, 1, None),
    "Repeat": (1, 1, "repeat"),
    "RetryUntilSuccessful": (1, 1, "retry"),
    "KeepRunningUntilFailure": (1, 1, None),
}
STATUSES = "SFR"


def random_tree(rng: random.Random, depth: int = 0, counter=None) -> tuple:
    """(ID, ports, children) or ("Leaf", script, name): a random tree of BT.CPP's built-ins."""
    counter = counter if counter is not None else [0]
    if depth >= 4 or rng.random() < 0.15 + 0.15 * depth:
        counter[0] += 1
        script = "".join(rng.choice("SFRR") for _ in range(rng.randint(1, 5)))
        if rng.random() < 0.5:
            script += rng.choice("SF")  # most leaves settle, so that trees end
        return ("Leaf", script, f"L{counter[0]}")
    ident = rng.choice(sorted(CONTROLS))
    low, high, kind = CONTROLS[ident]
    children = [random_tree(rng, depth + 1, counter) for _ in range(rng.randint(low, high))]
    n = len(children)
    ports = {}
    if kind == "parallel":
        ports = {
            "success_count": rng.choice([-1, *range(1, n + 1)]),
            "failure_count": rng.choice([-1, *range(1, n + 1)]),
        }
    elif kind == "parallel_all":
        ports = {"max_failures": rng.choice([-1, *range(1, n + 1)])}
    elif kind == "repeat":
        ports = {"num_cycles": rng.randint(1, 3)}
    elif kind == "retry":
        ports = {"num_attempts": rng.randint(1, 3)}
    return (ident, ports, children)


def to_xml(node: tuple) -> str:
    """The tree as BT.CPP XML (leaves are ``<L name=...>``)."""
    if node[0] == "Leaf":
        return f'<L name="{node[2]}"/>'
    ident, ports, children = node
    attrs = "".join(f' {k}="{v}"' for k, v in ports.items())
    return f"<{ident}{attrs}>" + "".join(to_xml(c) for c in children) + f"</{ident}>"


def document(node: tuple) -> str:
    """A whole BT.CPP 4 XML document of one tree."""
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{to_xml(node)}</BehaviorTree></root>'


def scripts(node: tuple, out=None) -> dict:
    """Each leaf's script by name."""
    out = {} if out is None else out
    if node[0] == "Leaf":
        out[node[2]] = node[1]
    else:
        for child in node[2]:
            scripts(child, out)
    return out


def scripted_factory(bt, plan: dict) -> tuple:
    """A BT.CPP factory whose leaf ``L`` returns, at each tick, the next status of its script in
    ``plan`` (by the leaf's name; the last one repeats), and the log it appends ticks ("t", name)
    and halts ("h", name) to."""
    codes = {"S": bt.NodeStatus.SUCCESS, "F": bt.NodeStatus.FAILURE, "R": bt.NodeStatus.RUNNING}
    calls, log = {}, []

    def step(leaf):
        name = leaf.name()
        index = calls.get(name, 0)
        calls[name] = index + 1
        log.append(("t", name))
        script = plan[name]
        return codes[script[min(index, len(script) - 1)]]

    factory = bt.BehaviorTreeFactory()
    factory.register_simple_stateful_action("L", step, step, lambda leaf: log.append(("h", leaf.name())))
    return factory, log


def run_btcpp(bt, node: tuple, ticks: int) -> list:
    """BT.CPP's trace: per tickOnce(), the leaves ticked ("t", name) and halted ("h", name) in
    order, and the tree's status; it stops when the tree completes."""
    factory, log = scripted_factory(bt, scripts(node))
    tree = factory.create_tree_from_text(document(node))
    trace = []
    for _ in range(ticks):
        status = tree.tick_once()
        trace.append((tuple(log), status.name))
        log.clear()
        if status.name != "RUNNING":
            break
    return trace


#: pre/post-condition attributes a generated node may carry (over the entries v and h)
CONDITIONS = {
    "_skipIf": ["v > 2", "v == 1", "false"],
    "_successIf": ["v >= 3", "v == 2"],
    "_failureIf": ["v == 4", "v > 5"],
    "_while": ["v < 4", "v != 3"],
    "_onSuccess": ["v += 1", "v := v * 2"],
    "_onFailure": ["v -= 1", "v := 0"],
    "_onHalted": ["h += 1"],
    "_post": ["h := h + 2"],
}
SCRIPTS = ["v += 1", "v := v > 2 ? 0 : v + 1", "h := h + v", "v := (v + 3) * 2 - v"]
CHECKS = ["v > 1", "v == 0 || h > 2", "!(v < 2) && h >= 0", "v + h > 3"]


def random_scripted_tree(rng: random.Random, depth: int = 0, counter=None) -> tuple:
    """A random tree with scripts: Script / ScriptCondition / AlwaysSuccess leaves besides the
    scripted ones, and BT.CPP's pre/post-condition attributes on some nodes (as a 4th element)."""
    counter = counter if counter is not None else [0]
    if depth < 4 and rng.random() >= 0.15 + 0.15 * depth:
        ident = rng.choice(sorted(CONTROLS))
        low, high, _ = CONTROLS[ident]
        children = [random_scripted_tree(rng, depth + 1, counter) for _ in range(rng.randint(low, high))]
        node = (ident, _ports(rng, ident, len(children)), children)
    else:
        node = _scripted_leaf(rng, counter, (0.2, 0.35, 0.42))
    return _conditioned(rng, node, 0.35, CONDITIONS, 2)


def _scripted_leaf(rng: random.Random, counter: list, cuts: tuple[float, float, float]) -> tuple:
    """A Script, ScriptCondition, AlwaysSuccess/Failure or scripted leaf, by where a draw falls
    among ``cuts``."""
    roll = rng.random()
    if roll < cuts[0]:
        return ("Script", rng.choice(SCRIPTS), "")
    if roll < cuts[1]:
        return ("ScriptCondition", rng.choice(CHECKS), "")
    if roll < cuts[2]:
        return (rng.choice(["AlwaysSuccess", "AlwaysFailure"]), "", "")
    return random_tree(rng, 99, counter)


def _conditioned(rng: random.Random, node: tuple, chance: float, table: dict, most: int) -> tuple:
    """``node`` with 1 to ``most`` pre/post-condition attributes of ``table``, with probability ``chance``."""
    if rng.random() < chance:
        keys = rng.sample(sorted(table), rng.randint(1, most))
        node = (*node, {k: rng.choice(table[k]) for k in keys})
    return node


def _ports(rng: random.Random, ident: str, n: int) -> dict:
    """Valid ports of a control node of ``n`` children."""
    kind = CONTROLS[ident][2]
    if kind == "parallel":
        return {
            "success_count": rng.choice([-1, *range(1, n + 1)]),
            "failure_count": rng.choice([-1, *range(1, n + 1)]),
        }
    if kind == "parallel_all":
        return {"max_failures": rng.choice([-1, *range(1, n + 1)])}
    if kind == "repeat":
        return {"num_cycles": rng.randint(1, 3)}
    if kind == "retry":
        return {"num_attempts": rng.randint(1, 3)}
    return {}


#: the dense trees' extra nodes: ID -> (min children, max children)
DENSE_EXTRA = {"RunOnce": (1, 1), "Precondition": (1, 1), "Switch2": (3, 3)}
#: the dense trees' conditions: constant ones too, so that nodes are often skipped
DENSE_CONDITIONS = {
    "_skipIf": ["true", "false", "v > 1", "h > 0"],
    "_successIf": ["v == 2", "h > 1", "false"],
    "_failureIf": ["v == 3", "v + h > 4", "false"],
    "_while": ["true", "v < 3", "h < 2", "v != 1"],
    "_onSuccess": ["v += 1", "h += 1"],
    "_onFailure": ["v -= 1", "h := h + 1"],
    "_onHalted": ["h += 1", "v += 2"],
    "_post": ["v := v > 3 ? 0 : v + 1"],
}


def random_dense_tree(rng: random.Random, depth: int = 0, counter=None) -> tuple:
    """A small tree dense in pre/post-conditions (half its nodes), with RunOnce, Precondition and
    Switch2 besides :data:`CONTROLS`: skips, halts and scripts meet more often than in
    :func:`random_scripted_tree` (whose seeds are unchanged)."""
    counter = counter if counter is not None else [0]
    if depth < 3 and rng.random() >= 0.2 + 0.2 * depth:
        ident = rng.choice(sorted(CONTROLS) + sorted(DENSE_EXTRA))
        low, high = DENSE_EXTRA.get(ident) or CONTROLS[ident][:2]
        children = [random_dense_tree(rng, depth + 1, counter) for _ in range(rng.randint(low, min(high, 3)))]
        node = (ident, _dense_ports(rng, ident, len(children)), children)
    else:
        node = _scripted_leaf(rng, counter, (0.2, 0.3, 0.4))
    return _conditioned(rng, node, 0.5, DENSE_CONDITIONS, 3)


def _dense_ports(rng: random.Random, ident: str, n: int) -> dict:
    """Valid ports of a dense tree's control node."""
    if ident == "RunOnce":
        return {"then_skip": rng.choice(["true", "false"])}
    if ident == "Precondition":
        return {"if": rng.choice(["v > 1", "h == 0", "true", "false"]), "else": rng.choice(["SUCCESS", "FAILURE"])}
    if ident == "Switch2":
        return {"variable": "{v}", "case_1": str(rng.randint(0, 2)), "case_2": str(rng.randint(1, 3))}
    return _ports(rng, ident, n)


def to_scripted_xml(node: tuple) -> str:
    """A scripted tree as BT.CPP XML."""
    attrs = "".join(f' {k}="{v}"' for k, v in (node[3] if len(node) > 3 else {}).items())
    ident = node[0]
    if ident == "Leaf":
        return f'<L name="{node[2]}"{attrs}/>'
    if ident in ("Script", "ScriptCondition"):
        return f'<{ident} code="{node[1]}"{attrs}/>'
    if ident in ("AlwaysSuccess", "AlwaysFailure"):
        return f"<{ident}{attrs}/>"
    ports = "".join(f' {k}="{v}"' for k, v in node[1].items())
    return f"<{ident}{ports}{attrs}>" + "".join(to_scripted_xml(c) for c in node[2]) + f"</{ident}>"


def scripted_document(node: tuple) -> str:
    """The whole document: the entries v and h set to 0 first, then the tree."""
    body = '<Sequence><Script code="v := 0; h := 0"/>' + to_scripted_xml(node) + "</Sequence>"
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


def leaf_scripts(node: tuple, out=None) -> dict:
    """Each scripted leaf's script by name, in a scripted tree."""
    out = {} if out is None else out
    if node[0] == "Leaf":
        out[node[2]] = node[1]
    elif isinstance(node[2], list):
        for child in node[2]:
            leaf_scripts(child, out)
    return out


def run_btcpp_xml(bt, xml: str, plan: dict, ticks: int) -> tuple[list, dict]:
    """BT.CPP's trace of a whole XML document (leaves ``L`` scripted by ``plan``) and its final
    entries v and h."""
    factory, log = scripted_factory(bt, plan)
    tree = factory.create_tree_from_text(xml)
    trace = []
    for _ in range(ticks):
        try:
            status = tree.tick_once().name
        except RuntimeError:  # BT.CPP refuses what happened (e.g. a skipped IfThenElse condition)
            status = "ERROR"
        trace.append((tuple(log), status))
        log.clear()
        if status != "RUNNING":
            break
    board = tree.root_blackboard()
    return trace, {key: board.get_double(key) for key in ("v", "h")}
