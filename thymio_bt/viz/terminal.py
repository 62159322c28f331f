"""The tree in the terminal: live statuses while a run goes, the failing branch after it, its
coverage over runs (:mod:`thymio_bt.run.coverage`), and exports to Graphviz (.dot always; .svg/.png
when Graphviz's ``dot`` program is installed), with the coverage drawn on it when given.

Example:

>>> print(tree_text(Path("square")).rstrip())  # the mission's repeat, a sequence and two leaves
-^- four sides
    {-} side
        --> MoveDistance
        --> TurnAngle
>>> node = {"path": "f", "name": "f", "kind": "selector", "behaviour": None, "where": "m.yaml:3", "depth": 0,
...         "ticks": 9, "success": 1, "failure": 0, "running": 8, "ended_by": {"f/go": 1}}
>>> check = {**node, "path": "f/near", "name": "near", "kind": "behaviour", "behaviour": "WallAhead",
...          "depth": 1, "running": 0, "success": 0, "failure": 9, "ended_by": {}}
>>> go = {**check, "path": "f/go", "name": "go", "behaviour": "MoveDistance", "success": 1, "failure": 0, "running": 8}
>>> print(coverage_text({"runs": 1, "nodes": [node, check, go]}, conditions={"WallAhead"}))
tree coverage over 1 run: 3 of 3 nodes ticked
{o} f          9 ticks: success 1, failure 0, running 8; ended by go x1
    --> near   9 ticks: true 0, false 9 (never true)
    --> go     9 ticks: success 1, failure 0, running 8
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections.abc import Collection, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import py_trees

from thymio_bt.errors import UserError

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from thymio_bt.behaviours.flow.node import ControlNode
    from thymio_bt.outputs import Output
    from thymio_bt.plan.model import NodePlan
    from thymio_bt.plan.registry import Registry
    from thymio_bt.run.runner import Run


class LiveTree:
    """An ``on_tick`` hook printing the tree with statuses and feedback whenever a status changes."""

    def __init__(self, stream: Any = None) -> None:
        self.stream = stream or sys.stdout
        self.last: tuple[Any, ...] | None = None
        self.clear = self.stream.isatty() if hasattr(self.stream, "isatty") else False

    def __call__(self, run: Run) -> None:
        """Print the tree if any node's status changed with this tick."""
        state = tuple((n.id, n.status) for n in run.root.iterate())
        if state == self.last:
            return
        self.last = state
        text = py_trees.display.unicode_tree(run.root, show_status=True)
        prefix = "\x1b[H\x1b[2J" if self.clear else ""
        self.stream.write(f"{prefix}t = {run.backend.time():.1f} s\n{text}\n")
        self.stream.flush()


def failing_tree(run: Run) -> str:
    """The tree with the statuses it had when the run ended, for the end of a failed run."""
    return "the tree when the run ended:\n" + run.final_tree


def _build(mission_path: Path, run_plugins: bool = False) -> Behaviour:
    """The mission's py_trees tree, to draw: built with no robot (behaviours touch it only when ticked);
    its plugins are read, not imported, unless ``run_plugins``."""
    from thymio_bt.behaviours import Context
    from thymio_bt.mission import build_tree, load_mission

    mission = load_mission(mission_path, run_plugins=run_plugins)
    nobody = Context(robot=None, entities=None)  # type: ignore[arg-type]  # drawn, never ticked: no robot needed
    return build_tree(mission.tree, nobody, mission.registry)


def tree_text(mission_path: Path, run_plugins: bool = False) -> str:
    """The mission's tree as py_trees draws it in a terminal (``thymio-bt tree``)."""
    return py_trees.display.unicode_tree(_build(mission_path, run_plugins))


def export_tree(
    mission_path: Path,
    out: Output,
    fmt: str,
    run_plugins: bool = False,
    coverage: Mapping[str, Any] | None = None,
    conditions: Collection[str] = (),
    registry: Registry | None = None,
) -> None:
    """Write the tree to ``out`` as Graphviz .dot text, or as .svg/.png drawn by Graphviz's ``dot``;
    with ``coverage`` (a coverage JSON of this mission), the tree drawn with its counts (``conditions``
    as in :func:`coverage_dot`, its kinds drawn as in ``registry``)."""
    if coverage is None:
        from thymio_bt.mission import load_mission

        mission = load_mission(mission_path, run_plugins=run_plugins)
        source = plan_dot(mission.tree, mission.registry)
    else:
        source = coverage_dot(coverage, conditions, registry)
    write_graph(source, out, fmt, f"thymio-bt tree {mission_path} --dot -o {Path(str(out)).stem}.dot")


def write_graph(source: str, out: Output, fmt: str, instead: str) -> None:
    """Write the Graphviz ``source`` to ``out``: as it is for ``fmt`` dot, else drawn by Graphviz's
    ``dot`` (``instead``: the command that writes the .dot, for the hint when it is not installed)."""
    if fmt == "dot":
        out.write_text(source)
        return
    program = shutil.which("dot")
    if program is None:
        raise UserError(
            f"a .{fmt} needs Graphviz's 'dot' program (hint: apt-get install graphviz, or write the .dot: {instead})"
        )
    if out.is_stdout:
        sys.stdout.buffer.write(
            subprocess.run([program, f"-T{fmt}"], input=source.encode(), check=True, capture_output=True).stdout
        )
        return
    with out.staged() as tmp:
        subprocess.run([program, f"-T{fmt}", "-o", str(tmp)], input=source.encode(), check=True)


def _kind(kind: str, registry: Registry | None) -> type[ControlNode]:
    """The class of a composite or decorator ``kind`` of ``registry``, whose ``symbol`` and ``family``
    say how it is drawn (a kind it lacks: :class:`ControlNode`'s, a decorator's)."""
    from thymio_bt.behaviours.flow.node import ControlNode
    from thymio_bt.plan.registry import control_kind

    return control_kind(kind, registry) or ControlNode


def _symbol(kind: str, registry: Registry | None = None) -> str:
    """The terminal symbol of a node ``kind``: its class's (``-->`` a behaviour)."""
    return "-->" if kind == "behaviour" else _kind(kind, registry).symbol


def _counts(node: Mapping[str, Any], conditions: Collection[str]) -> str:
    """What a node's coverage says: its ticks and results, or that it never ran."""
    if not node["ticks"]:
        return "never ticked"
    ticks = f"{node['ticks']} tick{'s' * (node['ticks'] != 1)}"
    if node["behaviour"] in conditions:
        never = " (never true)" if not node["success"] else " (never false)" if not node["failure"] else ""
        return f"{ticks}: true {node['success']}, false {node['failure']}{never}"
    text = f"{ticks}: success {node['success']}, failure {node['failure']}, running {node['running']}"
    if node["ended_by"]:
        enders = ", ".join(f"{path.rpartition('/')[2]} x{n}" for path, n in node["ended_by"].items())
        text += f"; ended by {enders}"
    return text


def coverage_text(
    coverage: Mapping[str, Any], conditions: Collection[str] = (), registry: Registry | None = None
) -> str:
    """The tree with each node's coverage (``run --coverage``): ticks and results (``conditions``, the
    behaviour names of conditions, as true and false), the child that ended each composite, and
    the nodes that never ran (each kind drawn as its class in ``registry`` says: the default one
    unless given)."""
    nodes = coverage["nodes"]
    runs = coverage["runs"]
    ticked = sum(1 for n in nodes if n["ticks"])
    lines = [f"tree coverage over {runs} run{'s' * (runs != 1)}: {ticked} of {len(nodes)} nodes ticked"]
    left = ["    " * n["depth"] + f"{_symbol(n['kind'], registry)} {n['name']}" for n in nodes]
    width = min(max((len(text) for text in left), default=0), 60)
    for text, node in zip(left, nodes, strict=True):
        lines.append(f"{text.ljust(width)}   {_counts(node, conditions)}")
    return "\n".join(lines)


#: how each node family is drawn in a Graphviz picture (shape, fill when ticked), like py_trees' dot
#: ("": any other composite or decorator)
_DOT_LOOK = {
    "sequence": ("box", "#ff9900"),
    "selector": ("octagon", "#00ffff"),
    "parallel": ("parallelogram", "#ffd700"),
    "": ("ellipse", "#f8f8ff"),
    "behaviour": ("ellipse", "#d3d3d3"),
}


def _family(kind: str, registry: Registry | None) -> str:
    """A node kind's family for drawing: its class's, or behaviour."""
    return "behaviour" if kind == "behaviour" else _kind(kind, registry).family


def _quoted(text: str) -> str:
    """``text`` as a Graphviz quoted string (lines joined by ``\\n``)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _role(kind: str, position: int, registry: Registry | None) -> str | None:
    """The role of a decorator's child at ``position`` that is not its ``do`` (a repeat's ``until``, a
    guard's ``condition``: its kind's ``node_keys``), written on the edge; None for an ordinary child."""
    keys = () if kind == "behaviour" else _kind(kind, registry).node_keys
    return keys[position - 1] if 0 < position <= len(keys) else None


def _label(node: Mapping[str, Any]) -> str:
    """A node's name, and under it what it is (its behaviour or kind) when the name does not say it."""
    what = node["behaviour"] or node["kind"]
    return node["name"] if what == node["name"] else f"{node['name']}\n{what}"


def plan_dot(plan: NodePlan, registry: Registry | None = None) -> str:
    """The mission's tree (``tree --dot/--svg/--png``) as Graphviz .dot text, drawn as
    :func:`coverage_dot` draws it without counts: a repeat's ``until`` and a guard's ``condition``
    on a dashed edge that says so, not as one more child.

    >>> from thymio_bt.mission import load_mission
    >>> print(plan_dot(load_mission("maze_part1_2").tree))  # doctest: +ELLIPSIS
    digraph tree {
    ...
    n... -> n... [label="until", style=dashed];
    ...
    """
    from thymio_bt.run.coverage import plan_paths

    nodes = [
        {"path": path, "name": n.name, "kind": n.kind, "behaviour": n.behaviour, "depth": depth}
        for n, path, depth in plan_paths(plan)
    ]
    return _dot("tree", nodes, None, registry)


def coverage_dot(
    coverage: Mapping[str, Any], conditions: Collection[str] = (), registry: Registry | None = None
) -> str:
    """The tree as Graphviz .dot text with each node's coverage: its counts under its name, the nodes
    that never ran dashed and grey, each edge labelled with how often that child ended its parent.

    >>> node = {"path": "s", "name": "s", "kind": "sequence", "behaviour": None, "where": "m.yaml:3", "depth": 0,
    ...         "ticks": 0, "success": 0, "failure": 0, "running": 0, "ended_by": {}}
    >>> print(coverage_dot({"runs": 1, "nodes": [node]}))  # doctest: +NORMALIZE_WHITESPACE
    digraph coverage {
    graph [ordering=out, fontname="sans"];
    node [fontname="sans", fontsize=10];
    edge [fontname="sans", fontsize=9];
    n0 [label="s\\nsequence\\nnever ticked", shape=box, style=dashed, color=grey60, fontcolor=grey45];
    }
    """
    return _dot("coverage", coverage["nodes"], conditions, registry)


def _dot(
    name: str, nodes: Sequence[Mapping[str, Any]], conditions: Collection[str] | None, registry: Registry | None
) -> str:
    """The .dot text of the tree ``nodes`` (pre-order, with depths), with their coverage counts
    unless ``conditions`` is None (a tree without coverage: every node filled), each kind drawn as
    its class in ``registry`` says."""
    lines = [f"digraph {name} {{", 'graph [ordering=out, fontname="sans"];', 'node [fontname="sans", fontsize=10];']
    lines.append('edge [fontname="sans", fontsize=9];')
    stack: list[tuple[int, Mapping[str, Any]]] = []  # the ancestors of the node being drawn
    children: dict[int, int] = {}  # how many children of each node are drawn so far
    for i, node in enumerate(nodes):
        shape, fill = _DOT_LOOK[_family(node["kind"], registry)]
        counts = "" if conditions is None else f"\n{_counts(node, conditions)}"
        label = _quoted(_label(node) + counts)
        if conditions is None or node["ticks"]:
            look = f'style=filled, fillcolor="{fill}"'
            if conditions is not None and node["behaviour"] in conditions and not node["success"]:
                look += ", color=red, penwidth=2"
        else:
            look = "style=dashed, color=grey60, fontcolor=grey45"
        lines.append(f"n{i} [label={label}, shape={shape}, {look}];")
        while stack and nodes[stack[-1][0]]["depth"] >= node["depth"]:
            stack.pop()
        if stack:
            parent, data = stack[-1]
            position = children[parent] = children.get(parent, -1) + 1
            role = _role(data["kind"], position, registry)
            ended = data.get("ended_by", {}).get(node["path"])
            words = [w for w in (role, f"ended it x{ended}" if ended else None) if w]
            attributes = [f"label={_quoted(' / '.join(words))}"] if words else []
            attributes += ["style=dashed"] if role else []
            edge = f" [{', '.join(attributes)}]" if attributes else ""
            lines.append(f"n{parent} -> n{i}{edge};")
        stack.append((i, node))
    lines.append("}")
    return "\n".join(lines) + "\n"
