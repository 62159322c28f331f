"""BT.CPP 4's decorators with BT.CPP's own semantics (``src/decorators`` of BT.CPP 4.8): Inverter,
ForceSuccess, ForceFailure, KeepRunningUntilFailure, Repeat, RetryUntilSuccessful, RunOnce, and the
constant leaves AlwaysSuccess/AlwaysFailure as BT.CPP nodes (see :mod:`.nodes` for the rules).

Example (Repeat goes on within the tick after a child that completed at once, as BT.CPP does)::

    >>> from py_trees.behaviours import Success
    >>> from thymio_bt.behaviours.flow.ticking import tick
    >>> loop = Repeat("three", Success("leg"), 3)
    >>> tick(loop); loop.status
    <Status.SUCCESS: 'SUCCESS'>
"""

from __future__ import annotations

from typing import Any

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.btcpp.runtime import nodes as bn
from thymio_bt.btcpp.runtime.nodes import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS


class BtDecorator(bn.BtNode):
    """A BT.CPP decorator: one child, reset after the tick when it completed (``DecoratorNode::executeTick``)."""

    def __init__(self, name: str, child: Behaviour) -> None:
        super().__init__(name, [child])
        self.decorated = child

    def execute_tick(self) -> Any:
        """The decorator's tick, then its child reset if it completed."""
        status = super().execute_tick()
        if self.decorated.status in bn.COMPLETED:
            bn.reset(self.decorated)
        return status


class _Mapped(BtDecorator):
    """Inverter, ForceSuccess, ForceFailure: the child's completed status mapped."""

    outcome: dict[Status, Status] = {}
    #: what a skipped child makes of it
    skipped: Any = SKIPPED

    def bt_tick(self) -> Any:
        """The child's status, SUCCESS and FAILURE mapped."""
        self.status = RUNNING
        status = bn.execute(self.decorated)
        if status in bn.COMPLETED:
            bn.reset(self.decorated)
            return self.outcome[status]
        return self.skipped if status is SKIPPED else status


class Inverter(_Mapped):
    """BT.CPP's ``Inverter``: SUCCESS and FAILURE swapped."""

    outcome = {SUCCESS: FAILURE, FAILURE: SUCCESS}


class ForceSuccess(_Mapped):
    """BT.CPP's ``ForceSuccess``: SUCCESS once the child completes."""

    outcome = {SUCCESS: SUCCESS, FAILURE: SUCCESS}


class ForceFailure(_Mapped):
    """BT.CPP's ``ForceFailure``: FAILURE once the child completes."""

    outcome = {SUCCESS: FAILURE, FAILURE: FAILURE}


class KeepRunningUntilFailure(_Mapped):
    """BT.CPP's ``KeepRunningUntilFailure``: RUNNING after each success (the child again next tick)."""

    outcome = {SUCCESS: RUNNING, FAILURE: FAILURE}
    skipped = RUNNING  # BT.CPP returns its own status, RUNNING, for a skipped child


class _Loop(BtDecorator):
    """Repeat and RetryUntilSuccessful: the child again after a SUCCESS (Repeat) or FAILURE (Retry)."""

    again: Status = SUCCESS

    def __init__(self, name: str, child: Behaviour, times: int) -> None:
        super().__init__(name, child)
        self.times, self.count = times, 0

    def bt_tick(self) -> Any:
        """BT.CPP's ``RepeatNode::tick`` (and ``RetryNode::tick``)."""
        looping = self.count < self.times or self.times == -1
        self.status = RUNNING
        while looping:
            before = self.decorated.status
            status = bn.execute(self.decorated)
            if status is RUNNING:
                return RUNNING
            if status is SKIPPED:
                bn.reset(self.decorated)
                return SKIPPED
            bn.reset(self.decorated)
            if status is not self.again:
                self.count = 0
                return status
            self.count += 1
            looping = self.count < self.times or self.times == -1
            if before is IDLE and looping:
                self.emit_wake_up()
                return RUNNING
        self.count = 0
        return self.again

    def halt(self) -> None:
        """The count reset, the child reset."""
        self.count = 0
        super().halt()


class Repeat(_Loop):
    """BT.CPP's ``Repeat``: the child ``num_cycles`` times (-1: for ever); a failure ends it."""


class RetryUntilSuccessful(_Loop):
    """BT.CPP's ``RetryUntilSuccessful``: the child again after a failure, ``num_attempts`` tries in all."""

    again = FAILURE


class RunOnce(BtDecorator):
    """BT.CPP's ``RunOnce``: the child until it completes once; then SKIPPED (``then_skip``) or that status."""

    def __init__(self, name: str, child: Behaviour, then_skip: bool = True) -> None:
        super().__init__(name, child)
        self.then_skip = then_skip
        self.done: Any = None

    def bt_tick(self) -> Any:
        """BT.CPP's ``RunOnceNode::tick``."""
        if self.done is not None:
            return SKIPPED if self.then_skip else self.done
        self.status = RUNNING
        status = bn.execute(self.decorated)
        if status in bn.COMPLETED:
            self.done = status
            bn.reset(self.decorated)
        return status


class Constant(bn.BtNode):
    """BT.CPP's ``AlwaysSuccess`` / ``AlwaysFailure``: a leaf that returns ``result`` at once."""

    def __init__(self, name: str, result: Status) -> None:
        super().__init__(name, [])
        self.result = result

    def bt_tick(self) -> Any:
        """The constant status."""
        return self.result
