"""Control nodes that py_trees lacks or only has in wall-clock time.

py_trees' own ``Timeout`` and ``Timer`` read the wall clock, which is wrong when the simulation
runs 1000x faster than real time; :class:`SimTimeout` reads the robot's clock instead.
:class:`SimTimer` is the one rule of a span of simulated time, which every timed node of both
vocabularies follows (``timeout``, ``delay``, BT.CPP's ``Timeout``, ``Delay`` and ``Sleep``).
:class:`RepeatUntil` is a do-while loop: run the body, and after each success check a condition.
:class:`NodeGuard` is py_trees' ``EternalGuard`` whose condition is a node, kept where a walk of the
tree (coverage) finds it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from thymio_bt.behaviours.base import FAILURE, INVALID, RUNNING, SUCCESS, Explains
from thymio_bt.behaviours.flow.ticking import TICK_OF
from thymio_bt.enums import FailureCode

#: how close to its end a span of simulated time counts as over: a tick's time is a sum of float
#: periods (ten ticks of 0.1 s end at 0.9999999999999999 s)
SLACK = 1e-9


class SimTimer:
    """A span of ``seconds`` on the run's simulated ``clock``, from :meth:`start`: over once the clock
    reaches its end (to :data:`SLACK`). ``end`` is None while it is not started.

    Example::

        >>> now = [0.0]
        >>> timer = SimTimer(1.0, lambda: now[0])
        >>> timer.start(); now[0] = sum([0.1] * 10)
        >>> timer.over(), now[0]
        (True, 0.9999999999999999)
        >>> now[0] = 0.25; timer.over(), timer.left()
        (False, 0.75)
    """

    __slots__ = ("clock", "end", "seconds")

    def __init__(self, seconds: float, clock: Callable[[], float]) -> None:
        self.seconds, self.clock = seconds, clock
        self.end: float | None = None

    def start(self) -> None:
        """The span starts now."""
        self.end = self.clock() + self.seconds

    def forget(self) -> None:
        """Not started (a BT.CPP node starts it again at its next tick)."""
        self.end = None

    def over(self) -> bool:
        """Whether the span (started) has passed."""
        assert self.end is not None, "a timer read before it started"
        return self.clock() >= self.end - SLACK

    def left(self) -> float:
        """The seconds to its end (started)."""
        assert self.end is not None, "a timer read before it started"
        return self.end - self.clock()


class SimTimeout(Explains, py_trees.decorators.Decorator):
    """Fail (and stop the child) when the child runs longer than ``duration`` simulated seconds.

    Example::

        >>> from py_trees.behaviours import Running
        >>> from thymio_bt.behaviours.flow.ticking import tick
        >>> clock = [0.0]
        >>> limit = SimTimeout("limit", Running("forever"), duration=30.0, clock=lambda: clock[0])
        >>> tick(limit); limit.status
        <Status.RUNNING: 'RUNNING'>
        >>> clock[0] = 30.0
        >>> tick(limit); limit.status, limit.decorated.status, limit.failure[0]
        (<Status.FAILURE: 'FAILURE'>, <Status.INVALID: 'INVALID'>, <FailureCode.TIMEOUT: 'TIMEOUT'>)
    """

    def __init__(self, name: str, child: Behaviour, duration: float, clock: Callable[[], float]) -> None:
        super().__init__(name=name, child=child)
        self.timer = SimTimer(duration, clock)

    def initialise(self) -> None:
        """py_trees' start hook: the time limit runs from now."""
        self.timer.start()
        self.feedback_message = ""
        self.failure = None

    def update(self) -> Status:
        """The child's status, or FAILURE (and the child halted) once the time is up (checked after
        the child's tick: BT.CPP's ``Timeout`` checks before it)."""
        if self.decorated.status == RUNNING and self.timer.over():
            self.decorated.stop(INVALID)
            limit = self.timer.seconds
            self.failure = (FailureCode.TIMEOUT, f"'{self.decorated.name}' did not finish within {limit:g} s")
            self.feedback_message = f"TIMEOUT: {self.failure[1]}"
            return FAILURE
        if self.decorated.status == RUNNING:
            self.feedback_message = f"{self.timer.left():.1f} s left"
        return self.decorated.status


class RepeatUntil(py_trees.composites.Composite):
    """Run ``body``; after each success tick ``condition``: SUCCESS ends the loop, else go again.

    A body failure ends the loop with FAILURE, so real errors are never masked.

    Example::

        >>> from py_trees.behaviours import Success, SuccessEveryN
        >>> from thymio_bt.behaviours.flow.ticking import tick
        >>> loop = RepeatUntil("until the third", body=Success("leg"), condition=SuccessEveryN("third", 3))
        >>> for _ in range(3):
        ...     tick(loop)
        >>> loop.status, loop.iterations
        (<Status.SUCCESS: 'SUCCESS'>, 3)
    """

    def __init__(self, name: str, body: Behaviour, condition: Behaviour) -> None:
        super().__init__(name=name, children=[body, condition])
        self.iterations = 0

    def tick(self) -> Iterator[Behaviour]:
        """py_trees' generator tick: the body, and the condition after each success of the body."""
        child: Behaviour | None = self._begin()
        while child is not None:
            yield from child.tick()
            child = self._after(child)
        yield self

    def tick_direct(self) -> None:
        """The same tick without generators (:mod:`.ticking`)."""
        # running: resume at the current child (what _begin returns then), a call less a tick
        child: Behaviour | None = self.current_child if self.status is RUNNING else self._begin()
        while child is not None:
            TICK_OF[child.__class__](child)  # tick(child), a call less
            child = self._after(child)

    def _begin(self) -> Behaviour | None:
        """Start the loop if it is not running; the child to tick first."""
        if self.status is not RUNNING:
            for child in self.children:
                if child.status is not INVALID:
                    child.stop(INVALID)
            self.current_child = self.children[0]
            self.iterations = 0
            self.initialise()
        return self.current_child

    def _after(self, child: Behaviour) -> Behaviour | None:
        """Act on ``child``'s status once it has ticked; the child to tick next in this tick, or None."""
        body, condition = self.children
        if child is body:
            if body.status is RUNNING:
                self.status = RUNNING
                return None
            if body.status is FAILURE:
                self.stop(FAILURE)
                return None
            self.iterations += 1
            self.current_child = condition
            return condition
        if condition.status is SUCCESS:
            self.stop(SUCCESS)
        else:
            if condition.status is FAILURE:
                self.current_child = body
            self.status = RUNNING
            self.feedback_message = f"iteration {self.iterations + 1}"
        return None


class NodeGuard(py_trees.decorators.EternalGuard):
    """py_trees' ``EternalGuard`` with a node as its condition, ticked before the child every tick.

    py_trees calls the condition through a function; the node is :attr:`condition_node`, declared,
    since it is ticked without being one of :attr:`children` (coverage counts it under the guard).

    Example::

        >>> from types import SimpleNamespace
        >>> from thymio_bt.behaviours.flow.ticking import tick
        >>> clock = SimpleNamespace(now=lambda: 0.0)
        >>> for result in ("success", "failure"):
        ...     ok = ScriptedStub("ok", result, clock)
        ...     guard = NodeGuard("g", ScriptedStub("go", "running", clock), ok)
        ...     tick(guard)
        ...     print(guard.status.name, ok.status.name)
        RUNNING SUCCESS
        FAILURE FAILURE
        >>> guard.condition_node is ok
        True
    """

    def __init__(self, name: str, child: Behaviour, condition: Behaviour) -> None:
        #: the condition's node, ticked by :meth:`check`
        self.condition_node = condition
        super().__init__(name=name, child=child, condition=self.check)

    def check(self) -> bool:
        """Tick the condition node; whether it succeeded."""
        for _ in self.condition_node.tick():
            pass
        return self.condition_node.status == SUCCESS


class ScriptedStub(Behaviour):
    """A test double that replaces a node: a scripted list of statuses, or a duration then a status.

    ``script`` is a status (``"success"``), a list of statuses returned one per tick (the last one
    repeats), or ``{"status": "success", "seconds": 2.0}`` (RUNNING for that long in simulated time).

    Example::

        >>> from types import SimpleNamespace
        >>> from thymio_bt.behaviours.flow.ticking import tick
        >>> stub = ScriptedStub("fake delete", ["running", "success"], SimpleNamespace(now=lambda: 0.0))
        >>> for _ in range(3):
        ...     tick(stub)
        ...     print(stub.status.name, stub.feedback_message)
        RUNNING scripted: running
        SUCCESS scripted: success
        RUNNING scripted: running
    """

    def __init__(self, name: str, script: Any, ctx: Any) -> None:
        super().__init__(name=name)
        self.ctx = ctx
        if isinstance(script, dict):
            self.queue = [Status[str(script.get("status", "success")).upper()]]
            self.seconds = float(script.get("seconds", 0.0))
        else:
            items = script if isinstance(script, (list, tuple)) else [script]
            self.queue = [Status[str(item).upper()] for item in items]
            self.seconds = 0.0
        if not self.queue:
            raise ValueError(f"the script for '{name}' is empty")
        self.index = 0
        self.started = 0.0

    def initialise(self) -> None:
        """py_trees' start hook: the script starts over."""
        self.index = 0
        self.started = self.ctx.now()

    def update(self) -> Status:
        """The script's next status (RUNNING while its ``seconds`` last)."""
        if self.ctx.now() - self.started < self.seconds - 1e-9:
            self.feedback_message = "scripted: running"
            return RUNNING
        status = self.queue[min(self.index, len(self.queue) - 1)]
        self.index += 1
        self.feedback_message = f"scripted: {status.name.lower()}"
        return status
