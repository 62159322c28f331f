"""BT.CPP 4's built-in nodes as node kinds of the mission language: ``bt_<name>``, tick for tick as
in BT.CPP (:mod:`thymio_bt.behaviours.btcpp_nodes`). An XML mission's ``<Sequence>``,
``<Fallback>``, ``<Repeat num_cycles="3">``... are these; in YAML they are written
``bt_sequence: [...]``, ``bt_repeat: {num_cycles: 3, do: ...}``, with BT.CPP's port names.
``Timeout``, ``Delay`` and ``Sleep`` count milliseconds of simulated time (a run has no other clock).

Example::

    >>> BTCPP_CONTROL[0].yaml_name, BTCPP_CONTROL[0].btcpp_id
    ('bt_sequence', 'Sequence')
    >>> sorted(BTCPP_IDS)[:3]
    ['Delay', 'Fallback', 'ForceFailure']
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

from py_trees.behaviour import Behaviour
from py_trees.common import Status
from pydantic import Field, create_model

from thymio_bt.behaviours import btcpp_nodes as bn
from thymio_bt.behaviours.control_node import ControlNode, ControlParams


class Timeout(bn._Decorator):
    """BT.CPP's ``Timeout``: the child halted and FAILURE once it has run ``msec`` (simulated)."""

    def __init__(self, name: str, child: Behaviour, msec: int, clock: Callable[[], float]) -> None:
        super().__init__(name, child)
        self.msec, self.clock = msec, clock
        self.deadline: float | None = None

    def bt_tick(self) -> Any:
        """The child, unless the time is up while it runs."""
        if self.deadline is None:
            self.deadline = self.clock() + self.msec / 1000.0
            self.status = Status.RUNNING
        if self.msec > 0 and self.decorated.status is Status.RUNNING and self.clock() >= self.deadline - 1e-9:
            bn.reset(self.decorated)
            self.deadline = None
            return Status.FAILURE
        status = bn.execute(self.decorated)
        if status in (Status.SUCCESS, Status.FAILURE):
            self.deadline = None
            bn.reset(self.decorated)
        return status

    def halt(self) -> None:
        """The timer stopped, the child reset."""
        self.deadline = None
        super().halt()


class Delay(bn._Decorator):
    """BT.CPP's ``Delay``: RUNNING for ``delay_msec`` (simulated), then the child."""

    def __init__(self, name: str, child: Behaviour, msec: int, clock: Callable[[], float]) -> None:
        super().__init__(name, child)
        self.msec, self.clock = msec, clock
        self.until: float | None = None

    def bt_tick(self) -> Any:
        """RUNNING until the delay is over, then the child's status."""
        if self.until is None:
            self.until = self.clock() + self.msec / 1000.0
            self.status = Status.RUNNING
        if self.clock() < self.until - 1e-9:
            return Status.RUNNING
        status = bn.execute(self.decorated)
        if status in (Status.SUCCESS, Status.FAILURE):
            self.until = None
            bn.reset(self.decorated)
        return status

    def halt(self) -> None:
        """The delay forgotten, the child reset."""
        self.until = None
        super().halt()


class Sleep(bn.BtNode):
    """BT.CPP's ``Sleep``: RUNNING for ``msec`` (simulated), then SUCCESS."""

    def __init__(self, name: str, msec: int, clock: Callable[[], float]) -> None:
        super().__init__(name, [])
        self.msec, self.clock = msec, clock
        self.until = 0.0

    def bt_tick(self) -> Any:
        """RUNNING until the time is over."""
        if self.status is not Status.RUNNING:
            if self.msec <= 0:
                return Status.SUCCESS
            self.until = self.clock() + self.msec / 1000.0
            return Status.RUNNING
        return Status.RUNNING if self.clock() < self.until - 1e-9 else Status.SUCCESS


class BtControl(ControlNode):
    """A BT.CPP built-in as a node kind: its BT.CPP ID and how it is built."""

    btcpp_id: ClassVar[str] = ""
    make: ClassVar[Callable[..., Behaviour]]

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """The BT.CPP node, with the ports as arguments (and the run's clock for the timed ones)."""
        return cls.make(name, children, params.model_dump(), ctx)


def _kind(ident: str, yaml: str, category: str, make: Callable[..., Behaviour], doc: str, **ports: Any) -> type:
    """A :class:`BtControl` subclass for BT.CPP's ``ident`` with its ``ports`` (name: (type, default))."""
    fields: dict[str, Any] = {k: (t, Field(d, description=desc)) for k, (t, d, desc) in ports.items()}
    params = create_model(f"{ident}Params", __base__=ControlParams, **fields) if fields else ControlParams
    example = f"e.g. '{yaml}: " + ("[A, B]'" if category == "composite" else "{do: CHILD}'")
    attrs = {"__doc__": doc, "yaml_name": yaml, "category": category, "Params": params, "btcpp_id": ident}
    attrs.update(make=staticmethod(make), example=example, short_form=category == "decorator" and not ports)
    return type(f"Bt{ident}", (BtControl,), attrs)


def _composite(cls: type[bn.BtNode]) -> Callable[..., Behaviour]:
    """How a composite of ``cls`` is built (its children, no ports)."""
    return lambda name, children, ports, ctx: cls(name, children)


def _decorator(cls: type[bn._Decorator]) -> Callable[..., Behaviour]:
    """How a decorator of ``cls`` is built (its one child, no ports)."""
    return lambda name, children, ports, ctx: cls(name, children[0])


_COUNT = (int, -1, "how many; -1: all (Parallel) or for ever")
BTCPP_CONTROL: tuple[type[ControlNode], ...] = (
    _kind(
        "Sequence", "bt_sequence", "composite", _composite(bn.Sequence), "BT.CPP's Sequence: restarts after a failure."
    ),
    _kind(
        "SequenceWithMemory",
        "bt_sequence_with_memory",
        "composite",
        _composite(bn.SequenceWithMemory),
        "BT.CPP's SequenceWithMemory: after a failure, resumes at the failed child.",
    ),
    _kind(
        "ReactiveSequence",
        "bt_reactive_sequence",
        "composite",
        _composite(bn.ReactiveSequence),
        "BT.CPP's ReactiveSequence: every child from the first, every tick.",
    ),
    _kind("Fallback", "bt_fallback", "composite", _composite(bn.Fallback), "BT.CPP's Fallback."),
    _kind(
        "ReactiveFallback",
        "bt_reactive_fallback",
        "composite",
        _composite(bn.ReactiveFallback),
        "BT.CPP's ReactiveFallback.",
    ),
    _kind(
        "Parallel",
        "bt_parallel",
        "composite",
        lambda name, children, ports, ctx: bn.Parallel(name, children, ports["success_count"], ports["failure_count"]),
        "BT.CPP's Parallel: success_count successes succeed it, failure_count failures fail it.",
        success_count=(int, -1, "successes that end it with SUCCESS (-1: all)"),
        failure_count=(int, 1, "failures that end it with FAILURE (-1: all)"),
    ),
    _kind(
        "ParallelAll",
        "bt_parallel_all",
        "composite",
        lambda name, children, ports, ctx: bn.ParallelAll(name, children, ports["max_failures"]),
        "BT.CPP's ParallelAll: every child to completion; FAILURE if max_failures failed.",
        max_failures=(int, 1, "failures that make it fail (-1: all)"),
    ),
    _kind("IfThenElse", "bt_if_then_else", "composite", _composite(bn.IfThenElse), "BT.CPP's IfThenElse."),
    _kind("WhileDoElse", "bt_while_do_else", "composite", _composite(bn.WhileDoElse), "BT.CPP's WhileDoElse."),
    _kind("Inverter", "bt_inverter", "decorator", _decorator(bn.Inverter), "BT.CPP's Inverter."),
    _kind("ForceSuccess", "bt_force_success", "decorator", _decorator(bn.ForceSuccess), "BT.CPP's ForceSuccess."),
    _kind("ForceFailure", "bt_force_failure", "decorator", _decorator(bn.ForceFailure), "BT.CPP's ForceFailure."),
    _kind(
        "KeepRunningUntilFailure",
        "bt_keep_running_until_failure",
        "decorator",
        _decorator(bn.KeepRunningUntilFailure),
        "BT.CPP's KeepRunningUntilFailure.",
    ),
    _kind(
        "Repeat",
        "bt_repeat",
        "decorator",
        lambda name, children, ports, ctx: bn.Repeat(name, children[0], ports["num_cycles"]),
        "BT.CPP's Repeat: the child num_cycles times, going on within the tick after a child done at once.",
        num_cycles=(int, ..., "how many successes (-1: for ever)"),
    ),
    _kind(
        "RetryUntilSuccessful",
        "bt_retry_until_successful",
        "decorator",
        lambda name, children, ports, ctx: bn.RetryUntilSuccessful(name, children[0], ports["num_attempts"]),
        "BT.CPP's RetryUntilSuccessful.",
        num_attempts=(int, ..., "how many tries (-1: for ever)"),
    ),
    _kind(
        "RunOnce",
        "bt_run_once",
        "decorator",
        lambda name, children, ports, ctx: bn.RunOnce(name, children[0], ports["then_skip"]),
        "BT.CPP's RunOnce.",
        then_skip=(bool, True, "after the first run: skipped (true) or the same status (false)"),
    ),
    _kind(
        "Timeout",
        "bt_timeout",
        "decorator",
        lambda name, children, ports, ctx: Timeout(name, children[0], ports["msec"], ctx.now),
        "BT.CPP's Timeout, in milliseconds of simulated time.",
        msec=(int, ..., "milliseconds of simulated time"),
    ),
    _kind(
        "Delay",
        "bt_delay",
        "decorator",
        lambda name, children, ports, ctx: Delay(name, children[0], ports["delay_msec"], ctx.now),
        "BT.CPP's Delay, in milliseconds of simulated time.",
        delay_msec=(int, ..., "milliseconds of simulated time"),
    ),
)
#: BT.CPP node ID -> its node kind here
BTCPP_IDS: dict[str, str] = {cls.btcpp_id: cls.yaml_name for cls in BTCPP_CONTROL}  # type: ignore[attr-defined]
