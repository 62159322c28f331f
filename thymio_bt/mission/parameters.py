"""A node's parameters, read by their declared types: the part of the planning pass
(:mod:`thymio_bt.mission.planner`) that turns ``{distance: 5cm, speed: $cruise}`` into the node's
pydantic parameter model.

Each value is read by its field's type (:mod:`thymio_bt.inputs.fields`): numbers through the unit
parser in the field's unit, tuples and lists element by element, a spawn name for a pose;
``$name`` takes a parameter of the mission or subtree, ``bb:key`` reads the blackboard when the
behaviour starts. Every problem is reported at its place, and all of a node's problems at once.

Example::

    >>> reference_name("$cruise"), reference_name("cruise"), reference_name("$2fast")
    ('cruise', None, None)
    >>> parse_value_kind("10cm/s"), parse_value_kind("fast")
    ('speed', None)
"""

from __future__ import annotations

import math
import types
import typing
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo
from pydantic_core import ErrorDetails

from thymio_bt.errors import Problem
from thymio_bt.inputs.fields import (
    IN_SI,
    SpawnName,
    Unit,
    called_name,
    field_metadata,
    key_hint,
    metadata,
    unit_of,
    within_sensor_range,
)
from thymio_bt.inputs.units import Quantity, UnitError, parse_value
from thymio_bt.inputs.validation import HintRule, Named, Wording, problems_from, range_hint
from thymio_bt.inputs.yamlio import MarkedDict
from thymio_bt.maze import Maze
from thymio_bt.mission.pass_base import LoaderPass, Scope, Where, _parameter_hint
from thymio_bt.robot.model import ROBOTS, RobotModel

#: what :meth:`ParameterReader.convert` returns for a value it reported a problem about
_INVALID = object()


@dataclass(frozen=True, slots=True)
class SetValue(Quantity):
    """A mission parameter's value given by ``--set NAME=TEXT``: a node that refuses it (used
    through ``$NAME``) reports the problem at ``--set``, with the hint the same text gets in a file.

    >>> SetValue(10.0, "speed", name="cruise", text="10").bare
    10.0
    >>> SetValue(0.1, "speed", name="cruise", text="10cm/s").bare is None
    True
    """

    name: str = ""
    text: str = ""

    @property
    def bare(self) -> float | None:
        """The value as a bare number when it was typed as one (``10``), else None."""
        try:
            return float(self.text)
        except ValueError:
            return None


def reference_name(raw: Any) -> str | None:
    """The parameter a ``$name`` value refers to (``"$cruise"`` -> ``cruise``), None for any other value."""
    if isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier():
        return raw[1:]
    return None


@dataclass
class _Reading:
    """One node's parameters being read: where they are written, and what was read so far."""

    kind: str
    model: type[BaseModel]
    body: MarkedDict
    where: Where
    path: str
    values: dict[str, Any] = field(default_factory=dict)
    #: parameter -> blackboard key, for the ``bb:`` values
    refs: dict[str, str] = field(default_factory=dict)
    #: a misspelt key was reported: the field it meant is 'missing' too, say it once
    unknown: bool = False
    #: parameter -> the ``--set`` value its ``$name`` stands for (a problem with it is reported there)
    set_values: dict[str, SetValue] = field(default_factory=dict)
    #: parameter -> the bare number its ``$name`` stands for (for the hint of the unit it meant)
    bare: dict[str, float] = field(default_factory=dict)

    @property
    def file(self) -> str:
        """The file the node is written in."""
        return self.where[0]

    @property
    def fields(self) -> dict[str, FieldInfo]:
        """The parameter model's fields."""
        return self.model.model_fields


class ParameterReader(LoaderPass):
    """Reads nodes' parameters into their models; the planning pass's :class:`LoaderPass` for values."""

    #: the mission's maze, for spawn names written where a pose goes (None: names are not checked)
    maze: Maze | None = None
    #: the mission's robot, whose sensor range bounds a sensed length (None: only the field's own bounds)
    robot: RobotModel | None = None

    def _params(
        self,
        kind: str,
        model: type[BaseModel],
        body: MarkedDict,
        keys: list[Any],
        where: Where,
        path: str,
        scope: Scope,
        allow_refs: bool,
        missing_hint: str = "",
    ) -> tuple[BaseModel | None, dict[str, str]]:
        """A node's parameter model from ``keys`` of ``body`` (units, $parameters, bb: references when
        ``allow_refs``), with every problem reported at its place; (None, refs) when there is one."""
        reading = _Reading(kind, model, body, where, path)
        before = len(self.problems)
        self._name_meant_as_field(reading)
        for key in keys:
            self._read_key(reading, key, scope, allow_refs)
        self._sensed(reading)
        params = self._validated(reading, keys, missing_hint)
        if params is None or len(self.problems) > before:
            return None, reading.refs
        return params, reading.refs

    def _name_meant_as_field(self, reading: _Reading) -> None:
        """``DeleteEntity: {name: my_robot}``: Gazebo's services call the entity ``name``, but here
        ``name:`` labels the node; given without the field other tools call so, it is refused there."""
        field = called_name(reading.model)
        if field is None or "name" not in reading.body or field in reading.body:
            return
        label = reading.body["name"]
        default = reading.fields[field].default
        self.problem(
            f"{reading.kind}: 'name' is the node's label in the tree, not the {field} it acts on "
            f"(that is '{field}', {default!r} when not given)",
            self.where_key(reading.body, "name", reading.file),
            f"{reading.path}.name",
            f"write {reading.kind}: {{{field}: {label}}}; to label the node too, give both: "
            f"{{name: {label}, {field}: {default}}}",
        )

    def _sensed(self, reading: _Reading) -> None:
        """A sensed length past the range of the mission's robot is a problem at its value (and not
        pydantic's, whose bound is the widest robot's): its sensors never read that far."""
        robot = self.robot
        if robot is None:
            return
        for key, value in list(reading.values.items()):
            field = reading.fields.get(key)
            if field is None or not within_sensor_range(field) or not isinstance(value, float):
                continue
            if value <= robot.range_max + 1e-12:
                continue
            del reading.values[key]  # said here, not again by pydantic
            message = f"{value:g} m is beyond the '{robot.name}' robot's sensor range ({robot.range_max:g} m)"
            further = [m for m in ROBOTS.values() if m.range_max >= value]
            hint = f"its sensors never read further: at most {robot.range_max:g} m" + (
                ", or a robot that sees further ("
                + ", ".join(f"--robot {m.name}: {m.range_max:g} m" for m in further)
                + ")"
                if further
                else ""
            )
            given = reading.set_values.get(key)
            if given is not None:  # the value came from --set: said there
                where: Where = ("--set", 0, 0)
                message = f"{given.name}={given.text}: {message} (where {reading.kind}.{key} uses it)"
            else:
                where = self.where_value(reading.body, key, reading.file)
                message = f"{reading.kind}: {key} {message}"
                guess = _unit_guess(field, reading.bare.get(key, reading.body.get(key)))
                hint = f"did you mean {guess}? a bare number is in m; {hint}" if guess else hint
            if not any(p.file == where[0] and p.message == message for p in self.problems):
                self.problem(message, where, f"{reading.path}.{key}", hint)

    def _read_key(self, reading: _Reading, key: Any, scope: Scope, allow_refs: bool) -> None:
        """One parameter of the node, into ``reading``: its value, its blackboard key, or a problem."""
        raw = reading.body[key]
        vwhere = self.where_value(reading.body, key, reading.file)
        if key not in reading.fields:
            if reading.model.model_config.get("extra") == "allow":
                reading.values[key] = raw  # a stand-in for a plugin that was not imported: unchecked
                return
            self.problem(
                f"{reading.kind} has no parameter '{key}'",
                self.where_key(reading.body, key, reading.file),
                f"{reading.path}.{key}",
                key_hint(str(key), reading.model),
            )
            reading.unknown = True
            return
        if allow_refs:
            name = reference_name(raw)
            looked = scope.get(name) if name is not None and name in scope.names() else None
            if isinstance(looked, str) and looked.startswith("bb:"):
                raw = looked  # a parameter that names a blackboard key
            if isinstance(raw, str) and raw.startswith("bb:"):
                self._blackboard_ref(reading, key, raw, vwhere)
                return
        name = reference_name(raw)
        looked = scope.get(name) if name is not None and name in scope.names() else None
        if isinstance(looked, SetValue):
            reading.set_values[key] = looked
        elif isinstance(looked, Quantity) and looked.kind is None:
            reading.bare[key] = looked.value  # cruise: 10 in parameters:, used as $cruise
        value = self.field_value(reading.fields[key], raw, scope, vwhere, f"{reading.path}.{key}")
        if value is not _INVALID:
            reading.values[key] = value

    def _blackboard_ref(self, reading: _Reading, key: Any, raw: str, where: Where) -> None:
        """``key: bb:name``: the value is read from the blackboard when the behaviour starts."""
        reading.refs[key] = raw[3:].strip()
        if not reading.refs[key]:
            self.problem(
                "bb: needs a blackboard key",
                where,
                f"{reading.path}.{key}",
                "e.g. bb:turn_angle (the key ChooseTurn writes)",
            )

    def _validated(self, reading: _Reading, keys: list[Any], missing_hint: str) -> BaseModel | None:
        """The model of the values read, or None when pydantic finds a problem not reported yet (it is
        reported now). A field left for the blackboard, or already reported, is not 'missing' again."""
        failed = {key for key in keys if key not in reading.values and key not in reading.refs}
        try:
            return reading.model.model_validate(reading.values, context=IN_SI)
        except ValidationError as exc:
            # the other values are still checked, so that every problem of the node is reported at once
            def settled(err: ErrorDetails) -> bool:
                """A 'missing' field left for the blackboard, or one already reported."""
                key = err["loc"][0] if err["loc"] else None
                return (
                    err["type"] == "missing"
                    and key is not None
                    and (key in reading.refs or key in failed or reading.unknown)
                )

            problems = problems_from(
                exc,
                reading.body,
                reading.file,
                reading.model,
                f"{reading.path}.",
                at=reading.where[1:],
                wording=Wording(missing=f"{reading.kind} needs '{{key}}'"),
                hint=_hint_rule(reading, missing_hint),
                skip=settled,
            )
            for problem in problems:
                self._validation_problem(reading, problem)
            if problems:
                return None
            return reading.model.model_construct(**{**{k: None for k in reading.refs}, **reading.values})

    def _validation_problem(self, reading: _Reading, problem: Problem) -> None:
        """A problem pydantic found in a node's parameters: at the value's place, or at ``--set`` when
        the value came from there (once, however many nodes use it)."""
        key = problem.path[len(reading.path) + 1 :].partition(".")[0]
        given = reading.set_values.get(key)
        if given is not None:
            message = f"{given.name}={given.text}: {problem.message} (where {reading.kind}.{key} uses it)"
            if any(p.file == "--set" and p.message == message for p in self.problems):
                return  # another use of the same value: the same fix
            problem = Problem(message, "--set", 0, 0, problem.path, problem.hint)
        self.problems.append(problem)

    def argument(self, raw: Any, scope: Scope, where: Where, path: str, kind: str | None) -> Any:
        """A subtree argument: a quantity when it is numeric (in the caller's scope), else as written."""
        name = reference_name(raw)
        if name is not None:
            try:
                return scope.get(name)
            except KeyError:
                self.problem(f"unknown parameter '{raw}'", where, path, _parameter_hint(name, scope))
                return None
        if (
            isinstance(raw, (int, float))
            and not isinstance(raw, bool)
            or (isinstance(raw, str) and not raw.startswith("bb:") and _looks_numeric(raw))
        ):
            value = self.quantity(raw, scope, where, path, kind)
            return None if value is None else Quantity(value, kind or parse_value_kind(raw))
        return raw

    def field_value(self, field: Any, raw: Any, scope: Scope, where: Where, path: str) -> Any:
        """Convert one YAML value for a parameter field: $references, then by the field's type."""
        annotation = field.annotation
        name = reference_name(raw)
        if name is not None and not _is_number(annotation):
            try:
                value = scope.get(name)
            except KeyError:
                self.problem(f"unknown parameter '{raw}'", where, path, _parameter_hint(name, scope))
                return _INVALID
            if isinstance(value, Quantity):
                return value.value
            if not isinstance(value, (str, list)):
                return value
            raw = value  # a text or list parameter (e.g. a spawn name): convert it like a literal
        return self.convert(annotation, field_metadata(field), raw, scope, where, path)

    def convert(self, annotation: Any, extra: list[Any], raw: Any, scope: Scope, where: Where, path: str) -> Any:
        """A YAML value as the type ``annotation`` wants it: numbers through the unit parser (in the
        type's unit), tuples and lists element by element, spawn names for pose types; anything else
        as written, for pydantic to check. The types (thymio_bt.inputs.fields) say everything: a new
        parameter shape built from them needs no change here."""
        meta = metadata(annotation, extra)
        base = _strip_optional(annotation)
        base = typing.get_args(base)[0] if typing.get_origin(base) is typing.Annotated else base
        if raw is None:
            return raw  # an optional value left empty: pydantic says whether that is allowed
        if base in (float, int):
            unit = next((m for m in meta if isinstance(m, Unit)), None)
            value = self.quantity(raw, scope, where, path, unit.kind if unit else None)
            return _INVALID if value is None else value
        origin, args = typing.get_origin(base), typing.get_args(base)
        if origin is tuple:
            return self._convert_tuple(args, meta, raw, scope, where, path)
        if origin is list and isinstance(raw, list) and args:
            out = [
                self.convert(args[0], [], item, scope, self.where_item(raw, i, where), f"{path}[{i}]")
                for i, item in enumerate(raw)
            ]
            return _INVALID if any(v is _INVALID for v in out) else out
        return raw

    def _convert_tuple(
        self, args: tuple[Any, ...], meta: list[Any], raw: Any, scope: Scope, where: Where, path: str
    ) -> Any:
        """A tuple type's value: a spawn name for a pose, else ``[a, b]`` or ``"a, b"`` item by item."""
        if isinstance(raw, str) and "," not in raw and any(isinstance(m, SpawnName) for m in meta):
            if self.maze is None:
                return raw
            pose = self.pose(raw, where, path, scope, self.maze)
            return _INVALID if pose is None else (pose.x, pose.y, pose.yaw)
        if isinstance(raw, str):
            raw = raw.split(",")
        if isinstance(raw, list) and (len(args) == len(raw) or (len(args) == 2 and args[1] is Ellipsis)):
            kinds = [args[0]] * len(raw) if args[1:] == (Ellipsis,) else list(args)
            out = [
                self.convert(kind, [], item, scope, self.where_item(raw, i, where), path)
                for i, (kind, item) in enumerate(zip(kinds, raw, strict=True))
            ]
            return _INVALID if any(v is _INVALID for v in out) else tuple(out)
        return raw


def _strip_optional(annotation: Any) -> Any:
    """``X`` for ``X | None``; any other type as it is."""
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    if typing.get_origin(annotation) in (typing.Union, types.UnionType) and len(args) == 1:
        return args[0]
    return annotation


def _is_number(annotation: Any) -> bool:
    """Whether a field holds a plain number (a ``$name`` there is an expression for the unit parser)."""
    return _strip_optional(annotation) in (float, int)


def _looks_numeric(text: str) -> bool:
    """Whether ``text`` parses as a number (with units, ``$names`` standing for 1)."""
    try:
        parse_value(text, lambda name: Quantity(1.0))
        return True
    except UnitError:
        return False


def parse_value_kind(text: str | int | float) -> str | None:
    """The kind of unit a value is written in (``length`` for ``5cm``), None without one or when it
    does not parse; ``$names`` count as plain numbers."""
    try:
        return parse_value(text, lambda name: Quantity(1.0)).kind
    except UnitError:
        return None


def _hint_rule(reading: _Reading, missing_hint: str) -> HintRule:
    """The hints of a node's parameter errors: a missing one's (the node's own, else the field's
    description), else :func:`_error_hint` of the value as written (or as ``--set`` gave it)."""

    def hint(err: ErrorDetails, named: Named | None) -> str:
        key = err["loc"][0] if err["loc"] else None
        field_info = reading.fields.get(key) if isinstance(key, str) else None
        if err["type"] == "missing":
            return missing_hint or (field_info.description if field_info else "") or ""
        given = reading.set_values.get(key) if isinstance(key, str) else None
        written = reading.bare.get(key, reading.body.get(key)) if isinstance(key, str) else None
        return _error_hint(err, field_info, given.bare if given is not None else written)

    return hint


def _error_hint(err: ErrorDetails, field_info: FieldInfo | None, raw: Any) -> str:
    """The hint for a pydantic error of a parameter written ``raw``: the validator's own, how to write
    a boolean, or the field's range (with the unit a bare number out of range probably meant)."""
    hint = str((err.get("ctx") or {}).get("hint", ""))
    if hint:
        return hint
    if err["type"] in ("bool_parsing", "bool_type"):
        return "write true or false"
    if field_info is None:
        return hint
    hint = range_hint(field_info)
    guess = _unit_guess(field_info, raw)
    if guess:
        return f"did you mean {guess}? a bare number is in {unit_of(field_info)}; {hint}"
    return hint


#: for a bare number out of range, the units a user may have meant, and their factor to the field's unit
_MEANT = {
    "rad": (("deg", math.pi / 180),),
    "m": (("cm", 0.01), ("mm", 0.001)),
    "m/s": (("cm/s", 0.01),),
    "rad/s": (("deg/s", math.pi / 180),),
}


def _unit_guess(field: Any, raw: Any) -> str | None:
    """``90deg`` for ``angle: 90``: the bare number with the first unit that brings it into range."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        return None
    checks = [
        (getattr(meta, attr), test)
        for meta in field.metadata
        for attr, test in (("ge", float.__ge__), ("gt", float.__gt__), ("le", float.__le__), ("lt", float.__lt__))
        if isinstance(getattr(meta, attr, None), (int, float))
    ]
    for unit, factor in _MEANT.get(unit_of(field), ()):
        if all(test(float(raw) * factor, float(bound)) for bound, test in checks):
            return f"{raw:g}{unit}"
    return None
