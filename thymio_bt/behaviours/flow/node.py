"""The base of the mission language's composites and decorators, as registered node kinds.

Like a robot behaviour, a control node kind is one class with its pydantic parameter model, so the
loader validates it, ``thymio-bt behaviours NAME`` documents it and the JSON Schema describes it
from the same place (BehaviorTree.CPP's factory works the same way). A composite takes
``children``; a decorator takes one child under ``do`` and, for some, more nodes under other keys
(``repeat``'s ``until``, ``guard``'s ``condition``).

Every fact about a kind is declared once, on its class, and read there by every tool: its family
(how the lint's rules reason about a sequence or a selector, and how a picture draws it), what it
makes of its children's outcomes (:meth:`ControlNode.ends`), whether it may stop a running child
(:meth:`ControlNode.may_stop`) or runs for ever (:meth:`ControlNode.endless`), its BT.CPP node and
ports for an export and a read back, its symbol in the terminal tree. A new kind, from the package or
a plugin, is one class: nothing else to write.

Example (a whole decorator kind: see :mod:`thymio_bt.behaviours.flow.decorators` for real ones)::

    >>> import py_trees
    >>> class Invert(ControlNode):
    ...     "Swap SUCCESS and FAILURE of the child."
    ...     yaml_name = "invert"
    ...     category = "decorator"
    ...     short_form = True
    ...     outcome = SWAP                     # what the lint knows of it: the child's result swapped,
    ...     halts = False                      # and it never stops its child by itself
    ...     btcpp_id = "Inverter"              # what an export writes
    ...     @classmethod
    ...     def build(cls, name, params, children, ctx):
    ...         return py_trees.decorators.Inverter(name=name, child=children[0])
    >>> Invert.keys()
    ('do',)
    >>> node = Invert.build("not", Invert.Params(), [py_trees.behaviours.Success("ok")], None)
    >>> from thymio_bt.behaviours.flow.ticking import tick
    >>> tick(node)
    >>> node.status
    <Status.FAILURE: 'FAILURE'>
    >>> given = Invert.Params()
    >>> sorted(Invert.ends(given, [frozenset({S})])), Invert.may_stop(given, [BOTH], 0), Invert.symbol
    (['F'], False, '-^-')
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar, Literal, final
from weakref import WeakKeyDictionary

from py_trees.behaviour import Behaviour
from pydantic import BaseModel, ConfigDict
from pydantic_core import PydanticCustomError

from thymio_bt.behaviours.base import RobotBehaviour

if TYPE_CHECKING:
    from thymio_bt.behaviours.base import Context


#: what a node can end with: S (SUCCESS), F (FAILURE); a set of neither is a node that never ends
S, F = "S", "F"
BOTH = frozenset((S, F))
#: the ``outcome`` of a decorator that returns what its child returns, and of one that swaps it
SAME: Mapping[str, str] = MappingProxyType({S: S, F: F})
SWAP: Mapping[str, str] = MappingProxyType({S: F, F: S})
#: a composite's family: ``sequence`` goes on after a success, ``selector`` after a failure,
#: ``parallel`` ticks every child; "" is any other kind (a decorator, BT.CPP's IfThenElse...)
Family = Literal["sequence", "selector", "parallel", ""]


class ControlParams(BaseModel):
    """Parameters of a composite or decorator (none by default)."""

    model_config = ConfigDict(extra="forbid", defer_build=True)


class ControlNode:
    """A composite or decorator kind of the mission language."""

    #: the node's name in mission YAML (``sequence``, ``repeat``, ...): the class's name unless its body sets one
    yaml_name: ClassVar[str] = ""
    category: ClassVar[Literal["composite", "decorator"]] = "decorator"
    Params: ClassVar[type[BaseModel]] = ControlParams
    #: a decorator's keys that hold nodes besides ``do``, and which of them must be given
    node_keys: ClassVar[tuple[str, ...]] = ()
    required_nodes: ClassVar[tuple[str, ...]] = ()
    #: pairs of keys that may not be given together (``repeat``: times or until)
    exclusive: ClassVar[tuple[tuple[str, str], ...]] = ()
    #: whether the decorator may be written ``kind: CHILD`` (no parameters, no other nodes)
    short_form: ClassVar[bool] = False
    #: how to write it, for hints and docs
    example: ClassVar[str] = ""

    # --- its facts, which the lint, the BT.CPP export and reader and the pictures read -------------
    #: its family (see :data:`Family`)
    family: ClassVar[Family] = ""
    #: a sequence or selector that starts again from its first child every tick
    reactive: ClassVar[bool] = False
    #: how the terminal tree draws it (py_trees' symbols: ``{-}`` a sequence, ``[o]`` a reactive selector)
    symbol: ClassVar[str] = "-^-"
    #: a decorator's result once its child ended with S or F (a result missing: it runs the child
    #: again); None when the lint knows nothing of it (it may end either way)
    outcome: ClassVar[Mapping[str, str] | None] = None
    #: whether it can fail by itself, whatever its child does (a timeout, when the time is up)
    fails_alone: ClassVar[bool] = False
    #: whether it may halt a running child by itself (a timeout: when the time is up); only False is trusted
    halts: ClassVar[bool] = True
    #: a decorator that starts its child when it starts (the lint follows a drive down through it)
    passes_on: ClassVar[bool] = False
    #: a decorator that returns its child's result, once it has one, without running the child again
    once: ClassVar[bool] = False
    #: the node key of a condition checked before the child at every tick: the child runs only while
    #: it succeeds (``guard``'s ``condition``)
    gate: ClassVar[str] = ""
    #: the node key of a condition checked after each success of the child, which ends the loop
    #: when it succeeds (``repeat``'s ``until``)
    then: ClassVar[str] = ""
    #: BT.CPP 4's node an export writes for it ("": none, the export writes ``yaml_name`` and declares it)
    btcpp_id: ClassVar[str] = ""
    #: its parameters' names as the ports of that BT.CPP node, where they differ
    btcpp_ports: ClassVar[Mapping[str, str]] = MappingProxyType({})
    #: whether it is BT.CPP's own node, tick for tick (``bt_*``): exported with BT.CPP's ports as they are
    btcpp_native: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Name the subclass: its own ``yaml_name``, else its class name (never its parent's)."""
        super().__init_subclass__(**kwargs)
        if "yaml_name" not in cls.__dict__:
            cls.yaml_name = cls.__name__

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """The keys its long form takes besides ``name``, in the order messages list them."""
        if cls.category == "composite":
            return ("children", *cls.Params.model_fields)
        return (*cls.Params.model_fields, *cls.node_keys, "do")

    @classmethod
    def build(cls, name: str, params: Any, children: list[Behaviour], ctx: Context) -> Behaviour:
        """The py_trees node: ``children`` are the built ``do`` child then the ``node_keys`` ones in
        order (a composite: its children)."""
        raise NotImplementedError

    @final
    @classmethod
    def instantiate(cls, name: str, params: Any, children: list[Behaviour], ctx: Context) -> Behaviour:
        """:meth:`build`'s node, remembered as one of this kind (:func:`node_kind`): what the tree
        builder calls (final: a kind overrides :meth:`build`)."""
        node = cls.build(name, params, children, ctx)
        _KINDS[node] = cls.yaml_name
        return node

    @classmethod
    def ends(cls, params: BaseModel, children: Sequence[frozenset[str]]) -> frozenset[str]:
        """What a node of this kind with parameters ``params`` (its ``Params``, validated) can end
        with, when its children (in the plan's order) can end with ``children``: a sequence or selector by its family, a
        decorator by its ``outcome``, anything else either way."""
        if cls.family in ("sequence", "selector"):
            go_on, stop = (S, F) if cls.family == "sequence" else (F, S)
            ends: set[str] = set()
            for got in children:
                ends |= got & {stop}
                if go_on not in got:
                    return frozenset(ends)
            return frozenset(ends | {go_on})
        if cls.outcome is not None and children:
            ends = {cls.outcome[c] for c in children[0] if c in cls.outcome}
            return frozenset(ends | {F}) if cls.fails_alone else frozenset(ends)
        return BOTH

    @classmethod
    def may_stop(cls, params: BaseModel, children: Sequence[frozenset[str]], index: int) -> bool:
        """Whether a node of this kind may stop its child ``index`` while it runs (``children``: what
        each child can end with): a reactive composite when an earlier child can end it, a plain one
        never, another kind as ``halts`` says."""
        if cls.family in ("sequence", "selector"):
            preempt = F if cls.family == "sequence" else S
            return cls.reactive and any(preempt in got for got in children[:index])
        return cls.halts

    @classmethod
    def endless(cls, params: BaseModel, children: int) -> bool:
        """Whether a node of this kind with parameters ``params`` and that many children loops for
        ever over a child that never fails (a ``repeat: forever``)."""
        return False

    @classmethod
    def to_btcpp(cls, params: Mapping[str, Any]) -> dict[str, Any]:
        """Its parameters as the ports of its BT.CPP node (``btcpp_ports`` renamed)."""
        return {cls.btcpp_ports.get(k, k): v for k, v in params.items()}

    @classmethod
    def from_btcpp(cls, ports: Mapping[str, Any]) -> dict[str, Any]:
        """The ports of its BT.CPP node, read back as its parameters (:meth:`to_btcpp` undone)."""
        names = {port: name for name, port in cls.btcpp_ports.items()}
        return {names.get(k, k): v for k, v in ports.items()}


#: the kind of each node a control kind made: py_trees' node classes have no room for it, and one
#: class may serve several kinds (``sequence`` and ``bt_sequence``); weak, so a dropped tree is forgotten
_KINDS: WeakKeyDictionary[Behaviour, str] = WeakKeyDictionary()


def node_kind(node: Behaviour) -> str:
    """The YAML kind of a node of a built tree, as logs and exports name it: the control kind that
    made it (:meth:`ControlNode.instantiate`), a robot behaviour's ``yaml_name``, else its class's name
    (py_trees' own nodes, those a control node builds inside itself, a substitution's stub).

    >>> import py_trees
    >>> class Invert(ControlNode):
    ...     yaml_name = "invert"
    ...     @classmethod
    ...     def build(cls, name, params, children, ctx):
    ...         return py_trees.decorators.Inverter(name=name, child=children[0])
    >>> node = Invert.instantiate("not", None, [py_trees.behaviours.Success("ok")], None)
    >>> node_kind(node), node_kind(node.children[0])
    ('invert', 'Success')
    """
    kind = _KINDS.get(node)
    if kind is not None:
        return kind
    return node.yaml_name if isinstance(node, RobotBehaviour) else type(node).__name__


def refuse(message: str, hint: str = "") -> PydanticCustomError:
    """A validation error with its own message and hint, for a parameter validator to raise."""
    return PydanticCustomError("value_error", message, {"hint": hint} if hint else None)


def whole(value: Any) -> int | None:
    """``value`` as an int when it is a whole number (``4`` or ``4.0``, as the unit parser gives), else None."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if isinstance(value, float) and not value.is_integer():
        return None
    return int(value)
