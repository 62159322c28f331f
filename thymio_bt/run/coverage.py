"""Tree coverage: how often each node of a mission's tree was ticked, what it returned, which child
ended each composite, and which nodes never ran, over one run or many.

Two halves. :class:`NodeStats` watches one run (``Run(mission, seed, node_stats=True)``): every node
of the built tree, a guard's condition too, counts its own ticks however it is ticked (py_trees'
generators, the direct tick of :mod:`thymio_bt.behaviours.flow.ticking`, BT.CPP's ``executeTick``), and
its table is the run's ``node_stats``. :class:`Coverage` holds the counts of every node of the
mission's plan (so a node never ticked is there too), adds runs' tables and merges other coverages:
its JSON is the ``coverage`` of the run report (``run --coverage``), the sweep JSON and ``grade``.

Example (three runs of the bonus maze; the dead-end check ends the loop once per run):

>>> from thymio_bt.mission import load_mission
>>> from thymio_bt.run.runner import Run
>>> mission = load_mission("maze_bonus")
>>> cov = Coverage.of(mission.tree)
>>> for seed in range(3):
...     _ = cov.add(Run(mission, seed, node_stats=True).run().node_stats)
>>> data = cov.to_json()
>>> data["runs"], data["never_ticked"]
(3, [])
>>> loop = data["nodes"][0]
>>> loop["path"], loop["kind"], loop["where"], loop["success"], loop["ended_by"]
('bonus maze', 'repeat', '...lib/maze_legs.yaml:18', 3, {'bonus maze/IsDeadEnd': 3})
>>> Coverage.from_json(data).merge(data).to_json()["runs"]
6
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour

from thymio_bt.behaviours.base import FAILURE, RUNNING, SUCCESS, node_path
from thymio_bt.behaviours.flow import ticking
from thymio_bt.behaviours.flow.primitives import NodeGuard
from thymio_bt.btcpp.runtime.nodes import BtNode
from thymio_bt.plan.model import NodePlan


def plan_paths(plan: NodePlan) -> Iterator[tuple[NodePlan, str, int]]:
    """Every node of ``plan`` in pre-order with its path (names from the root joined by ``/``, as
    ``node_stats`` and substitutions name nodes) and its depth (the root's is 0). A path already
    taken (a decorator's ``do`` and ``until`` of one name) gets ``#2``, ``#3``... so that each is one node."""
    taken: set[str] = set()

    def walk(node: NodePlan, parent: str, depth: int) -> Iterator[tuple[NodePlan, str, int]]:
        path = base = f"{parent}/{node.name}" if parent else node.name
        n = 1
        while path in taken:
            n += 1
            path = f"{base}#{n}"
        taken.add(path)
        yield node, path, depth
        for child in node.children:
            yield from walk(child, path, depth + 1)

    yield from walk(plan, "", 0)


@dataclass
class NodeCoverage:
    """One node's counts, summed over runs (a condition's successes and failures are its true and false)."""

    path: str
    name: str
    kind: str
    behaviour: str | None
    where: str
    depth: int
    ticks: int = 0
    success: int = 0
    failure: int = 0
    running: int = 0
    #: a composite's or decorator's child path -> how often that child's result ended it
    ended_by: dict[str, int] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """The node's entry of the coverage JSON (the grade contract's keys, in its order)."""
        return {
            "path": self.path,
            "name": self.name,
            "kind": self.kind,
            "behaviour": self.behaviour,
            "where": self.where,
            "depth": self.depth,
            "ticks": self.ticks,
            "success": self.success,
            "failure": self.failure,
            "running": self.running,
            "ended_by": dict(self.ended_by),
        }

    def add(self, ticks: int, success: int, failure: int, running: int, ended_by: Mapping[str, int]) -> None:
        """Add one run's (or one coverage's) counts."""
        self.ticks += ticks
        self.success += success
        self.failure += failure
        self.running += running
        for child, count in ended_by.items():
            self.ended_by[child] = self.ended_by.get(child, 0) + int(count)


class Coverage:
    """The coverage of a mission's tree: every node of its plan, in pre-order, with its counts."""

    def __init__(self, nodes: list[NodeCoverage], runs: int = 0) -> None:
        self.nodes = nodes
        self.runs = runs

    @classmethod
    def of(cls, plan: NodePlan) -> Coverage:
        """An empty coverage (no run yet) of every node of ``plan``."""
        return cls(
            [
                NodeCoverage(path, node.name, node.kind, node.behaviour, f"{node.where[0]}:{node.where[1]}", depth)
                for node, path, depth in plan_paths(plan)
            ]
        )

    def add(self, table: Mapping[str, Mapping[str, Any]] | None) -> Coverage:
        """Add one run's ``node_stats``: a :class:`NodeTable`, or rows with at least ``ticks``,
        ``successes`` and ``failures`` (with ``running`` and ``ended_by`` too, as
        :meth:`NodeTable.rows` gives them, for a table that went through JSON); nodes it does not
        name were not ticked. Returns ``self``."""
        if table is None:
            return self
        detail = table.detail if isinstance(table, NodeTable) else {}
        for node in self.nodes:
            row = table.get(node.path)
            if not row:
                continue
            extra = detail.get(node.path, row)
            ticks, success, failure = int(row["ticks"]), int(row["successes"]), int(row["failures"])
            running = int(extra.get("running", ticks - success - failure))
            node.add(ticks, success, failure, running, extra.get("ended_by", {}))
        self.runs += 1
        return self

    def merge(self, other: Mapping[str, Any] | Coverage) -> Coverage:
        """Add another coverage (its :meth:`to_json`, say from another process); a node it has that
        this one lacks is added at the end. Returns ``self``."""
        data = other.to_json() if isinstance(other, Coverage) else other
        mine = {node.path: node for node in self.nodes}
        for entry in data.get("nodes", []):
            node = mine.get(entry["path"])
            if node is None:
                node = mine[entry["path"]] = _node(entry)
                self.nodes.append(node)
                continue
            node.add(entry["ticks"], entry["success"], entry["failure"], entry["running"], entry.get("ended_by", {}))
        self.runs += int(data.get("runs", 0))
        return self

    @property
    def never_ticked(self) -> list[str]:
        """The paths of the nodes no run ticked, in pre-order."""
        return [node.path for node in self.nodes if not node.ticks]

    def to_json(self) -> dict[str, Any]:
        """The coverage JSON: ``runs``, ``nodes`` (pre-order) and ``never_ticked``."""
        return {"runs": self.runs, "nodes": [n.to_json() for n in self.nodes], "never_ticked": self.never_ticked}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Coverage:
        """The coverage of a :meth:`to_json`."""
        return cls([_node(entry) for entry in data.get("nodes", [])], int(data.get("runs", 0)))


def _node(entry: Mapping[str, Any]) -> NodeCoverage:
    """A node's coverage read from its JSON entry."""
    node = NodeCoverage(
        entry["path"], entry["name"], entry["kind"], entry.get("behaviour"), entry["where"], int(entry["depth"])
    )
    node.add(entry["ticks"], entry["success"], entry["failure"], entry["running"], entry.get("ended_by", {}))
    return node


class NodeTable(dict[str, dict[str, float]]):
    """A run's ``node_stats``: per node path, ``ticks``, ``successes``, ``failures`` and
    ``running_time`` (simulated seconds RUNNING); :attr:`detail` has, per path, ``running`` (ticks
    that returned RUNNING) and ``ended_by`` (child path -> how often its result ended the node)."""

    def __init__(
        self, rows: Mapping[str, dict[str, float]] | None = None, detail: Mapping[str, dict[str, Any]] | None = None
    ) -> None:
        super().__init__(rows or {})
        self.detail: dict[str, dict[str, Any]] = dict(detail or {})

    def rows(self) -> dict[str, dict[str, Any]]:
        """Plain rows with their :attr:`detail` in them: what :meth:`Coverage.add` reads in full after
        a JSON round trip (JSON keeps a dict's items, not the table's :attr:`detail`)."""
        return {path: {**row, **self.detail.get(path, {})} for path, row in self.items()}


class _Slot:
    """The counts of one node of the tree in one run, and what finding the child that ended it needs."""

    __slots__ = (
        "path", "parent", "period", "clock", "depth", "ticks", "success", "failure", "running", "running_time",
        "ended_by", "serial", "started", "last_child",
    )  # fmt: skip

    def __init__(self, path: str, parent: _Slot | None, period: float, clock: list[int]) -> None:
        self.path, self.parent, self.period, self.clock = path, parent, period, clock
        self.depth = self.ticks = self.success = self.failure = self.running = 0
        self.running_time = 0.0
        self.ended_by: dict[str, int] = {}
        self.serial = self.started = 0  # when its last tick ended, when its current one began
        self.last_child: _Slot | None = None

    def enter(self) -> None:
        """A tick of the node begins (nested entries, a generator calling the direct tick, count once)."""
        if not self.depth:
            self.started = self.clock[0]
        self.depth += 1

    def leave(self, node: Behaviour) -> None:
        """A tick of the node ends: count it once the outermost entry ends."""
        self.depth -= 1
        if not self.depth:
            self.record(node)

    def record(self, node: Behaviour) -> None:
        """Count one tick of ``node`` by the status it ended with; note which child ended it."""
        status = node.status
        if status is SUCCESS:
            self.success += 1
        elif status is FAILURE:
            self.failure += 1
        elif status is RUNNING:
            self.running += 1
            self.running_time = round(self.running_time + self.period, 9)
        else:
            return  # skipped (BT.CPP's SKIPPED leaves it IDLE): not ticked
        self.ticks += 1
        self.clock[0] += 1
        self.serial = self.clock[0]
        if self.parent is not None:
            self.parent.last_child = self
        if status is not RUNNING:
            ender = self._ender(node)
            if ender is not None:
                self.ended_by[ender.path] = self.ended_by.get(ender.path, 0) + 1

    def _ender(self, node: Behaviour) -> _Slot | None:
        """The child whose result ended this tick: the node's ``current_child`` if it was ticked in
        it (a parallel's failing child), else the last child ticked in it; None when none was."""
        current = getattr(getattr(node, "current_child", None), "_coverage", None)
        if isinstance(current, _Slot) and current.parent is self and current.serial > self.started:
            return current
        last = self.last_child
        return last if last is not None and last.serial > self.started else None


#: each node class's counting subclass (see :func:`_counting`)
_COUNTING: dict[type, type] = {}
_COUNTED: set[type] = set()


def _counting(cls: type) -> type:
    """``cls`` with every way it is ticked counted: py_trees' ``tick`` generator, the direct tick of
    :mod:`~thymio_bt.behaviours.flow.ticking` (``tick_direct``: the class's own, or the one that module
    has for its kind, so that counting keeps the direct tick) and BT.CPP's ``execute_tick``; same
    name, same behaviour."""
    made = _COUNTING.get(cls)
    if made is not None or cls in _COUNTED:
        return made or cls
    namespace: dict[str, Any] = {"__module__": cls.__module__, "__qualname__": cls.__qualname__}
    base_tick = cls.tick  # type: ignore[attr-defined]  # every node class has py_trees' tick

    def tick(self: Any) -> Iterator[Behaviour]:
        slot: _Slot = self._coverage
        slot.enter()
        left = False
        try:
            for node in base_tick(self):
                if node is self and not left:
                    left = True
                    slot.leave(self)
                yield node
        finally:
            if not left:
                slot.depth -= 1

    namespace["tick"] = tick
    # the direct tick the ticking module dispatches to for this class (its table is keyed by class)
    namespace["tick_direct"] = _counted(ticking.TICK_OF[cls])
    if issubclass(cls, BtNode):
        namespace["execute_tick"] = _counted(cls.execute_tick)  # BT.CPP nodes
    made = _COUNTING[cls] = type(cls.__name__, (cls,), namespace)
    _COUNTED.add(made)
    return made


def _counted(method: Any) -> Any:
    """``method`` (a direct tick) wrapped to count the tick it gives."""

    def counted(self: Any) -> Any:
        slot: _Slot = self._coverage
        if slot.depth:  # inside another entry of the same tick (its generator): that one counts it
            return method(self)
        slot.started = slot.clock[0]  # :meth:`_Slot.enter` and :meth:`_Slot.leave`, inlined: ticked often
        slot.depth = 1
        try:
            result = method(self)
        finally:
            slot.depth = 0
        slot.record(self)
        return result

    return counted


class NodeStats(py_trees.visitors.VisitorBase):
    """Per-node statistics of one run (like BehaviorTree.CPP's TreeObserver): :meth:`attach` makes
    every node of a built tree count its ticks, statuses and the child that ended it; :attr:`table`
    is the run's ``node_stats``, keyed by the paths of :func:`plan_paths`."""

    def __init__(self, period: float) -> None:
        super().__init__(full=False)
        self.period = period
        self.slots: dict[str, _Slot] = {}
        self._clock = [0]

    def attach(self, root: Behaviour, plan: NodePlan | None = None) -> None:
        """Count the ticks of every node of ``root`` (built from ``plan``: paths and hidden
        children, a guard's condition, are found by it)."""
        paths = {id(node): path for node, path, _ in plan_paths(plan)} if plan is not None else {}
        self._attach(root, plan, paths, None)

    def _attach(self, node: Behaviour, plan: NodePlan | None, paths: dict[int, str], parent: _Slot | None) -> None:
        """Make ``node`` (built from ``plan`` when known) and its subtree count their ticks."""
        path = paths.get(id(plan)) if plan is not None else None
        slot = self._slot(path or node_path(node), parent)
        node._coverage = slot  # type: ignore[attr-defined]  # a tag py_trees' nodes do not declare
        node.__class__ = _counting(node.__class__)
        built = [*node.children, *_hidden_children(node)]
        planned = list(plan.children) if plan is not None else []
        for child in built:
            match = next((p for p in planned if p.name == child.name), None)
            if match is not None:
                planned.remove(match)
            self._attach(child, match, paths, slot)

    def _slot(self, path: str, parent: _Slot | None) -> _Slot:
        """A new slot for the node at ``path``, or the one already there (a path shared in a visitor's use)."""
        slot = self.slots.get(path)
        if slot is None:
            slot = self.slots[path] = _Slot(path, parent, self.period, self._clock)
        return slot

    def run(self, behaviour: Behaviour) -> None:
        """Count one tick of ``behaviour`` as a py_trees visitor (a tree ticked without :meth:`attach`)."""
        self._slot(node_path(behaviour), None).record(behaviour)

    @property
    def table(self) -> NodeTable:
        """The run's ``node_stats``: the ticked nodes' rows, and their :attr:`NodeTable.detail`."""
        ticked = [s for s in self.slots.values() if s.ticks]
        return NodeTable(
            {
                s.path: {
                    "ticks": s.ticks,
                    "successes": s.success,
                    "failures": s.failure,
                    "running_time": s.running_time,
                }
                for s in ticked
            },
            {s.path: {"running": s.running, "ended_by": dict(s.ended_by)} for s in ticked},
        )


def _hidden_children(node: Behaviour) -> list[Behaviour]:
    """Nodes ``node`` ticks that are not its py_trees children: a guard's condition node."""
    return [node.condition_node] if isinstance(node, NodeGuard) else []


__all__ = ["Coverage", "NodeCoverage", "NodeStats", "NodeTable", "plan_paths"]
