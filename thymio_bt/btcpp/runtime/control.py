"""BT.CPP 4's built-in nodes as node kinds of the mission language: ``bt_<name>``, tick for tick as
in BT.CPP (:mod:`thymio_bt.btcpp.runtime.nodes`). An XML mission's ``<Sequence>``,
``<Fallback>``, ``<Repeat num_cycles="3">``... are these; in YAML they are written
``bt_sequence: [...]``, ``bt_repeat: {num_cycles: 3, do: ...}``, with BT.CPP's port names.
``Timeout``, ``Delay`` and ``Sleep`` count milliseconds of simulated time (a run has no other clock).

Example::

    >>> BTCPP_CONTROL[0].yaml_name, BTCPP_CONTROL[0].btcpp_id
    ('bt_sequence', 'Sequence')
    >>> sorted(BTCPP_IDS)[:3]
    ['AlwaysFailure', 'AlwaysSuccess', 'Delay']
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, ClassVar, Literal, cast

from py_trees.behaviour import Behaviour
from py_trees.common import Status
from pydantic import BaseModel, Field, create_model

from thymio_bt.behaviours.flow import composites, decorators
from thymio_bt.behaviours.flow.node import ControlNode, ControlParams, F, S
from thymio_bt.btcpp.runtime import decorators as bd
from thymio_bt.btcpp.runtime import nodes as bn
from thymio_bt.btcpp.runtime import scripted as bs

#: XML attribute -> its name here
CONDITION_ATTRS = {
    "_failureIf": "failure_if",
    "_successIf": "success_if",
    "_skipIf": "skip_if",
    "_while": "while_true",
    "_onHalted": "on_halted",
    "_onFailure": "on_failure",
    "_onSuccess": "on_success",
    "_post": "post",
}


class BtControl(ControlNode):
    """A BT.CPP built-in as a node kind: its BT.CPP ID and how it is built.

    A BT.CPP node with a twin among the YAML kinds (``like``: ``Sequence``'s is ``sequence``) has
    that kind's facts (:data:`TWIN_FACTS`: its family, its symbol, what it makes of its child's
    outcomes...), declared there once; its body declares only how it differs."""

    btcpp_native = True
    make: ClassVar[Callable[..., Behaviour]]
    #: the YAML kind nearest to it, whose facts it has (docs/btcpp.md's "nearest YAML node")
    like: ClassVar[type[ControlNode] | None] = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Take the twin's facts that the class's body does not declare."""
        super().__init_subclass__(**kwargs)
        if cls.like is not None:
            for fact in TWIN_FACTS:
                if fact not in cls.__dict__:
                    setattr(cls, fact, getattr(cls.like, fact))

    @classmethod
    def build(cls, name: str, params: Any, children: list, ctx: Any) -> Behaviour:
        """The BT.CPP node, with the ports as arguments (and the run's clock for the timed ones)."""
        return cls.make(name, children, params.model_dump(), ctx)


#: the facts a BT.CPP kind takes from its YAML twin: those the lint and the pictures read
TWIN_FACTS = ("family", "reactive", "symbol", "outcome", "fails_alone", "halts", "passes_on", "once")


class _Loop(BtControl):
    """``Repeat`` and ``RetryUntilSuccessful``: the child again after a SUCCESS (Repeat) or a FAILURE
    (Retry), for ever when the count (``num_cycles``, ``num_attempts``) is -1 (``repeat`` and
    ``retry`` have no count of -1: what it makes of the child's outcomes is declared here)."""

    #: the port that counts, and the child's result that runs it again
    count: ClassVar[str]
    again: ClassVar[str]

    @classmethod
    def endless(cls, params: BaseModel, children: int) -> bool:
        """A Repeat of -1 cycles."""
        return cls.again == S and cls.for_ever(params)

    @classmethod
    def ends(cls, params: BaseModel, children: Sequence[frozenset[str]]) -> frozenset[str]:
        """The child's results, but the one that runs it again when it goes on for ever."""
        child = children[0]
        return child - {cls.again} if cls.for_ever(params) else child

    @classmethod
    def for_ever(cls, params: BaseModel) -> bool:
        """Whether the count port is -1 (the kind's ``Params`` are made from its ports: the count is a field)."""
        return bool(getattr(params, cls.count) == -1)


def _kind(
    ident: str,
    yaml: str,
    category: str,
    make: Callable[..., Behaviour],
    doc: str,
    like: type[ControlNode] | None = None,
    facts: Mapping[str, Any] | None = None,
    base: type[BtControl] = BtControl,
    /,
    **ports: Any,
) -> type[BtControl]:
    """A subclass of ``base`` for BT.CPP's ``ident`` with its ``ports`` (name: (type, default)), the
    YAML kind it is ``like`` (its facts) and its own ``facts`` (:class:`ControlNode`'s class
    attributes: family, outcome, symbol...)."""
    fields: dict[str, Any] = {k: (t, Field(d, description=desc)) for k, (t, d, desc) in ports.items()}
    params = create_model(f"{ident}Params", __base__=ControlParams, **fields) if fields else ControlParams
    given = "".join(f"{k}: ..., " for k, (_, d, _) in ports.items() if d is ...)
    example = f"e.g. '{yaml}: " + (
        f"{{{given}children: [A, B]}}'" if category == "composite" else f"{{{given}do: CHILD}}'"
    )
    attrs = {"__doc__": doc, "yaml_name": yaml, "category": category, "Params": params, "btcpp_id": ident}
    attrs.update(make=staticmethod(make), example=example, short_form=category == "decorator" and not ports)
    return cast(type[BtControl], type(f"Bt{ident}", (base,), {**attrs, "like": like, **(facts or {})}))


def _composite(cls: type[bn.BtNode]) -> Callable[..., Behaviour]:
    """How a composite of ``cls`` is built (its children, no ports)."""
    return lambda name, children, ports, ctx: cls(name, children)


def _decorator(cls: type[bd.BtDecorator]) -> Callable[..., Behaviour]:
    """How a decorator of ``cls`` is built (its one child, no ports)."""
    return lambda name, children, ports, ctx: cls(name, children[0])


def _mapping(yaml: str, cls: type[bd._Mapped], like: type[ControlNode] | None) -> type[BtControl]:
    """The kind of BT.CPP's decorator ``cls``, which maps its child's result: the ``outcome`` the
    lint reads is the map its tick uses (a result mapped to RUNNING runs the child again), the other
    facts its twin's (without one: it never halts its child, and starts it when it starts)."""
    letter = {Status.SUCCESS: S, Status.FAILURE: F}
    outcome = {letter[got]: letter[to] for got, to in cls.outcome.items() if to in letter}
    facts = {"outcome": outcome} if like else {"outcome": outcome, "halts": False, "passes_on": True}
    return _kind(cls.__name__, yaml, "decorator", _decorator(cls), f"BT.CPP's {cls.__name__}.", like, facts)


def _loop(
    ident: str, yaml: str, like: type[ControlNode], count: str, again: str, doc: str, what: str
) -> type[BtControl]:
    """The kind of BT.CPP's ``Repeat`` or ``RetryUntilSuccessful`` (``bd``'s class ``ident``), which
    runs its child again after the result ``again``, ``count`` (a port: ``what``) times."""
    loop = getattr(bd, ident)
    make = lambda name, children, ports, ctx: loop(name, children[0], ports[count])  # noqa: E731
    facts = {"count": count, "again": again}
    return _kind(ident, yaml, "decorator", make, doc, like, facts, _Loop, **{count: (int, ..., what)})


def _timed(node: type[bd.Timed], yaml: str, port: str, like: type[ControlNode]) -> type[BtControl]:
    """The kind of BT.CPP's ``Timeout`` or ``Delay`` (``node``): ``port`` milliseconds on the run's clock."""
    make = lambda name, children, ports, ctx: node(name, children[0], ports[port], ctx.now)  # noqa: E731
    doc = f"BT.CPP's {node.__name__}, in milliseconds of simulated time."
    return _kind(
        node.__name__, yaml, "decorator", make, doc, like, **{port: (int, ..., "milliseconds of simulated time")}
    )


BTCPP_CONTROL: tuple[type[ControlNode], ...] = (
    _kind(
        "Sequence",
        "bt_sequence",
        "composite",
        _composite(bn.Sequence),
        "BT.CPP's Sequence: restarts after a failure.",
        composites.Sequence,
    ),
    _kind(
        "SequenceWithMemory",
        "bt_sequence_with_memory",
        "composite",
        _composite(bn.SequenceWithMemory),
        "BT.CPP's SequenceWithMemory: after a failure, resumes at the failed child.",
        composites.Sequence,
    ),
    _kind(
        "ReactiveSequence",
        "bt_reactive_sequence",
        "composite",
        _composite(bn.ReactiveSequence),
        "BT.CPP's ReactiveSequence: every child from the first, every tick.",
        composites.ReactiveSequence,
    ),
    _kind("Fallback", "bt_fallback", "composite", _composite(bn.Fallback), "BT.CPP's Fallback.", composites.Selector),
    _kind(
        "ReactiveFallback",
        "bt_reactive_fallback",
        "composite",
        _composite(bn.ReactiveFallback),
        "BT.CPP's ReactiveFallback.",
        composites.ReactiveSelector,
    ),
    _kind(
        "Parallel",
        "bt_parallel",
        "composite",
        lambda name, children, ports, ctx: bn.Parallel(name, children, ports["success_count"], ports["failure_count"]),
        "BT.CPP's Parallel: success_count successes succeed it, failure_count failures fail it.",
        composites.Parallel,
        success_count=(int, -1, "successes that end it with SUCCESS (-1: all)"),
        failure_count=(int, 1, "failures that end it with FAILURE (-1: all)"),
    ),
    _kind(
        "ParallelAll",
        "bt_parallel_all",
        "composite",
        lambda name, children, ports, ctx: bn.ParallelAll(name, children, ports["max_failures"]),
        "BT.CPP's ParallelAll: every child to completion; FAILURE if max_failures failed.",
        composites.Parallel,
        max_failures=(int, 1, "failures that make it fail (-1: all)"),
    ),
    _kind("IfThenElse", "bt_if_then_else", "composite", _composite(bn.IfThenElse), "BT.CPP's IfThenElse."),
    _kind("WhileDoElse", "bt_while_do_else", "composite", _composite(bn.WhileDoElse), "BT.CPP's WhileDoElse."),
    _mapping("bt_inverter", bd.Inverter, decorators.Invert),
    _mapping("bt_force_success", bd.ForceSuccess, decorators.ForceSuccess),
    _mapping("bt_force_failure", bd.ForceFailure, decorators.ForceFailure),
    _mapping("bt_keep_running_until_failure", bd.KeepRunningUntilFailure, None),
    _loop(
        "Repeat",
        "bt_repeat",
        decorators.Repeat,
        "num_cycles",
        S,
        "BT.CPP's Repeat: the child num_cycles times, going on within the tick after a child done at once.",
        "how many successes (-1: for ever)",
    ),
    _loop(
        "RetryUntilSuccessful",
        "bt_retry_until_successful",
        decorators.Retry,
        "num_attempts",
        F,
        "BT.CPP's RetryUntilSuccessful.",
        "how many tries (-1: for ever)",
    ),
    _kind(
        "RunOnce",
        "bt_run_once",
        "decorator",
        lambda name, children, ports, ctx: bd.RunOnce(name, children[0], ports["then_skip"]),
        "BT.CPP's RunOnce.",
        decorators.OneShot,
        then_skip=(bool, True, "after the first run: skipped (true) or the same status (false)"),
    ),
    _timed(bd.Timeout, "bt_timeout", "msec", decorators.Timeout),
    _timed(bd.Delay, "bt_delay", "delay_msec", decorators.Delay),
)
#: BT.CPP node ID -> its node kind here
BTCPP_IDS: dict[str, str] = {cls.btcpp_id: cls.yaml_name for cls in BTCPP_CONTROL}


def _scripted(kind: str) -> Callable[..., Behaviour]:
    """How the script nodes are built from their ports."""

    def make(name: str, children: list[Behaviour], ports: dict[str, Any], ctx: Any) -> Behaviour:
        if kind == "Precondition":
            otherwise = {"SUCCESS": Status.SUCCESS, "FAILURE": Status.FAILURE, "RUNNING": Status.RUNNING}
            return bs.Precondition(name, children[0], bs.parse(ports["if"]), otherwise[ports["else"]])
        if kind == "conditions":
            scripts = {k: bs.parse(v) for k, v in ports.items() if v is not None}
            return bs.Conditioned(name, children[0], scripts)
        cases = [str(ports[f"case_{i}"]) for i in range(1, int(kind[-1]) + 1)]
        return bs.Switch(name, children, str(ports["variable"]), cases)

    return make


_TEXT = (str, ..., "text, or {key} for a blackboard entry")
#: BT.CPP's leaves, kept with the script nodes: node kind -> BT.CPP ID (filled in below)
BTCPP_SCRIPTED: tuple[type[ControlNode], ...] = (
    _kind(
        "Precondition",
        "bt_precondition",
        "decorator",
        _scripted("Precondition"),
        "BT.CPP's Precondition: the child if the script 'if' holds when it starts.",
        **{
            "if": (bs.Code, ..., "the condition (a script)"),
            "else": (Literal["SUCCESS", "FAILURE", "RUNNING"], "FAILURE", "the status otherwise"),
        },
    ),
    *(
        _kind(
            f"Switch{n}",
            f"bt_switch{n}",
            "composite",
            _scripted(f"Switch{n}"),
            f"BT.CPP's Switch{n}: {n} cases and a default, the last child.",
            variable=_TEXT,
            **{f"case_{i}": (str, ..., f"the value of case {i}") for i in range(1, n + 1)},
        )
        for n in range(2, 7)
    ),
    _kind(
        "conditions",
        "bt_conditions",
        "decorator",
        _scripted("conditions"),
        "BT.CPP's pre/post-condition attributes (_skipIf=... on a node in XML) on the node under do.",
        **{key: (bs.OptionalCode, None, f"BT.CPP's _{key}") for key in (*bs.PRE, *bs.POST)},
    ),
)
BTCPP_IDS.update({c.btcpp_id: c.yaml_name for c in BTCPP_SCRIPTED if c.btcpp_id != "conditions"})
BTCPP_IDS.update({c.btcpp_id: c.yaml_name for c in bs.BTCPP_LEAVES})
