"""A tree as a Graphviz picture: .dot text always, .svg/.png drawn by Graphviz's ``dot`` program
when it is installed (``tree --dot/--svg/--png``, ``run --coverage-tree``), with the coverage of
runs drawn on it when given (:mod:`thymio_bt.run.coverage`). Each kind is drawn as its class says
(its ``family`` and ``node_keys``)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from collections.abc import Collection, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from thymio_bt.errors import UserError
from thymio_bt.viz.terminal import counts_text, node_class

if TYPE_CHECKING:
    from thymio_bt.outputs import Output
    from thymio_bt.plan.model import NodePlan
    from thymio_bt.plan.registry import Registry


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
    return "behaviour" if kind == "behaviour" else node_class(kind, registry).family


def _quoted(text: str) -> str:
    """``text`` as a Graphviz quoted string (lines joined by ``\\n``)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _role(kind: str, position: int, registry: Registry | None) -> str | None:
    """The role of a decorator's child at ``position`` that is not its ``do`` (a repeat's ``until``, a
    guard's ``condition``: its kind's ``node_keys``), written on the edge; None for an ordinary child."""
    keys = () if kind == "behaviour" else node_class(kind, registry).node_keys
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
        counts = "" if conditions is None else f"\n{counts_text(node, conditions)}"
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
