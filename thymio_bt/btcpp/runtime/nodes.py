"""BehaviorTree.CPP 4's control nodes with BT.CPP's own semantics, tick for tick, as py_trees nodes.

Each class follows BT.CPP 4.8's C++ (``src/controls``, ``src/decorators``): the same child index
kept or reset, the same children halted (a RUNNING child is halted, every child reset to IDLE), the
same wake-ups. py_trees' INVALID stands for BT.CPP's IDLE; BT.CPP's SKIPPED (a ``RunOnce`` after its
run) is :data:`SKIPPED`, which a parent gets from :meth:`BtNode.execute` while the node stays IDLE.

A wake-up: ``SequenceWithMemory``, ``Repeat`` and ``RetryUntilSuccessful`` return RUNNING after a
child that completed at once and ask to be woken up; BT.CPP's ``tickOnce()`` then ticks the tree
again from its root within the same tick. Here the topmost BT.CPP node of the tree does that loop
(:meth:`BtNode.tick_direct`), so a tree made of these nodes ticks as ``tickOnce()`` does.

Example (BT.CPP's Sequence restarts after a failure; SequenceWithMemory resumes at the failed child)::

    >>> from py_trees.behaviours import Failure, Success
    >>> from thymio_bt.btcpp.runtime.decorators import RetryUntilSuccessful
    >>> from thymio_bt.behaviours.flow.ticking import tick
    >>> seq = SequenceWithMemory("memory", [Success("a"), Failure("b")])
    >>> retry = RetryUntilSuccessful("retry", seq, 2)
    >>> tick(retry); retry.status, seq.index
    (<Status.FAILURE: 'FAILURE'>, 1)
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours.base import RobotBehaviour
from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.errors import ThymioBtError

IDLE, RUNNING, SUCCESS, FAILURE = Status.INVALID, Status.RUNNING, Status.SUCCESS, Status.FAILURE


class _Skipped:
    """BT.CPP's SKIPPED: what a skipped node returns to its parent (its own status stays IDLE)."""

    def __repr__(self) -> str:
        return "SKIPPED"


SKIPPED: Any = _Skipped()
#: how many times one tick may re-tick the tree for wake-ups before it is an error (BT.CPP hangs)
MAX_PASSES = 10_000


class NeverYields(RuntimeError, ThymioBtError):
    """A tree that asks to be woken up again at every pass of a tick: BT.CPP's tickOnce() never returns."""


COMPLETED = (SUCCESS, FAILURE)


def execute(child: Behaviour) -> Any:
    """BT.CPP's ``executeTick`` of any child: a BT.CPP node's own, or py_trees' tick of another node.
    An action that completed and was not reset returns that status again without running (BT.CPP's
    StatefulActionNode); a condition runs every time (a SyncActionNode). A child that returns IDLE
    (a WhileDoElse whose condition was skipped) is an error, as in BT.CPP."""
    if isinstance(child, BtNode):
        status = child.execute_tick()
    elif child.status in COMPLETED and not (isinstance(child, RobotBehaviour) and child.bt_sync):
        return child.status
    else:
        tick(child)
        status = child.status
    if status is IDLE:
        raise RuntimeError(f"'{child.name}' returned IDLE: a child should not (BT.CPP refuses it too)")
    return status


def reset(child: Behaviour) -> None:
    """BT.CPP's ``haltChild``/``resetChild``: halt the child if it is RUNNING, then it is IDLE."""
    if isinstance(child, BtNode):
        if child.status is RUNNING:
            child.halt()
        child.reset_status()
    elif child.status is not IDLE:
        child.stop(IDLE)  # py_trees: terminate(INVALID), a halt when it was RUNNING


class BtNode(py_trees.composites.Composite):
    """A BT.CPP control node or decorator: its ``children`` ticked by BT.CPP's rules."""

    def __init__(self, name: str, children: list[Behaviour]) -> None:
        super().__init__(name=name, children=children)
        self.wake = False  # a wake-up was asked for (kept by the topmost BT.CPP node)

    # --- the tick: BT.CPP's executeTick, and tickOnce()'s loop at the top ---------------------

    def execute_tick(self) -> Any:
        """One BT.CPP ``executeTick``: :meth:`bt_tick`, the status kept (IDLE if SKIPPED)."""
        status = self.bt_tick()
        if status is not SKIPPED:  # skipped: the status the tick left (RUNNING if it set it, as BT.CPP)
            self.status = status
        return status

    def bt_tick(self) -> Any:
        """The node's own ``tick()``: its new status (RUNNING, SUCCESS, FAILURE or SKIPPED)."""
        raise NotImplementedError

    def halt(self) -> None:
        """BT.CPP's ``halt()``: every child reset (a RUNNING one halted), the node's own state reset."""
        self.reset_children()
        self.status = IDLE

    def reset_children(self) -> None:
        """BT.CPP's ``resetChildren()``: every child reset (a RUNNING one halted); the node's own
        status is left as it is (RUNNING during its tick: a SKIPPED result keeps it so)."""
        for child in self.children:
            reset(child)

    def reset_status(self) -> None:
        """BT.CPP's ``resetStatus()``: IDLE, the node's state kept."""
        self.status = IDLE

    def tick_direct(self) -> None:
        """A tick from a py_trees parent (or the run): at the top of the BT.CPP nodes, BT.CPP's
        ``tickOnce()``, which ticks again while a node asked to be woken up and the tree runs."""
        top = self._top()
        if top is not self:
            self.execute_tick()
            return
        self.wake = False
        status = self.execute_tick()
        passes = 1
        while status is RUNNING and self.wake:
            if passes >= MAX_PASSES:  # BT.CPP would never return from this tickOnce()
                raise NeverYields(f"'{self.name}' was woken up {passes} times in one tick: the tree never yields")
            self.wake = False
            status = self.execute_tick()
            passes += 1

    def tick(self) -> Iterator[Behaviour]:
        """py_trees' generator tick: the direct tick, then the nodes it left active (for visitors)."""
        self.tick_direct()
        yield from (node for node in self.iterate() if node.status is not IDLE or node is self)

    def stop(self, new_status: Status = IDLE) -> None:
        """py_trees' stop from a py_trees parent: a halt when RUNNING and reset to IDLE."""
        if new_status is IDLE and self.status is RUNNING:
            self.halt()
        self.status = new_status

    def emit_wake_up(self) -> None:
        """BT.CPP's ``emitWakeUpSignal()``: the topmost BT.CPP node ticks the tree again."""
        self._top().wake = True

    def _top(self) -> BtNode:
        """The topmost BT.CPP node above (or) this one."""
        top, node = self, self.parent
        while node is not None:
            if isinstance(node, BtNode):
                top = node
            node = node.parent
        return top


class _Sequential(BtNode):
    """Sequence, SequenceWithMemory and Fallback: children in order from a kept index."""

    #: the child status that moves on to the next child, and whether a failure keeps the index
    go_on: Status = SUCCESS
    memory = False
    wakes = False

    def __init__(self, name: str, children: list[Behaviour]) -> None:
        super().__init__(name, children)
        self.index = 0
        self.skipped = 0

    def bt_tick(self) -> Any:
        """BT.CPP's ``SequenceNode::tick`` (and its two siblings)."""
        count = len(self.children)
        if self.status is IDLE:  # BT.CPP: !isStatusActive(status()); a completed node keeps its count
            self.skipped = 0
        self.status = RUNNING
        while self.index < count:
            child = self.children[self.index]
            before = child.status
            status = execute(child)
            if status is RUNNING:
                return RUNNING
            if status is SKIPPED:
                self.index += 1
                self.skipped += 1
                continue
            if status is not self.go_on:
                if self.memory:
                    for other in self.children[self.index :]:
                        reset(other)
                else:  # BT.CPP keeps skipped_count_ here (reset when next ticked from IDLE)
                    self.reset_children()
                    self.index = 0
                return status
            self.index += 1
            if self.wakes and before is IDLE and self.index < count:
                self.emit_wake_up()
                return RUNNING
        all_skipped = self.skipped == count
        self.reset_children()
        self.index = self.skipped = 0
        return SKIPPED if all_skipped else self.go_on

    def halt(self) -> None:
        """BT.CPP's halt: back to the first child (SequenceWithMemory keeps its place)."""
        if not self.memory:
            self.index = self.skipped = 0
        super().halt()


class Sequence(_Sequential):
    """BT.CPP's ``Sequence``: resumes at the RUNNING child; after a failure, starts over."""


class SequenceWithMemory(_Sequential):
    """BT.CPP's ``SequenceWithMemory``: after a failure, resumes at the failed child."""

    memory = True
    wakes = True


class Fallback(_Sequential):
    """BT.CPP's ``Fallback``: the children in order until one does not fail."""

    go_on = FAILURE


class _Reactive(BtNode):
    """ReactiveSequence and ReactiveFallback: every child from the first, every tick."""

    go_on: Status = SUCCESS

    def bt_tick(self) -> Any:
        """BT.CPP's ``ReactiveSequence::tick`` (and ReactiveFallback's)."""
        all_skipped = True
        self.status = RUNNING
        for index, child in enumerate(self.children):
            status = execute(child)
            all_skipped = all_skipped and status is SKIPPED
            if status is RUNNING:
                for i, other in enumerate(self.children):
                    if i != index:
                        reset(other)
                return RUNNING
            if status is SKIPPED:
                reset(child)
            elif status is not self.go_on:
                self.halt_all()
                return status
        self.halt_all()
        return SKIPPED if all_skipped else self.go_on

    def halt_all(self) -> None:
        """Every child reset."""
        for child in self.children:
            reset(child)


class ReactiveSequence(_Reactive):
    """BT.CPP's ``ReactiveSequence``: earlier children are ticked again every tick."""


class ReactiveFallback(_Reactive):
    """BT.CPP's ``ReactiveFallback``: higher-priority children are tried again every tick."""

    go_on = FAILURE


def _threshold(value: int, count: int) -> int:
    """A Parallel count: negative counts from the number of children (-1: all of them)."""
    return max(count + value + 1, 0) if value < 0 else value


class Parallel(BtNode):
    """BT.CPP's ``Parallel``: SUCCESS at ``success_count`` successes, FAILURE at ``failure_count``
    failures (or when success can no longer be reached); negative counts are from the end (-1: all)."""

    def __init__(self, name: str, children: list[Behaviour], success_count: int = -1, failure_count: int = 1) -> None:
        super().__init__(name, children)
        self.success_count, self.failure_count = success_count, failure_count
        self.completed: set[int] = set()
        self.successes = self.failures = 0

    def bt_tick(self) -> Any:
        """BT.CPP's ``ParallelNode::tick``."""
        count = len(self.children)
        need, fail = _threshold(self.success_count, count), _threshold(self.failure_count, count)
        self.status = RUNNING
        skipped = 0
        for i, child in enumerate(self.children):
            if i not in self.completed:
                status = execute(child)
                if status is SKIPPED:
                    skipped += 1
                elif status is SUCCESS:
                    self.completed.add(i)
                    self.successes += 1
                elif status is FAILURE:
                    self.completed.add(i)
                    self.failures += 1
            if self.successes >= need or (self.success_count < 0 and self.successes + skipped >= need):
                self.halt()
                return SUCCESS
            if count - self.failures < need or self.failures == fail:
                self.halt()
                return FAILURE
        return SKIPPED if skipped == count else RUNNING

    def halt(self) -> None:
        """The counts cleared, every child reset."""
        self.completed.clear()
        self.successes = self.failures = 0
        super().halt()


class ParallelAll(BtNode):
    """BT.CPP's ``ParallelAll``: every child to completion; FAILURE if ``max_failures`` failed."""

    def __init__(self, name: str, children: list[Behaviour], max_failures: int = 1) -> None:
        super().__init__(name, children)
        self.max_failures = max_failures
        self.completed: set[int] = set()
        self.failures = 0

    def bt_tick(self) -> Any:
        """BT.CPP's ``ParallelAllNode::tick``."""
        count = len(self.children)
        threshold = _threshold(self.max_failures, count)
        self.status = RUNNING
        skipped = 0
        for i, child in enumerate(self.children):
            if i in self.completed:
                continue
            status = execute(child)
            if status in COMPLETED:
                self.completed.add(i)
                self.failures += status is FAILURE
            elif status is SKIPPED:
                skipped += 1
        if skipped == count:
            return SKIPPED
        if skipped + len(self.completed) >= count:
            failed = self.failures >= threshold
            self.halt()
            return FAILURE if failed else SUCCESS
        return RUNNING

    def halt(self) -> None:
        """The counts cleared, every child reset."""
        self.completed.clear()
        self.failures = 0
        super().halt()


class IfThenElse(BtNode):
    """BT.CPP's ``IfThenElse``: the first child decides, once, between the second and the third."""

    def __init__(self, name: str, children: list[Behaviour]) -> None:
        super().__init__(name, children)
        self.branch = 0

    def bt_tick(self) -> Any:
        """BT.CPP's ``IfThenElseNode::tick``."""
        self.status = RUNNING
        if self.branch == 0:
            condition = execute(self.children[0])
            if condition is RUNNING:
                return RUNNING
            if condition is SUCCESS:
                self.branch = 1
            elif condition is FAILURE:
                if len(self.children) < 3:
                    return FAILURE
                self.branch = 2
            else:
                raise RuntimeError(f"IfThenElse '{self.name}': its condition was skipped")
        status = execute(self.children[self.branch])
        if status is RUNNING:
            return RUNNING
        self.reset_children()  # not a halt: a SKIPPED branch leaves this node RUNNING, as in BT.CPP
        self.branch = 0
        return status

    def halt(self) -> None:
        """Back to the condition, every child reset."""
        self.branch = 0
        super().halt()


class WhileDoElse(BtNode):
    """BT.CPP's ``WhileDoElse``: the first child is checked every tick; it chooses the second or third."""

    def bt_tick(self) -> Any:
        """BT.CPP's ``WhileDoElseNode::tick``."""
        self.status = RUNNING
        children = self.children
        condition = execute(children[0])
        if condition is RUNNING:
            return RUNNING
        status: Any = IDLE
        if condition is SUCCESS:
            if len(children) == 3:
                reset(children[2])
            status = execute(children[1])
        elif condition is FAILURE:
            if len(children) == 3:
                reset(children[1])
                status = execute(children[2])
            else:
                status = FAILURE
        if status is RUNNING:
            return RUNNING
        self.reset_children()  # not a halt: a SKIPPED branch leaves this node RUNNING, as in BT.CPP
        return status
