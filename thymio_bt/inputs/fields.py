"""Parameter types that carry their unit: ``Length``, ``Angle``, ``Speed``, ``Duration``, ...

A node's pydantic parameter model declares each field with one of these types, and everything else
follows from the type: the mission loader converts ``5cm``, ``90deg`` or ``$cruise`` to SI and
refuses a value of the wrong kind, ``thymio-bt behaviours`` prints the unit, and the JSON Schema
carries it. Composite shapes are built from them (``tuple[Length, Length]`` is a point,
``list[Point]`` a path), so a new parameter shape needs no change to the loader.

The same types hold the numbers of the files pydantic reads alone (mazes, a mission's ``expect:``,
assignments): there the :class:`Unit` parses ``20cm`` or ``pi/2`` itself and refuses a value of the
wrong kind or a bare angle past a full turn, with a hint. Values already in SI (the mission loader's,
the blackboard's) are validated with the context :data:`IN_SI` and taken as they are.

Example::

    >>> from pydantic import BaseModel, Field
    >>> class MoveParams(BaseModel):
    ...     distance: Length = Field(0.1, gt=0, description="how far to drive")
    ...     goal: Pose2D = Field(description="[x, y, yaw] or a named spawn of the maze")
    >>> unit_of(MoveParams.model_fields["distance"]), unit_of(MoveParams.model_fields["goal"])
    ('m', 'm, m, rad')
    >>> MoveParams(goal="0.5, 0.3, pi/2").goal          # in Python too, a pose may be written as text
    (0.5, 0.3, 1.5707963267948966)
    >>> MoveParams(distance="5cm", goal=(0, 0, 0)).distance     # and a number with its unit
    0.05
    >>> Unit("rad/s").kind, Unit("1/s").kind              # the unit parser's kind, if the unit has one
    ('angular_speed', None)
"""

from __future__ import annotations

import functools
import types
import typing
from dataclasses import dataclass
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, GetCoreSchemaHandler, ValidationInfo
from pydantic_core import PydanticCustomError, core_schema

from thymio_bt.errors import did_you_mean, type_name
from thymio_bt.inputs.units import UnitError, kind_hint, parse_kind, parse_pose

#: kinds of the units that numbers are declared in (others, like 1/s, are plain numbers); MiB is no
#: SI unit, but the one memory limits are given in
_KIND = {
    "m": "length",
    "rad": "angle",
    "s": "time",
    "m/s": "speed",
    "rad/s": "angular_speed",
    "Hz": "frequency",
    "MiB": "memory",
}

#: the validation context of values already in SI (converted by the mission loader, or computed and
#: put on the blackboard): a :class:`Unit` takes them as they are, leaving pydantic's checks
IN_SI = {"in_si": True}


def hinted_error(message: str, hint: str) -> PydanticCustomError:
    """A validation error with a hint, which :func:`thymio_bt.inputs.validation.problems_from` shows."""
    return PydanticCustomError("value", "{message}", {"message": message, "hint": hint})


def _written(kind: str, value: Any, info: ValidationInfo) -> Any:
    """A number as written in a file, in the unit of ``kind`` (``20cm``, ``pi/2``, ``$name`` where the
    context has a ``resolve``); a :func:`hinted_error` when it is no number of that kind."""
    context = info.context or {}
    if context.get("in_si"):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise hinted_error(f"expected a number, got {type_name(value)}", kind_hint(kind))
    try:
        return parse_kind(value, context.get("resolve"), kind)
    except UnitError as exc:
        raise hinted_error(str(exc), exc.hint or kind_hint(kind)) from None


@dataclass(frozen=True, slots=True)
class Unit:
    """Metadata of a number type: the SI unit it is expressed in."""

    symbol: str

    @property
    def kind(self) -> str | None:
        """The unit parser's kind (``length``, ``angle``...), None for a unit without one (``1/s``)."""
        return _KIND.get(self.symbol)

    def __get_pydantic_core_schema__(self, source: Any, handler: GetCoreSchemaHandler) -> core_schema.CoreSchema:
        """The number's validation: written with a unit of its kind, or already in SI (:data:`IN_SI`)."""
        schema = handler(source)
        kind = self.kind
        if kind is None:
            return schema
        return core_schema.with_info_before_validator_function(functools.partial(_written, kind), schema)

    def __get_pydantic_json_schema__(self, core_schema: Any, handler: Any) -> dict[str, Any]:
        """The number's JSON Schema, with its ``unit`` (editors show it; ``thymio-bt schema`` writes it)."""
        schema = handler(core_schema)
        schema["unit"] = self.symbol
        return schema


class Marker:
    """Metadata that marks a field's type for the readers that look for it (``isinstance``), with an
    optional ``role``; equal to a marker of its class and role. Not a dataclass: a frozen dataclass
    costs about 3 M instructions to create, paid by every start of ``thymio-bt`` (benchmarks/README.md).

    >>> Entry() == Entry("entry") != Entry("removed"), SpawnName()
    (True, SpawnName())
    """

    __slots__ = ("role",)

    def __init__(self, role: str = "") -> None:
        self.role = role

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.role == self.role

    def __hash__(self) -> int:
        return hash((type(self), self.role))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.role!r})" if self.role else f"{type(self).__name__}()"


class SpawnName(Marker):
    """Metadata of a pose type: a named spawn of the mission's maze may be written instead of numbers."""

    __slots__ = ()


class SensorRange(Marker):
    """Metadata of a length a proximity sensor must read: the mission reader bounds it by the range
    of the mission's robot (the field's own ``le``, for the JSON Schema, is the widest robot's)."""

    __slots__ = ()


class CalledName(Marker):
    """Metadata of a text field that other tools call ``name`` (Gazebo's services name the entity so):
    in a mission ``name:`` labels the node, so one given without this field is refused, pointing here."""

    __slots__ = ()


class Entry(Marker):
    """Metadata of a text field that names a blackboard entry: role ``"entry"`` one the node reads or
    writes, ``"removed"`` one it removes. Readers that rename entries read it (the BT.CPP XML reader
    makes the name a subtree's own), as they read :class:`ScriptText` for a field that holds a script."""

    __slots__ = ()

    def __init__(self, role: str = "entry") -> None:
        super().__init__(role)


class ScriptText(Marker):
    """Metadata of a text field that holds a script (BT.CPP's script language), whose entries a reader
    renames as it renames an :class:`Entry`."""

    __slots__ = ()


def port_roles(model: Any) -> dict[str, Entry | ScriptText]:
    """The fields of a parameter model that name a blackboard entry or hold a script, by field name.

    >>> from pydantic import BaseModel
    >>> class P(BaseModel):
    ...     key: BlackboardKey = "turn"
    ...     distance: Length = 0.1
    >>> port_roles(P)
    {'key': Entry('entry')}
    """
    return {
        name: marker
        for name, f in model.model_fields.items()
        for marker in f.metadata
        if isinstance(marker, (Entry, ScriptText))
    }


def called_name(model: Any) -> str | None:
    """The field of a parameter model that other tools call ``name`` (:data:`EntityName`), if any.

    >>> from pydantic import BaseModel
    >>> class P(BaseModel):
    ...     entity: EntityName = "thymio"
    >>> called_name(P), called_name(BaseModel)
    ('entity', None)
    """
    return next((k for k, f in model.model_fields.items() if any(isinstance(m, CalledName) for m in f.metadata)), None)


def key_hint(key: str, model: Any, allowed: Any = None) -> str:
    """The hint for an unknown key of ``model``'s parameters: the field that takes it as a value
    (``forever`` in ``repeat: {forever: true}`` is ``times: forever``), else the nearest of ``allowed``
    (default: the model's fields).

    >>> from typing import Literal
    >>> from pydantic import create_model
    >>> P = create_model("P", times=(int | Literal["forever"], 1))
    >>> key_hint("forever", P), key_hint("tims", P)
    ("did you mean 'times: forever'? forever is a value of times, not a key", "did you mean 'times'?")
    """
    for name, field in model.model_fields.items():
        if key in _words(field.annotation):
            return f"did you mean '{name}: {key}'? {key} is a value of {name}, not a key"
    return did_you_mean(str(key), model.model_fields if allowed is None else allowed)


def _words(annotation: Any) -> set[str]:
    """The strings a type takes as literal values (``Literal["left", "right"]``, inside unions too)."""
    if typing.get_origin(annotation) is typing.Literal:
        return {a for a in typing.get_args(annotation) if isinstance(a, str)}
    return {w for a in typing.get_args(annotation) for w in _words(a)}


def within_sensor_range(field: Any) -> bool:
    """Whether a pydantic field is a :data:`SensedLength`.

    >>> from pydantic import BaseModel
    >>> class P(BaseModel):
    ...     distance: SensedLength = 0.05
    ...     speed: Speed = 0.1
    >>> within_sensor_range(P.model_fields["distance"]), within_sensor_range(P.model_fields["speed"])
    (True, False)
    """
    return any(isinstance(meta, SensorRange) for meta in field.metadata)


Length = Annotated[float, Unit("m")]
"""A length in metres, written ``5cm``, ``0.05 m`` or ``0.05``."""
SensedLength = Annotated[float, Unit("m"), SensorRange()]
"""A length a proximity sensor must be able to read (a stop distance, a wall-ahead threshold):
refused when a mission's robot cannot see that far."""
Angle = Annotated[float, Unit("rad")]
"""An angle in radians, written ``90deg``, ``pi/2`` or ``1.57``."""
Speed = Annotated[float, Unit("m/s")]
"""A speed in metres per second, written ``10cm/s`` or ``0.1``."""
AngularSpeed = Annotated[float, Unit("rad/s")]
"""A turn rate in radians per second, written ``90deg/s`` or ``1.57``."""
Duration = Annotated[float, Unit("s")]
"""A duration in (simulated) seconds, written ``2s``, ``500ms`` or ``2``."""
PerSecond = Annotated[float, Unit("1/s")]
"""A rate or gain per second (e.g. a heading correction)."""
PerSecondPerMetre = Annotated[float, Unit("rad/s/m")]
"""An angular-speed gain per metre of error."""
Point = tuple[Length, Length]
"""A point ``[x, y]`` in world metres."""
Memory = Annotated[float, Unit("MiB")]
"""An amount of memory in MiB, written ``512MiB``, ``1GiB``, ``512MB`` or ``512``."""
EntityName = Annotated[str, CalledName()]
"""The name of an entity of the world (the robot: ``thymio``), what Gazebo's services call ``name``."""
BlackboardKey = Annotated[str, Entry()]
"""The name of a blackboard entry the node reads or writes (a subtree read from BT.CPP XML makes it its own)."""


def _pose_text(value: Any) -> Any:
    """``"0.5, 0.3, pi/2"`` written in Python (the loader converts YAML text itself)."""
    if isinstance(value, str):
        try:
            return parse_pose(value)
        except UnitError as exc:
            raise ValueError(str(exc)) from None
    return value


#: x, y (m) and yaw (rad) of base_link; in a mission, also a named spawn of the maze
Pose2D = Annotated[tuple[Length, Length, Angle], SpawnName(), BeforeValidator(_pose_text)]


def metadata(annotation: Any, field_metadata: list[Any] | tuple[Any, ...] = ()) -> list[Any]:
    """The metadata of a field: pydantic's own list, then an ``Annotated`` one (also inside ``X | None``)."""
    found = list(field_metadata)
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    if typing.get_origin(annotation) is Annotated:
        found += list(annotation.__metadata__)
    elif len(args) == 1 and typing.get_origin(args[0]) is Annotated:
        found += list(args[0].__metadata__)
    return found


def field_metadata(field: Any) -> list[Any]:
    """A pydantic field's own metadata; a plugin written before these types, whose float field says
    ``json_schema_extra={"unit": "m"}``, gets that unit as a :class:`Unit` too."""
    extra = field.json_schema_extra if isinstance(field.json_schema_extra, dict) else {}
    legacy = [Unit(extra["unit"])] if isinstance(extra.get("unit"), str) else []
    return [*field.metadata, *legacy]


def units_in(annotation: Any, field_metadata: list[Any] | tuple[Any, ...] = ()) -> list[str]:
    """The unit symbols of a type, element by element for tuples and lists (``["m", "m", "rad"]``)."""
    own = [m.symbol for m in metadata(annotation, field_metadata) if isinstance(m, Unit)]
    if own:
        return own
    base = annotation.__origin__ if typing.get_origin(annotation) is Annotated else annotation
    args = [a for a in typing.get_args(base) if a is not type(None) and a is not Ellipsis]
    if typing.get_origin(base) in (typing.Union, types.UnionType, tuple, list):
        return [u for a in args for u in units_in(a)]
    return []


def unit_of(field: Any) -> str:
    """The unit of a pydantic field for docs: ``m``, ``m, m, rad`` for a pose, ``""`` without one."""
    units = units_in(field.annotation, field_metadata(field))
    return units[0] if len(set(units)) == 1 else ", ".join(units)


@functools.cache
def _values_class(model: type[BaseModel]) -> type:
    """A plain class with a slot per field of ``model`` (one per parameter model, made once)."""
    return type(f"{model.__name__}Values", (), {"__slots__": tuple(model.model_fields), "__module__": __name__})


def plain_values(params: BaseModel) -> Any:
    """``params``' field values as the attributes of a plain object: the same objects, read in a few
    dozen instructions where a pydantic model's attribute costs ~400 on CPython 3.11 (pydantic's
    ``__getattr__`` keeps the interpreter from specialising the read); for the parameters a
    behaviour reads every tick.

    >>> from pydantic import BaseModel
    >>> class Cruise(BaseModel):
    ...     speed: Speed = 0.1
    >>> values = plain_values(Cruise(speed="5cm/s"))
    >>> values.speed, type(values).__name__
    (0.05, 'CruiseValues')
    """
    values = _values_class(type(params))()
    for name in type(params).model_fields:
        setattr(values, name, getattr(params, name))
    return values


__all__ = [
    "Angle",
    "AngularSpeed",
    "BlackboardKey",
    "Duration",
    "Entry",
    "EntityName",
    "Length",
    "Memory",
    "PerSecond",
    "PerSecondPerMetre",
    "Point",
    "ScriptText",
    "SensedLength",
    "Speed",
    "Unit",
    "plain_values",
    "port_roles",
]
