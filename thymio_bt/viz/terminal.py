"""The tree as text in the terminal: a mission's tree, its live statuses while a run goes (a tick
hook), the failing branch after it, and its coverage over runs (:mod:`thymio_bt.run.coverage`).
Its Graphviz picture is :mod:`thymio_bt.viz.graph`'s.

Example:

>>> from thymio_bt.mission import load_mission
>>> print(tree_text(load_mission("square")).rstrip())  # the mission's repeat, a sequence and two leaves
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

import sys
from collections.abc import Collection, Mapping
from typing import TYPE_CHECKING, Any

import py_trees

if TYPE_CHECKING:
    from thymio_bt.behaviours.flow.node import ControlNode
    from thymio_bt.plan.model import Mission
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


def tree_text(mission: Mission) -> str:
    """The mission's tree as py_trees draws it in a terminal (``thymio-bt tree``): built with no
    robot (behaviours touch it only when ticked)."""
    from thymio_bt.behaviours import Context
    from thymio_bt.mission import build_tree

    nobody = Context(robot=None, entities=None)  # type: ignore[arg-type]  # drawn, never ticked: no robot needed
    return py_trees.display.unicode_tree(build_tree(mission.tree, nobody, mission.registry))


def node_class(kind: str, registry: Registry | None) -> type[ControlNode]:
    """The class of a composite or decorator ``kind`` of ``registry``, whose ``symbol`` and ``family``
    say how it is drawn (a kind it lacks: :class:`ControlNode`'s, a decorator's)."""
    from thymio_bt.behaviours.flow.node import ControlNode
    from thymio_bt.plan.registry import control_kind

    return control_kind(kind, registry) or ControlNode


def _symbol(kind: str, registry: Registry | None = None) -> str:
    """The terminal symbol of a node ``kind``: its class's (``-->`` a behaviour)."""
    return "-->" if kind == "behaviour" else node_class(kind, registry).symbol


def counts_text(node: Mapping[str, Any], conditions: Collection[str]) -> str:
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
        lines.append(f"{text.ljust(width)}   {counts_text(node, conditions)}")
    return "\n".join(lines)
