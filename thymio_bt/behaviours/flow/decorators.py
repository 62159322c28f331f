"""The decorators of the mission language: one child under ``do``, changed in one way.

Written ``repeat: {times: 4, do: CHILD}``; those without parameters also as ``invert: CHILD``.

- ``repeat``: run the child ``times`` times (or ``forever``), or ``until`` a condition succeeds
  after a success of the child (a do-while loop); a failure of the child ends it with FAILURE.
- ``retry``: run the child again after a failure, at most ``times`` times.
- ``timeout``: fail the child when it runs longer than ``seconds`` of simulated time.
- ``delay``: wait ``seconds`` of simulated time, then run the child.
- ``invert``: swap SUCCESS and FAILURE; ``force_success`` / ``force_failure``: report that status
  whatever the child ends with (RUNNING stays RUNNING).
- ``until``: RUNNING until the child returns ``status`` (success or failure), then SUCCESS.
- ``guard``: run the child while ``condition`` succeeds (checked every tick); fail when it does not.
- ``one_shot``: once the child succeeded (``on: success``) or finished (``on: completion``), return
  that result without ticking it again.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Annotated, Any, ClassVar, Literal, get_args

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import OneShotPolicy, Status
from py_trees.decorators import FailureIsSuccess, Inverter, SuccessIsFailure
from pydantic import BaseModel, Field, field_validator

from thymio_bt.behaviours.flow.node import SAME, SWAP, ControlNode, ControlParams, F, S, refuse, whole
from thymio_bt.behaviours.flow.primitives import NodeGuard, RepeatUntil, SimTimeout, SimTimer
from thymio_bt.inputs.fields import Duration

_REPEAT_EXAMPLE = "e.g. 'repeat: {times: 4, do: {TurnAngle: {angle: 90deg}}}' or 'repeat: {until: IsDeadEnd, do: ...}'"
_RETRY_EXAMPLE = "e.g. 'retry: {times: 3, do: {MoveUntilWall: {}}}'"


def _times(value: Any, message: str, example: str) -> int:
    """A count of ``repeat`` or ``retry``: a whole number >= 1, else refused with ``message``."""
    count = whole(value)
    if count is None or count < 1:
        raise refuse(message, example)
    return count


def _one_of(field: str, message: str) -> Any:
    """A validator of the ``Literal`` parameter ``field``: a value that is not one of its choices is
    refused with ``message`` (pydantic's own would not name the decorator)."""

    def known(cls: type[ControlParams], value: Any) -> Any:
        if value not in get_args(cls.model_fields[field].annotation):
            raise refuse(message)
        return value

    return field_validator(field, mode="before")(known)


class RepeatParams(ControlParams):
    """How many times ``repeat`` runs its child."""

    times: Annotated[int, Field(ge=1)] | Literal["forever"] = Field(
        "forever", description="how many successes of the child end the loop, or forever"
    )

    @field_validator("times", mode="before")
    @classmethod
    def _count(cls, value: Any) -> Any:
        if value == "forever":
            return value
        return _times(value, "repeat times must be a whole number >= 1 or 'forever'", _REPEAT_EXAMPLE)


class CountedRepeat(py_trees.decorators.Repeat):
    """py_trees' ``Repeat``, its feedback in words ("iteration 2 of 4"; py_trees' own reads
    "[status: 0 success from -1]" for a loop for ever).

    >>> from py_trees.behaviours import Success
    >>> loop = CountedRepeat("loop", Success("leg"), -1)
    >>> loop.tick_once(); loop.feedback_message
    'iteration 2 (for ever)'
    """

    def update(self) -> Status:
        """py_trees' result, with the iteration the loop is at."""
        status = super().update()
        of = "(for ever)" if self.num_success == -1 else f"of {self.num_success}"
        if status is Status.SUCCESS:
            self.feedback_message = f"done: {self.success} iterations"
        else:  # the one running, the one that failed, or the next after a success
            self.feedback_message = f"iteration {self.success + 1} {of}{' failed' * (status is Status.FAILURE)}"
        return status


class CountedRetry(py_trees.decorators.Retry):
    """py_trees' ``Retry``, its feedback in words ("attempt 2 of 3"; py_trees' own reads
    "[status: 1 failure from 3]").

    >>> from py_trees.behaviours import Failure
    >>> retry = CountedRetry("retry", Failure("leg"), 3)
    >>> retry.tick_once(); retry.feedback_message
    'attempt 2 of 3 (1 failed)'
    """

    def update(self) -> Status:
        """py_trees' result, with the attempt it is at."""
        status = super().update()
        if status is Status.FAILURE:
            self.feedback_message = f"all {self.num_failures} attempts failed"
        elif status is Status.SUCCESS:
            self.feedback_message = f"attempt {self.failures + 1} of {self.num_failures} succeeded"
        else:
            failed = f" ({self.failures} failed)" if self.failures else ""
            self.feedback_message = f"attempt {self.failures + 1} of {self.num_failures}{failed}"
        return status


class Repeat(ControlNode):
    """Run the child again after each success: ``times`` times, forever, or ``until`` a condition succeeds."""

    yaml_name = "repeat"
    Params = RepeatParams
    node_keys = ("until",)
    exclusive = (("times", "until"),)
    example = _REPEAT_EXAMPLE
    outcome, halts, passes_on, then = SAME, False, True, "until"
    btcpp_id, btcpp_ports = "Repeat", {"times": "num_cycles"}

    @classmethod
    def endless(cls, params: BaseModel, children: int) -> bool:
        """``times: forever`` (without ``until``)."""
        return isinstance(params, RepeatParams) and params.times == "forever" and children == 1

    @classmethod
    def ends(cls, params: BaseModel, children: Sequence[frozenset[str]]) -> frozenset[str]:
        """A failure of the body ends it; a success, with ``until`` if the condition succeeds after
        it, with ``times`` after the last one, never for ever."""
        body = children[0]
        if len(children) == 2:
            return (body & {F}) | ({S} if S in body and S in children[1] else frozenset())
        return body & {F} if cls.endless(params, len(children)) else body

    @classmethod
    def to_btcpp(cls, params: Mapping[str, Any]) -> dict[str, Any]:
        """``num_cycles``, -1 for ever."""
        return {"num_cycles": -1} if params.get("times") == "forever" else super().to_btcpp(params)

    @classmethod
    def from_btcpp(cls, ports: Mapping[str, Any]) -> dict[str, Any]:
        """``times``, forever for -1."""
        params = super().from_btcpp(ports)
        return {**params, "times": "forever"} if params.get("times") == -1 else params

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A py_trees ``Repeat`` of the child, or a :class:`RepeatUntil` with the ``until`` condition."""
        if len(children) == 2:
            return RepeatUntil(name, body=children[0], condition=children[1])
        times = -1 if params.times == "forever" else params.times
        return CountedRepeat(name=name, child=children[0], num_success=times)


class RetryParams(ControlParams):
    """How many failures ``retry`` takes."""

    times: Annotated[int, Field(ge=1)] = Field(description="how many failures of the child end it with FAILURE")

    @field_validator("times", mode="before")
    @classmethod
    def _count(cls, value: Any) -> Any:
        return _times(value, "retry times must be a whole number >= 1", _RETRY_EXAMPLE)


class Retry(ControlNode):
    """Run the child again after a failure, at most ``times`` failures in all."""

    yaml_name = "retry"
    Params = RetryParams
    example = _RETRY_EXAMPLE
    outcome, halts, passes_on = SAME, False, True
    btcpp_id, btcpp_ports = "RetryUntilSuccessful", {"times": "num_attempts"}

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A py_trees ``Retry`` of the child."""
        return CountedRetry(name=name, child=children[0], num_failures=params.times)


class SecondsParams(ControlParams):
    """A time in simulated seconds (``timeout``, ``delay``)."""

    seconds: Duration = Field(gt=0, le=36000, description="simulated seconds")


class Timeout(ControlNode):
    """Fail (stopping the child) when the child runs longer than ``seconds`` of simulated time."""

    yaml_name = "timeout"
    Params = SecondsParams
    example = "e.g. 'timeout: {seconds: 30, do: {WallFollow: {}}}'"
    outcome, fails_alone, halts, passes_on = SAME, True, True, True

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A :class:`SimTimeout` of the child on the run's clock."""
        return SimTimeout(name, children[0], duration=params.seconds, clock=ctx.now)


class Delay(py_trees.decorators.Decorator, ControlNode):
    """Wait ``seconds`` of simulated time (RUNNING), then run the child and return what it returns."""

    yaml_name = "delay"
    Params = SecondsParams
    example = "e.g. 'delay: {seconds: 2, do: {MoveDistance: {distance: 10cm}}}'"
    outcome, halts, passes_on = SAME, False, True

    def __init__(self, name: str, child: Behaviour, seconds: float, clock: Any) -> None:
        super().__init__(name=name, child=child)
        self.timer = SimTimer(seconds, clock)

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A :class:`Delay` of the child on the run's clock."""
        return cls(name, children[0], params.seconds, ctx.now)

    def initialise(self) -> None:
        """py_trees' start hook: the wait starts now."""
        self.timer.start()

    def tick(self) -> Iterator[Behaviour]:
        """Tick the child only once the delay is over (a Decorator ticks its child first otherwise)."""
        if self.status != Status.RUNNING:
            self.initialise()
        if not self.timer.over():
            self.status = Status.RUNNING
            self.feedback_message = f"{self.timer.left():.1f} s to wait"
            yield self
            return
        yield from super().tick()

    def update(self) -> Status:
        """The child's status, once it runs."""
        self.feedback_message = self.decorated.feedback_message
        return self.decorated.status


class _Outcome(ControlNode):
    """A decorator that only changes how the child's result reads (RUNNING stays RUNNING): a py_trees
    decorator of the child, no parameters, so it may be written ``kind: CHILD``."""

    short_form = True
    halts, passes_on = False, True
    #: the py_trees decorator that maps the child's status
    wraps: ClassVar[type[py_trees.decorators.Decorator]]

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """The py_trees decorator of the child."""
        return cls.wraps(name=name, child=children[0])

    @classmethod
    def of(
        cls,
        yaml_name: str,
        wraps: type[py_trees.decorators.Decorator],
        outcome: Mapping[str, str],
        btcpp_id: str,
        doc: str,
        child: str,
    ) -> type[_Outcome]:
        """The kind ``yaml_name`` (class ``ForceSuccess`` for ``force_success``): ``wraps`` of the child,
        whose results it maps by ``outcome``, BT.CPP's ``btcpp_id``. ``doc`` says what it does,
        ``child`` is an example of one."""
        return type(
            yaml_name.title().replace("_", ""),
            (cls,),
            {
                "__doc__": f"{doc} (RUNNING stays RUNNING).",
                "__module__": cls.__module__,
                "yaml_name": yaml_name,
                "example": f"e.g. '{yaml_name}: {child}'",
                "wraps": wraps,
                "outcome": outcome,
                "btcpp_id": btcpp_id,
            },
        )


#: the kinds that only change how the child's result reads: name, py_trees decorator, its outcome,
#: BT.CPP's node, what it does, a child
_OUTCOMES = (
    ("invert", Inverter, SWAP, "Inverter", "Swap SUCCESS and FAILURE of the child", "{WallAhead: {}}"),
    (
        *("force_success", FailureIsSuccess, {S: S, F: S}, "ForceSuccess"),
        *("Report SUCCESS when the child fails", "{MoveDistance: {distance: 5cm}}"),
    ),
    (
        *("force_failure", SuccessIsFailure, {S: F, F: F}, "ForceFailure"),
        *("Report FAILURE when the child succeeds", "{WallAhead: {}}"),
    ),
)
Invert, ForceSuccess, ForceFailure = (_Outcome.of(*row) for row in _OUTCOMES)


class UntilParams(ControlParams):
    """The child's result ``until`` waits for."""

    status: Literal["success", "failure"] = Field(
        description="the child's result that ends the wait: success or failure"
    )

    _known = _one_of("status", "until status must be success or failure")


class Until(ControlNode):
    """RUNNING until the child returns ``status``, then SUCCESS (the child is ticked again meanwhile)."""

    yaml_name = "until"
    Params = UntilParams
    example = "e.g. 'until: {status: success, do: ...}'"
    halts, passes_on = False, True

    @classmethod
    def ends(cls, params: BaseModel, children: Sequence[frozenset[str]]) -> frozenset[str]:
        """SUCCESS once the child ends with ``status``; never if it cannot."""
        wanted = S if isinstance(params, UntilParams) and params.status == "success" else F
        return frozenset({S}) if wanted in children[0] else frozenset()

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A py_trees ``Condition`` on the child's ``status``."""
        status = Status.SUCCESS if params.status == "success" else Status.FAILURE
        return py_trees.decorators.Condition(name=name, child=children[0], status=status)


class Guard(ControlNode):
    """Run the child while ``condition`` succeeds, checked every tick; FAILURE as soon as it does not."""

    yaml_name = "guard"
    node_keys = ("condition",)
    required_nodes = ("condition",)
    example = "e.g. 'guard: {condition: {WallAhead: {}}, do: ...}'"
    gate = "condition"

    @classmethod
    def ends(cls, params: BaseModel, children: Sequence[frozenset[str]]) -> frozenset[str]:
        """FAILURE when the condition or the child fails; SUCCESS when the child succeeds under it."""
        child, condition = children
        failure = {F} if F in condition or F in child else set()
        return frozenset(failure | ({S} if S in child and S in condition else set()))

    @classmethod
    def may_stop(cls, params: BaseModel, children: Sequence[frozenset[str]], index: int) -> bool:
        """It stops its child when the condition fails."""
        return index == 0 and F in children[1]

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A py_trees ``EternalGuard`` of the child, ``condition`` ticked as its check."""
        child, condition = children
        return NodeGuard(name, child, condition)


class OneShotParams(ControlParams):
    """Which result of the child ``one_shot`` keeps."""

    on: Literal["success", "completion"] = Field(
        "success", description="success: only a success counts; completion: any result"
    )

    _known = _one_of("on", "one_shot on must be success or completion")


class OneShot(ControlNode):
    """Run the child until it succeeds (or finishes, ``on: completion``), then return that result for ever."""

    yaml_name = "one_shot"
    Params = OneShotParams
    short_form = True
    example = "e.g. 'one_shot: {on: completion, do: ...}'"
    outcome, halts, passes_on, once = SAME, False, True, True

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """A py_trees ``OneShot`` of the child with the ``on`` policy."""
        policy = OneShotPolicy.ON_SUCCESSFUL_COMPLETION if params.on == "success" else OneShotPolicy.ON_COMPLETION
        return py_trees.decorators.OneShot(name=name, child=children[0], policy=policy)


#: The decorators, in the order docs list them.
DECORATORS: tuple[type[ControlNode], ...] = (
    Repeat,
    Retry,
    Timeout,
    Delay,
    Invert,
    ForceSuccess,
    ForceFailure,
    Until,
    Guard,
    OneShot,
)
