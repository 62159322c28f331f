"""The validate-and-plan pass: the ``tree:`` of an assembled mission, node by node, into a
:class:`~thymio_bt.mission.plan.NodePlan`.

Each node's type is looked up in the registry (a behaviour, a composite, a decorator) or among the
mission's subtrees; its parameters are read by their declared types (thymio_bt.inputs.fields: units,
tuples, spawn names) and validated by its pydantic model, so every problem is reported where it
was written. Subtrees are expanded with their arguments in place.
"""

from __future__ import annotations

import math
import types
import typing
from typing import Any

from pydantic import BaseModel, ValidationError

from thymio_bt.behaviours import ControlNode
from thymio_bt.errors import did_you_mean, type_name
from thymio_bt.inputs.fields import SpawnName, Unit, field_metadata, metadata, unit_of
from thymio_bt.inputs.units import Quantity, UnitError, parse_value
from thymio_bt.inputs.yamlio import MarkedDict
from thymio_bt.mission.assemble import Assembly
from thymio_bt.mission.checker import Checker, Scope, Where, _parameter_hint
from thymio_bt.mission.plan import NodePlan

MAX_DEPTH = 64
#: Most nodes one mission may expand to (subtrees calling subtrees twice each multiply).
MAX_NODES = 20_000


class TreePlanner(Checker):
    """Runs the planning pass over an :class:`Assembly`'s tree; problems go to the assembly's list."""

    def __init__(self, assembly: Assembly) -> None:
        super().__init__(assembly.problems)
        self.registry = assembly.registry
        self.subtrees = assembly.subtrees
        self.maze = assembly.maze
        self.root_scope = Scope(assembly.parameters)
        self.node_count = 0
        self.too_deep: set[Where] = set()

    def plan(self, data: MarkedDict, file: str) -> NodePlan | None:
        """The plan of the mission's ``tree:`` (None when it is missing or broken: see the problems)."""
        if "tree" not in data:
            self.problem("missing required key 'tree'", (file, *data.mark), "", "the tree is the mission's root node")
            return None
        return self.node(data["tree"], self.where_value(data, "tree", file), "tree", self.root_scope, 0, ())

    def node(
        self, value: Any, where: Where, path: str, scope: Scope, depth: int, subtree_stack: tuple[str, ...]
    ) -> NodePlan | None:
        """One tree node: ``{Type: body}``, or a bare ``Type`` string for a node without parameters.
        A node the XML reader made from a ``<SubTree>`` stays marked as that subtree's use."""
        plan = self._node(value, where, path, scope, depth, subtree_stack)
        used = getattr(value, "subtree_use", None)
        if plan is not None and used is not None:
            plan.subtree = used
        return plan

    def _node(
        self, value: Any, where: Where, path: str, scope: Scope, depth: int, subtree_stack: tuple[str, ...]
    ) -> NodePlan | None:
        file = where[0]
        self.node_count += 1
        if self.node_count > MAX_NODES:
            if self.node_count == MAX_NODES + 1:
                self.problem(
                    f"the tree expands to more than {MAX_NODES} nodes",
                    where,
                    path,
                    "subtrees that use other subtrees several times multiply; simplify the tree",
                )
            return None
        if depth > MAX_DEPTH:
            if where not in self.too_deep:  # once per place, not once per subtree expansion
                self.too_deep.add(where)
                self.problem(f"the tree is nested deeper than {MAX_DEPTH} levels", where, path)
            return None
        if isinstance(value, str):
            kind, body, body_where = value, None, where
        elif isinstance(value, MarkedDict) and len(value) == 1:
            kind = next(iter(value))
            body, body_where = value[kind], self.where_value(value, kind, file)
            where = self.where_key(value, kind, file)
        else:
            keys = f" (found keys: {', '.join(map(str, value))})" if isinstance(value, dict) and value else ""
            self.problem(
                f"a node is a mapping with exactly one key: a behaviour, composite, decorator or subtree name{keys}",
                where,
                path,
                "e.g. '- MoveUntilWall: {distance: 5cm}' or '- sequence: [...]'",
            )
            return None
        if not isinstance(kind, str):
            self.problem(f"a node type must be a name, got {type_name(kind)}", where, path)
            return None
        node_path = f"{path}.{kind}" if path else kind
        if kind in self.registry:
            cls = self.registry[kind]
            if issubclass(cls, ControlNode):
                return self._control(cls, body, where, body_where, node_path, scope, depth, subtree_stack)
            return self._behaviour(kind, body, where, body_where, node_path, scope)
        if kind in self.subtrees:
            return self._use_subtree(kind, body, where, body_where, node_path, scope, depth, subtree_stack)
        self.problem(
            f"unknown node type '{kind}'", where, node_path, did_you_mean(kind, [*self.registry, *self.subtrees])
        )
        return None

    def _name(self, body: Any, default: str, file: str, path: str) -> str:
        if isinstance(body, MarkedDict) and "name" in body:
            name = body["name"]
            if isinstance(name, str) and name and "/" not in name:
                return name
            self.problem("name must be a non-empty string without '/'", self.where_value(body, "name", file), path)
        return default

    def _children(
        self, raw: Any, where: Where, path: str, scope: Scope, depth: int, stack: tuple[str, ...]
    ) -> list[NodePlan]:
        file = where[0]
        if not isinstance(raw, list) or not raw:
            self.problem(
                "children must be a non-empty list of nodes",
                where,
                path,
                "e.g. children: [{MoveUntilWall: {distance: 5cm}}, {TurnAngle: {angle: 90deg}}]",
            )
            return []
        children = []
        for i, item in enumerate(raw):
            child = self.node(item, self.where_value(raw, i, file), f"{path}[{i}]", scope, depth + 1, stack)
            if child is not None:
                children.append(child)
        seen: dict[str, int] = {}
        for child in children:  # unique names among siblings keep node paths unambiguous
            count = seen.get(child.name, 0) + 1
            seen[child.name] = count
            if count > 1:
                child.name = f"{child.name}#{count}"
        return children

    def _control(
        self,
        cls: type[ControlNode],
        body: Any,
        where: Where,
        body_where: Where,
        path: str,
        scope: Scope,
        depth: int,
        stack: tuple[str, ...],
    ) -> NodePlan | None:
        """A composite (``children``) or decorator (``do`` and its other node keys), with its parameters."""
        file, kind = where[0], cls.yaml_name
        composite = cls.category == "composite"
        long_form = isinstance(body, MarkedDict) and ("children" in body if composite else "do" in body)
        if composite and isinstance(body, MarkedDict):
            long_form = True
        elif not composite and not long_form and not cls.short_form:
            self.problem(f"{kind} needs a mapping with {', '.join(cls.keys())}", body_where, path, cls.example)
            return None
        if long_form:
            self.check_keys(body, ("name", *cls.keys()), file, path, f"a {kind}")
        fields = cls.Params.model_fields
        params, _ = self._params(
            kind,
            cls.Params,
            body if long_form else MarkedDict(),
            [k for k in body if k in fields] if long_form else [],
            where,
            path,
            scope,
            allow_refs=False,
            missing_hint=cls.example,
        )
        if composite:
            raw_children = body.get("children") if long_form else body
            children_where = (
                self.where_value(body, "children", file) if long_form and "children" in body else body_where
            )
            children = self._children(raw_children, children_where, path, scope, depth, stack)
        else:
            child = (
                self.node(body["do"], self.where_value(body, "do", file), f"{path}.do", scope, depth + 1, stack)
                if long_form
                else self.node(body, body_where, f"{path}.do", scope, depth + 1, stack)
            )
            children = [child] if child is not None else []
            for key in cls.node_keys:
                if long_form and key in body:
                    extra = self.node(
                        body[key], self.where_value(body, key, file), f"{path}.{key}", scope, depth + 1, stack
                    )
                    if extra is not None:
                        children.append(extra)
                elif key in cls.required_nodes:
                    self.problem(f"{kind} needs a {key}", body_where, path, cls.example)
                    return None
            for first, second in cls.exclusive:
                if long_form and first in body and second in body:
                    self.problem(f"{kind} takes either {first} or {second}, not both", body_where, path)
            if child is None:
                return None
        if params is None:
            return None
        return NodePlan(
            kind,
            self._name(body, kind, file, path),
            path,
            params=params,
            options=params.model_dump(),
            children=children,
            where=where,
        )

    def _behaviour(
        self, kind: str, body: Any, where: Where, body_where: Where, path: str, scope: Scope
    ) -> NodePlan | None:
        file = where[0]
        if body is None:
            body = MarkedDict()
        if not isinstance(body, MarkedDict):
            self.problem(
                f"{kind} takes a mapping of parameters, got {type_name(body)}",
                body_where,
                path,
                f"e.g. '{kind}: {{}}'; see 'thymio-bt behaviours {kind}'",
            )
            return None
        params, refs = self._params(
            kind,
            self.registry[kind].Params,
            body,
            [k for k in body if k != "name"],
            where,
            path,
            scope,
            allow_refs=True,
        )
        if params is None:
            return None
        return NodePlan(
            "behaviour",
            self._name(body, kind, file, path),
            path,
            behaviour=kind,
            params=params,
            blackboard_refs=refs,
            where=where,
        )

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
    ) -> tuple[Any, dict[str, str]]:
        """A node's parameter model from ``keys`` of ``body`` (units, $parameters, bb: references when
        ``allow_refs``), with every problem reported at its place; (None, refs) when there is one."""
        file = where[0]
        fields = model.model_fields
        values: dict[str, Any] = {}
        refs: dict[str, str] = {}
        unknown = False  # a misspelt key: the field it meant is 'missing' too, say it once
        before = len(self.problems)
        for key in keys:
            raw = body[key]
            vwhere = self.where_value(body, key, file)
            if key not in fields and model.model_config.get("extra") == "allow":
                values[key] = raw  # a stand-in for a plugin that was not imported: unchecked
                continue
            if key not in fields:
                self.problem(
                    f"{kind} has no parameter '{key}'",
                    self.where_key(body, key, file),
                    f"{path}.{key}",
                    did_you_mean(str(key), fields),
                )
                unknown = True
                continue
            if allow_refs and isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier():
                looked = scope.values.get(raw[1:]) if raw[1:] in scope.names() else None
                if looked is None and raw[1:] in scope.names():
                    looked = scope.get(raw[1:])
                if isinstance(looked, str) and looked.startswith("bb:"):
                    raw = looked
            if allow_refs and isinstance(raw, str) and raw.startswith("bb:"):
                refs[key] = raw[3:].strip()
                if not refs[key]:
                    self.problem(
                        "bb: needs a blackboard key",
                        vwhere,
                        f"{path}.{key}",
                        "e.g. bb:turn_angle (the key ChooseTurn writes)",
                    )
                continue
            value = self.field_value(fields[key], raw, scope, vwhere, f"{path}.{key}")
            if value is not _INVALID:
                values[key] = value
        failed = {key for key in keys if key not in values and key not in refs}  # already reported
        try:
            params = model.model_validate(values)
        except ValidationError as exc:
            # the other values are still checked, so that every problem of the node is reported at once
            errors = [
                e
                for e in exc.errors(include_url=False)
                if not (
                    e["type"] == "missing" and e["loc"] and (e["loc"][0] in refs or e["loc"][0] in failed or unknown)
                )
            ]
            if errors:
                for err in errors:
                    key = err["loc"][0] if err["loc"] else None
                    vwhere = self.where_value(body, key, file) if key in body else where
                    message = err["msg"].removeprefix("Value error, ")
                    hint = str((err.get("ctx") or {}).get("hint", ""))
                    if not hint and err["type"] in ("bool_parsing", "bool_type"):
                        hint = "write true or false"
                    elif not hint and key in fields:
                        hint = _range_hint(fields[key])
                        guess = _unit_guess(fields[key], body.get(key) if isinstance(body, dict) else None)
                        if guess:
                            hint = f"did you mean {guess}? a bare number is in {unit_of(fields[key])}; {hint}"
                    if err["type"] == "missing":
                        message = f"{kind} needs '{key}'"
                        hint = missing_hint or fields[key].description or ""
                    self.problem(message, vwhere, f"{path}.{key}" if key else path, hint)
                return None, refs
            params = model.model_construct(**{**{k: None for k in refs}, **values})
        if len(self.problems) > before:
            return None, refs
        return params, refs

    def _use_subtree(
        self,
        kind: str,
        body: Any,
        where: Where,
        body_where: Where,
        path: str,
        scope: Scope,
        depth: int,
        stack: tuple[str, ...],
    ) -> NodePlan | None:
        file = where[0]
        if kind in stack:
            self.problem(
                f"subtree '{kind}' uses itself ({' -> '.join([*stack, kind])})",
                where,
                path,
                "a subtree may not contain itself; use repeat: to loop",
            )
            return None
        sub = self.subtrees[kind]
        sfile = sub.where[0]
        declared = sub.body.get("parameters") or MarkedDict()
        if not isinstance(declared, MarkedDict):
            self.problem(
                f"subtree '{kind}': parameters must be a mapping of name: default",
                self.where_value(sub.body, "parameters", sfile),
                f"subtrees.{kind}",
            )
            return None
        values: dict[str, Any] = {}
        for name, raw in declared.items():
            values[name] = self._argument(
                raw,
                self.root_scope,
                self.where_value(declared, name, sfile),
                f"subtrees.{kind}.parameters.{name}",
                None,
            )
        if body is not None and not isinstance(body, MarkedDict):
            self.problem(f"subtree '{kind}' takes a mapping of parameters", body_where, path)
            return None
        for name, raw in (body or {}).items():
            if name == "name":
                continue
            if name not in declared:
                self.problem(
                    f"subtree '{kind}' has no parameter '{name}'",
                    self.where_key(body, name, file),
                    f"{path}.{name}",
                    did_you_mean(str(name), declared) if declared else f"subtree '{kind}' declares no parameters",
                )
                continue
            old = values.get(name)
            values[name] = self._argument(
                raw,
                scope,
                self.where_value(body, name, file),
                f"{path}.{name}",
                old.kind if isinstance(old, Quantity) else None,
            )
        tree = self.node(
            sub.body["tree"],
            self.where_value(sub.body, "tree", sfile),
            path,
            Scope(values, self.root_scope),
            depth + 1,
            (*stack, kind),
        )
        if tree is not None:
            tree.name = self._name(body, kind, file, path)
            tree.subtree = kind
        return tree

    def _argument(self, raw: Any, scope: Scope, where: Where, path: str, kind: str | None) -> Any:
        """A subtree argument: a quantity when it is numeric (in the caller's scope), else as written."""
        if isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier():
            try:
                return scope.get(raw[1:])
            except KeyError:
                self.problem(f"unknown parameter '{raw}'", where, path, _parameter_hint(raw[1:], scope))
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
        if isinstance(raw, str) and raw.startswith("$") and raw[1:].isidentifier() and not _is_number(annotation):
            try:
                value = scope.get(raw[1:])
            except KeyError:
                self.problem(f"unknown parameter '{raw}'", where, path, _parameter_hint(raw[1:], scope))
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
            if isinstance(raw, str) and "," not in raw and any(isinstance(m, SpawnName) for m in meta):
                if self.maze is None:
                    return raw
                pose = self.pose(raw, where, path, scope, self.maze)
                return _INVALID if pose is None else (pose.x, pose.y, pose.yaw)
            if isinstance(raw, str):
                raw = raw.split(",")
            if isinstance(raw, list) and (len(args) == len(raw) or (len(args) == 2 and args[1] is Ellipsis)):
                kinds = [args[0]] * len(raw) if args[1:] == (Ellipsis,) else list(args)
                out = [self.convert(kind, [], item, scope, where, path) for kind, item in zip(kinds, raw)]
                return _INVALID if any(v is _INVALID for v in out) else tuple(out)
        if origin is list and isinstance(raw, list) and args:
            out = [
                self.convert(args[0], [], item, scope, self.where_item(raw, i, where), f"{path}[{i}]")
                for i, item in enumerate(raw)
            ]
            return _INVALID if any(v is _INVALID for v in out) else out
        return raw


_INVALID = object()


def _strip_optional(annotation: Any) -> Any:
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    if typing.get_origin(annotation) in (typing.Union, types.UnionType) and len(args) == 1:
        return args[0]
    return annotation


def _is_number(annotation: Any) -> bool:
    return _strip_optional(annotation) in (float, int)


def _looks_numeric(text: str) -> bool:
    try:
        parse_value(text, lambda name: Quantity(1.0))
        return True
    except UnitError:
        return False


def parse_value_kind(text: str) -> str | None:
    try:
        return parse_value(text, lambda name: Quantity(1.0)).kind
    except UnitError:
        return None


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


def _range_hint(field: Any) -> str:
    bounds = []
    for meta in field.metadata:
        for attr, sym in (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<")):
            value = getattr(meta, attr, None)
            if value is not None:
                bounds.append(f"{sym} {value:g}" if isinstance(value, (int, float)) else f"{sym} {value}")
    unit = unit_of(field)
    return f"allowed: {' and '.join(bounds)}{(' ' + unit) if unit else ''}" if bounds else (field.description or "")
