"""The base of the mission language's composites and decorators, as registered node kinds.

Like a robot behaviour, a control node kind is one class with its pydantic parameter model, so the
loader validates it, ``thymio-bt behaviours NAME`` documents it and the JSON Schema describes it
from the same place (BehaviorTree.CPP's factory works the same way). A composite takes
``children``; a decorator takes one child under ``do`` and, for some, more nodes under other keys
(``repeat``'s ``until``, ``guard``'s ``condition``).

Example (a whole decorator kind: see :mod:`thymio_bt.behaviours.flow.decorators` for real ones)::

    >>> import py_trees
    >>> class Invert(ControlNode):
    ...     "Swap SUCCESS and FAILURE of the child."
    ...     yaml_name = "invert"
    ...     category = "decorator"
    ...     short_form = True
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
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict
from pydantic_core import PydanticCustomError

if TYPE_CHECKING:
    from py_trees.behaviour import Behaviour

    from thymio_bt.behaviours.base import Context


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
