"""BT.CPP 4's decorators with BT.CPP's own semantics (``src/decorators`` of BT.CPP 4.8): Inverter,
ForceSuccess, ForceFailure, KeepRunningUntilFailure, Repeat, RetryUntilSuccessful, RunOnce, Timeout
and Delay (in simulated time), and the constant leaves AlwaysSuccess/AlwaysFailure as BT.CPP nodes
(see :mod:`.nodes` for the rules).

Example (Repeat goes on within the tick after a child that completed at once, as BT.CPP does)::

    >>> from py_trees.behaviours import Success
    >>> from thymio_bt.behaviours.flow.ticking import tick
    >>> loop = Repeat("three", Success("leg"), 3)
    >>> tick(loop); loop.status
    <Status.SUCCESS: 'SUCCESS'>
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours.base import Explains
from thymio_bt.behaviours.flow.primitives import SimTimer
from thymio_bt.btcpp.runtime import nodes as bn
from thymio_bt.btcpp.runtime.nodes import FAILURE, IDLE, RUNNING, SKIPPED, SUCCESS
from thymio_bt.enums import FailureCode


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


class Timed(BtDecorator):
    """Timeout and Delay: a :class:`~thymio_bt.behaviours.flow.primitives.SimTimer` of ``msec``
    (simulated), started at the node's first tick, forgotten when the child completes or the node is
    halted (BT.CPP's ``TimeoutNode`` and ``DelayNode``: the next tick starts it again)."""

    def __init__(self, name: str, child: Behaviour, msec: int, clock: Callable[[], float]) -> None:
        super().__init__(name, child)
        self.timer = SimTimer(msec / 1000.0, clock)

    def started(self) -> SimTimer:
        """The timer, started (and the node RUNNING) if this is the node's first tick."""
        if self.timer.end is None:
            self.timer.start()
            self.status = RUNNING
        return self.timer

    def tick_child(self) -> Any:
        """The child's tick; once it completes, the timer forgotten and the child reset."""
        status = bn.execute(self.decorated)
        if status in bn.COMPLETED:
            self.timer.forget()
            bn.reset(self.decorated)
        return status

    def halt(self) -> None:
        """The timer forgotten, the child reset."""
        self.timer.forget()
        super().halt()


class Timeout(Explains, Timed):
    """BT.CPP's ``Timeout``: the child halted and FAILURE once it has run ``msec`` (0: no limit), the
    report saying so as ``timeout``'s does. BT.CPP's timer fires between ticks, so the deadline is
    checked before the child's tick (``timeout``'s
    :class:`~thymio_bt.behaviours.flow.primitives.SimTimeout` checks it after)."""

    def bt_tick(self) -> Any:
        """The child, unless the time is up while it runs."""
        timer = self.started()
        if timer.seconds > 0 and self.decorated.status is RUNNING and timer.over():
            bn.reset(self.decorated)
            timer.forget()
            limit = f"{timer.seconds * 1000:g} ms"
            self.failure = (FailureCode.TIMEOUT, f"'{self.decorated.name}' did not finish within {limit}")
            self.feedback_message = f"TIMEOUT: {self.failure[1]}"
            return FAILURE
        return self.tick_child()

    def started(self) -> SimTimer:
        """The timer, started at the node's first tick, when an earlier time-out is forgotten."""
        if self.timer.end is None:
            self.failure = None
        return super().started()


class Delay(Timed):
    """BT.CPP's ``Delay``: RUNNING for ``delay_msec``, then the child (``delay`` in BT.CPP's protocol)."""

    def bt_tick(self) -> Any:
        """RUNNING until the delay is over, then the child's status."""
        return self.tick_child() if self.started().over() else RUNNING


class Constant(bn.BtNode):
    """BT.CPP's ``AlwaysSuccess`` / ``AlwaysFailure``: a leaf that returns ``result`` at once."""

    def __init__(self, name: str, result: Status) -> None:
        super().__init__(name, [])
        self.result = result

    def bt_tick(self) -> Any:
        """The constant status."""
        return self.result
