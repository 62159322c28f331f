"""The structural rules of the teaching lint (:mod:`thymio_bt.analysis.lint`): what each node of a
tree can end with, and what that makes of its siblings and of the loops above it: ``unreachable``,
``reactive-restart``, ``forever`` and ``checked-once``; and what a finding is.

A node can end with S (SUCCESS), F (FAILURE), both, or neither (it never ends: a ``repeat:
forever`` of a child that never fails). A leaf is a condition (it answers at once), an instant
action (``Stop``, ``SetBlackboard``...), a long action (it runs over ticks) or unknown (a plugin not
imported: no finding rests on it).

Example::

    >>> from thymio_bt.mission.loader import load_mission
    >>> rules = TreeRules(load_mission("maze_bonus"))
    >>> loop = rules.tree
    >>> sorted(rules.outcomes(loop)), rules.may_run(loop), rules.nature(loop.children[1])
    (['F', 'S'], True, 'condition')
    >>> list(rules.findings())
    []
"""

from __future__ import annotations

import math
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel

from thymio_bt.behaviours.base import RobotBehaviour, UnrunPlugin
from thymio_bt.behaviours.flow.node import BOTH, SWAP, ControlNode, F, S
from thymio_bt.plan.model import Mission, NodePlan


class _Unknown(ControlNode):
    """A control kind the registry lacks: it may end either way and stop its child (its facts' defaults)."""


@dataclass(frozen=True)
class Finding:
    """One finding: where (file and line), the rule's id, what is wrong and what to do."""

    file: str
    line: int
    rule: str
    message: str
    hint: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}: [{self.rule}] {self.message} (hint: {self.hint})"


def is_condition(cls: Any) -> bool:
    """Whether a node class is a condition: it answers at once, true (SUCCESS) or false (FAILURE), as
    its class declares (:attr:`RobotBehaviour.condition`)."""
    return isinstance(cls, type) and issubclass(cls, RobotBehaviour) and cls.condition


def condition_names(registry: Any) -> set[str]:
    """The YAML names of the conditions in ``registry``."""
    return {name for name, cls in registry.behaviours() if is_condition(cls)}


def finding_at(node: NodePlan, rule: str, message: str, hint: str) -> Finding:
    """A finding at ``node``'s place."""
    return Finding(node.where[0], node.where[1], rule, message, hint)


class TreeRules:
    """The rules on the tree's structure: what each node can end with, and what that makes of its
    siblings and of the loops above it."""

    def __init__(self, mission: Mission) -> None:
        self.registry = mission.registry
        self.tree = mission.tree
        self._outcomes: dict[int, frozenset[str]] = {}

    def findings(self) -> Iterator[Finding]:
        """Every finding of the tree rules, parents first."""
        yield from self._walk(self.tree, ())

    def _walk(self, node: NodePlan, above: tuple[NodePlan, ...]) -> Iterator[Finding]:
        """The findings at ``node`` (``above``: its ancestors, the root first), then below it; a
        child found unreachable is not looked into."""
        unreachable = yield from self._unreachable(node)
        yield from self._restart(node)
        yield from self._forever(node, above)
        yield from self._checked_once(node)
        for child in node.children:
            if id(child) not in unreachable:
                yield from self._walk(child, (*above, node))

    # --- what a node can end with ------------------------------------------------------------

    def _class(self, node: NodePlan) -> Any:
        """The class of a behaviour node (None when the registry lacks it)."""
        return self.registry.get(node.behaviour) if node.behaviour and self.registry is not None else None

    def params(self, node: NodePlan) -> BaseModel:
        """A composite or decorator node's validated parameters (the planner gives every node its own;
        a plan made by hand without them counts as one that says nothing)."""
        return node.params if node.params is not None else BaseModel()

    def kind(self, node: NodePlan) -> type[ControlNode]:
        """The class of a composite or decorator node, whose facts the rules read."""
        cls = self.registry.get(node.kind) if self.registry is not None else None
        return cls if isinstance(cls, type) and issubclass(cls, ControlNode) else _Unknown

    def _family(self, node: NodePlan, *families: str, reactive: bool | None = None) -> bool:
        """Whether ``node`` is a composite of one of ``families`` (and, unless None, ``reactive`` or not)."""
        cls = self.kind(node)
        return cls.family in families and (reactive is None or cls.reactive == reactive)

    def nature(self, node: NodePlan) -> str:
        """A leaf's nature: ``condition``, ``instant`` (an action done in one tick), ``long`` (runs over
        ticks) or ``unknown`` (a plugin not imported)."""
        cls = self._class(node)
        if cls is None or issubclass(cls, UnrunPlugin):
            return "unknown"
        if is_condition(cls):
            return "condition"
        if issubclass(cls, RobotBehaviour) and (cls.bt_sync or cls.instant or cls.always):
            return "instant"
        return "long"

    def outcomes(self, node: NodePlan) -> frozenset[str]:
        """What ``node`` can end with: S (success), F (failure); empty when it never ends."""
        key = id(node)
        if key not in self._outcomes:
            self._outcomes[key] = frozenset(self._ends(node))
        return self._outcomes[key]

    def _ends(self, node: NodePlan) -> set[str]:
        """:meth:`outcomes`, worked out (conservatively: both when the kind is not known here)."""
        if node.kind == "behaviour":
            cls = self._class(node)
            known = cls.always if self.nature(node) != "unknown" else ""
            return {known} if known else set(BOTH)
        return set(self.kind(node).ends(self.params(node), [self.outcomes(k) for k in node.children]))

    # --- the rules -----------------------------------------------------------------------------

    def _unreachable(self, node: NodePlan) -> Generator[Finding, None, set[int]]:
        """``unreachable``: the first child that cannot run in ``node``; returns the ids of the children
        that cannot run."""
        kids = node.children
        blocker: NodePlan | None = None
        if self._family(node, "sequence", "selector"):
            go_on = S if self._family(node, "sequence") else F
            blocker = next((k for k in kids[:-1] if go_on not in self.outcomes(k)), None)
            if blocker is not None:
                after = kids[kids.index(blocker) + 1 :]
                yield self._unreachable_finding(node, blocker, after[0], go_on, len(after))
                return {id(k) for k in after}
        elif (then := self._node_at(node, self.kind(node).then)) is not None and S not in self.outcomes(kids[0]):
            yield finding_at(
                then,
                "unreachable",
                f"the {self.kind(node).then} condition '{then.name}' of '{node.name}' is never checked: "
                f"'{kids[0].name}' {self._why(kids[0], S)}",
                "the condition is checked after each success of the loop's body",
            )
            return {id(then)}
        elif (gate := self._gate(node)) is not None and S not in self.outcomes(gate):
            yield finding_at(
                kids[0],
                "unreachable",
                f"'{kids[0].name}' never runs: the {self.kind(node).gate} '{gate.name}' of {node.kind} "
                f"'{node.name}' {self._why(gate, S)}",
                f"a {node.kind} runs its child only while its {self.kind(node).gate} succeeds",
            )
            return {id(kids[0])}
        return set()

    def _node_at(self, node: NodePlan, key: str) -> NodePlan | None:
        """The child of decorator ``node`` under its node key ``key`` ("", or not given: None)."""
        keys = self.kind(node).node_keys
        at = 1 + keys.index(key) if key in keys else 0
        return node.children[at] if 0 < at < len(node.children) else None

    def _gate(self, node: NodePlan) -> NodePlan | None:
        """The condition that gates ``node``'s child (its kind's ``gate``: a guard's), None if none."""
        return self._node_at(node, self.kind(node).gate)

    def _why(self, node: NodePlan, missing: str) -> str:
        """Why ``node`` never ends with ``missing``, in words."""
        got = self.outcomes(node)
        if not got:
            return "never ends"
        return "always succeeds" if got == {S} else "always fails" if got == {F} else "never " + missing

    def _unreachable_finding(self, node: NodePlan, blocker: NodePlan, first: NodePlan, go_on: str, n: int) -> Finding:
        """The finding of the children after ``blocker`` in the sequence or selector ``node``."""
        what = "sequence" if go_on == S else "selector"
        more = f" (nor the {n - 1} after it)" if n > 1 else ""
        if go_on == S:
            hint = (
                "a sequence goes on to its next child only when one succeeds: remove the children after it, or fix it"
            )
        else:
            hint = "a selector tries its next child only when one fails: put the child that always succeeds last"
        return finding_at(
            first,
            "unreachable",
            f"'{first.name}' never runs{more}: '{blocker.name}' before it in {what} '{node.name}' "
            f"{self._why(blocker, go_on)}",
            hint,
        )

    def may_run(self, node: NodePlan) -> bool:
        """Whether ``node`` can return RUNNING when ticked again after it ended: it holds a long action
        (a ``one_shot`` returns its result without running its child again)."""
        if node.kind == "behaviour":
            return self.nature(node) == "long"
        if self.kind(node).once:
            return False
        return any(self.may_run(k) for k in node.children)

    def unguarded(self, node: NodePlan) -> bool:
        """Whether ``node``, ticked from the start, reaches a long action before any condition that
        could fail and stop it (a selector's first instant child ends or gates it too)."""
        kids = node.children
        if node.kind == "behaviour":
            return self.nature(node) == "long"
        if (gate := self._gate(node)) is not None:
            return F not in self.outcomes(gate) and self.unguarded(kids[0])
        if self._family(node, "parallel"):
            return any(self.unguarded(k) for k in kids)
        if self._family(node, "sequence", "selector"):
            for kid in kids:
                if self.may_run(kid):
                    return self.unguarded(kid)
                if self._family(node, "selector") or F in self.outcomes(kid):
                    return False
            return False
        return bool(kids) and self.unguarded(kids[0])

    def _restart(self, node: NodePlan) -> Iterator[Finding]:
        """``reactive-restart``: the children of a reactive composite started again at every tick."""
        if not self._family(node, "sequence", "selector", reactive=True):
            return
        kids = node.children
        sequence = self._family(node, "sequence")
        for i, kid in enumerate(kids[:-1]):
            if not any(self.may_run(k) for k in kids[i + 1 :]):
                break
            if sequence and self.may_run(kid):
                yield finding_at(
                    kid,
                    "reactive-restart",
                    f"'{kid.name}' runs over several ticks but is not the last child of reactive sequence "
                    f"'{node.name}': once a later child runs, every tick starts '{kid.name}' again (it had "
                    "succeeded) and halts the later child",
                    "before the last child put only conditions; make the steps one sequence, e.g. "
                    "reactive_sequence: [CONDITION, sequence: [STEP, STEP]], or wrap the step in one_shot",
                )
            elif not sequence and self.unguarded(kid):
                yield finding_at(
                    kid,
                    "reactive-restart",
                    f"'{kid.name}' starts an action with no condition first, and reactive selector "
                    f"'{node.name}' ticks it from the start at every tick: once it fails and a later child "
                    f"runs, '{kid.name}' starts again at every tick and halts it",
                    "begin each higher-priority child with a condition that fails at once when it does not "
                    "apply, e.g. sequence: [ObstacleAhead, AVOID]",
                )

    def _forever(self, node: NodePlan, above: tuple[NodePlan, ...]) -> Iterator[Finding]:
        """``forever``: a loop that never ends, with nothing above it that could stop it."""
        endless = self.kind(node).endless(self.params(node), len(node.children))
        if not endless or self.outcomes(node) or self._way_out(node, above):
            return
        yield finding_at(
            node,
            "forever",
            f"'{node.name}' repeats for ever: '{node.children[0].name}' never fails, and nothing above it "
            "can stop it: the run can only end at its time limit (status TIMEOUT)",
            "give the repeat times: N or until: CONDITION, or put it under a timeout or a guard",
        )

    def _checked_once(self, node: NodePlan) -> Iterator[Finding]:
        """``checked-once``: in a plain sequence, a check that the way ahead is clear (``invert:
        WallAhead``...) before a drive that goes farther than the check saw: the sequence checks it
        once, before the drive starts, and not while it drives (docs/control_nodes.md's classic
        mistake). A check before a turn, a decision (``SideOpen``, ``IsDeadEnd``), or a drive no
        longer than the clearance it vouches for is what it is meant to be, and not found."""
        if not self._family(node, "sequence", reactive=False):
            return
        kids = node.children
        for i, kid in enumerate(kids[:-1]):
            clear = self._clearance(kid)
            then = next((k for k in kids[i + 1 :] if self.may_run(k)), None)
            drive = self._first_drive(then) if clear is not None and then is not None else None
            if clear is None or drive is None or not drive[1] > clear[1] + 1e-9:
                continue
            far = "with no bound" if math.isinf(drive[1]) else f"{drive[1]:g} m"
            yield finding_at(
                kid,
                "checked-once",
                f"'{clear[0].name}' (inverted: nothing within {clear[1]:g} m ahead) is checked once, then "
                f"'{drive[0].name}' drives {far}: sequence '{node.name}' does not check it again while "
                f"'{drive[0].name}' runs, so the robot can drive into what the check meant to avoid",
                "to keep the condition checked while driving, make the parent a reactive_sequence (or use "
                "guard: {condition: ..., do: ...}); or drive with MoveUntilWall, which stops at the wall itself",
            )

    def _clearance(self, node: NodePlan) -> tuple[NodePlan, float] | None:
        """The condition under ``node`` that says the way ahead is clear (an odd number of inverters
        over a condition whose class declares :meth:`~RobotBehaviour.clear_ahead`), with the distance
        it vouches for; None otherwise."""
        inverted = False
        while self.kind(node).outcome == SWAP and node.children:
            inverted, node = not inverted, node.children[0]
        cls = self._class(node)
        if not inverted or not self._known(node) or self.nature(node) != "condition":
            return None
        how_far = cls.clear_ahead(node.params)
        return None if how_far is None else (node, how_far)

    def _first_drive(self, node: NodePlan) -> tuple[NodePlan, float] | None:
        """The forward drive ``node`` starts with, and how far it goes (inf: no bound); None when it
        starts with something else, or under a node that may watch it (reactive, guard, parallel)."""
        kind, kids = node.kind, node.children
        if kind == "behaviour":
            far = (
                self._class(node).drives_forward(node.params)
                if self.nature(node) == "long" and self._known(node)
                else 0.0
            )
            return (node, far) if far > 0 else None
        if self._family(node, "sequence", "selector", reactive=False):
            first = next((k for k in kids if self.may_run(k)), None)
            return self._first_drive(first) if first is not None else None
        return self._first_drive(kids[0]) if self.kind(node).passes_on and kids else None

    def _known(self, node: NodePlan) -> bool:
        """Whether ``node``'s values are written (not read from the blackboard when it starts)."""
        return node.params is not None and not node.blackboard_refs

    def _way_out(self, node: NodePlan, above: tuple[NodePlan, ...]) -> bool:
        """Whether an ancestor of ``node`` can stop it: a timeout, a guard whose condition can fail, a
        parallel whose other child can end it, a reactive composite's earlier child that can preempt."""
        for parent, via in zip(reversed(above), (node, *reversed(above))[: len(above)], strict=True):
            kids = [self.outcomes(k) for k in parent.children]
            if self.kind(parent).may_stop(self.params(parent), kids, parent.children.index(via)):
                return True
        return False


__all__ = ["BOTH", "Finding", "TreeRules", "condition_names", "finding_at", "is_condition"]
