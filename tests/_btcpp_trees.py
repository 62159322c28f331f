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


def run_btcpp(bt, node: tuple, ticks: int) -> list:
    """BT.CPP's trace: per tickOnce(), the leaves ticked ("t", name) and halted ("h", name) in
    order, and the tree's status; it stops when the tree completes."""
    codes = {"S": bt.NodeStatus.SUCCESS, "F": bt.NodeStatus.FAILURE, "R": bt.NodeStatus.RUNNING}
    plan, calls, log = scripts(node), {}, []

    def step(leaf):
        name = leaf.name()
        index = calls.get(name, 0)
        calls[name] = index + 1
        log.append(("t", name))
        script = plan[name]
        return codes[script[min(index, len(script) - 1)]]

    factory = bt.BehaviorTreeFactory()
    factory.register_simple_stateful_action("L", step, step, lambda leaf: log.append(("h", leaf.name())))
    tree = factory.create_tree_from_text(document(node))
    trace = []
    for _ in range(ticks):
        status = tree.tick_once()
        trace.append((tuple(log), status.name))
        log.clear()
        if status.name != "RUNNING":
            break
    return trace
