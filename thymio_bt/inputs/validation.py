"""Turn pydantic validation errors into :class:`Problem` s that point at file:line:col: the one
translator every reader of user input calls (missions, mazes, profiles, topic maps, backend options,
run logs), so that each says the same thing the same way.

The data should come from :func:`thymio_bt.inputs.yamlio.load_yaml`, whose dicts and lists carry
marks; data without marks (``--backend-opt``, values built from an XML element) gives the place
``at`` instead.

Example::

    >>> from thymio_bt.inputs.yamlio import loads_yaml
    >>> from thymio_bt.robot.noise import NoiseConfig
    >>> data = loads_yaml("noise: {wheel: 0.1, whel: 2}", "m.yaml")
    >>> locate(data, ["noise", "wheel"]), key_mark(data, ["noise", "wheel"])     # (line, column)
    ((1, 16), (1, 9))
    >>> validate(NoiseConfig, data["noise"], "m.yaml", "noise.")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: m.yaml:1:21: unknown key 'whel' [at noise.whel] (hint: did you mean 'wheel'?)
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo
from pydantic_core import ErrorDetails

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.fields import unit_of
from thymio_bt.inputs.yamlio import Mark, MarkedDict, MarkedList, mark_of

M = TypeVar("M", bound=BaseModel)

#: a field and the name it is written with
Named = tuple[str, FieldInfo]
#: the hint of an error that is no unknown key: (error, the field it is about or None) -> hint
HintRule = Callable[[ErrorDetails, Named | None], str]

_BOUNDS = (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<"))


@dataclass(frozen=True, slots=True)
class Wording:
    """How a translated error reads: ``{key}`` is the last name of its place, ``{path}`` the whole
    place, ``{msg}`` pydantic's message (without its 'Value error, '); no other braces are read, so
    a name from a file may be written into a template as it is."""

    unknown: str = "unknown key '{key}'"
    missing: str = "missing required key '{key}'"
    invalid: str = "{msg}"

    def say(self, template: str, words: dict[str, str]) -> str:
        """``template`` with its ``{key}``, ``{path}`` and ``{msg}`` filled in, in one pass."""
        return _WORDS.sub(lambda m: words[m.group(1)], template)


_WORDS = re.compile(r"\{(key|path|msg)\}")


def locate(data: Any, loc: Sequence[Any]) -> Mark:
    """The mark of the deepest node of ``data`` along ``loc`` (keys and indexes)."""
    mark: Mark = mark_of(data)
    node = data
    for step in loc:
        if isinstance(node, MarkedDict) and step in node:
            mark = node.value_marks.get(step, node.marks.get(step, mark))
            node = node[step]
        elif isinstance(node, MarkedList) and isinstance(step, int) and 0 <= step < len(node):
            mark = node.marks[step] if step < len(node.marks) else mark
            node = node[step]
        else:
            break
    return mark


def key_mark(data: Any, loc: Sequence[Any]) -> Mark:
    """The mark of the key named by the last step of ``loc`` (falls back to its parent)."""
    parent = data
    for step in loc[:-1]:
        try:
            parent = parent[step]
        except (KeyError, IndexError, TypeError):
            return locate(data, loc)
    if isinstance(parent, MarkedDict) and loc and loc[-1] in parent.marks:
        return parent.marks[loc[-1]]
    return locate(data, loc)


def _field(model: type[BaseModel], name: str) -> FieldInfo | None:
    """The field of ``model`` called ``name`` (or with that alias)."""
    fields = model.model_fields
    return fields.get(name) or next((f for f in fields.values() if f.alias == name), None)


def _inner_model(field: FieldInfo) -> type[BaseModel] | None:
    """The model a field holds, also inside ``X | None``, ``list[X]``, ``dict[str, X]``."""
    annotation = field.annotation
    args = getattr(annotation, "__args__", ())
    candidates = [annotation, *args, *(a for x in args for a in getattr(x, "__args__", ()))]
    return next((c for c in candidates if isinstance(c, type) and issubclass(c, BaseModel)), None)


def _model_at(model: type[BaseModel], loc: Sequence[Any]) -> type[BaseModel] | None:
    """The (nested) model that holds the value at ``loc``, for its field names and descriptions."""
    current: type[BaseModel] | None = model
    for step in loc:
        if isinstance(step, int) or current is None:
            continue
        field = _field(current, step)
        current = _inner_model(field) if field is not None else None
        if current is None:
            return None
    return current


def _named_field(model: type[BaseModel], loc: Sequence[Any]) -> Named | None:
    """The last named field along ``loc`` (``points`` for ``points.0``), with its name."""
    found: Named | None = None
    current: type[BaseModel] | None = model
    for step in loc:
        field = _field(current, step) if isinstance(step, str) and current is not None else None
        if field is not None:
            found, current = (step, field), _inner_model(field)
    return found


def range_hint(field: FieldInfo) -> str:
    """'allowed: > 0 and <= 2 m', or the field's description when it has no bounds."""
    bounds = [
        f"{sym} {value:g}" if isinstance(value, (int, float)) else f"{sym} {value}"
        for meta in field.metadata
        for attr, sym in _BOUNDS
        if (value := getattr(meta, attr, None)) is not None
    ]
    unit = unit_of(field)
    return f"allowed: {' and '.join(bounds)}{(' ' + unit) if unit else ''}" if bounds else (field.description or "")


def default_hint(err: ErrorDetails, named: Named | None) -> str:
    """The hint of an error: the validator's own, the allowed range, else what the field is for."""
    ctx = err.get("ctx") or {}
    if "hint" in ctx:
        return str(ctx["hint"])
    bounds = [f"{sym} {ctx[attr]}" for attr, sym in _BOUNDS if attr in ctx]
    if named is None:
        return f"allowed: {' and '.join(bounds)}" if bounds else ""
    name, field = named
    if err["type"] == "missing":
        return (field.description or "") if err["loc"] and name == err["loc"][-1] else ""
    if bounds:
        return range_hint(field)
    return f"{name}: {field.description}" if field.description else ""


@dataclass(frozen=True, slots=True)
class _Source:
    """What was validated and how its problems are told."""

    data: Any
    filename: str
    model: type[BaseModel]
    prefix: str
    at: Mark | None
    wording: Wording
    hint: HintRule | None

    def place(self, loc: Sequence[Any], of_key: bool = False) -> Mark:
        """Where the value (or key) at ``loc`` is written; ``at`` where the data has no mark for it."""
        held = isinstance(self.data, (MarkedDict, MarkedList)) and bool(loc) and _holds(self.data, loc[0])
        if self.at is not None and not held:
            return self.at
        return key_mark(self.data, loc) if of_key else locate(self.data, loc)

    def problem(self, err: ErrorDetails) -> Problem:
        """One error as a problem at its place, with its path and hint."""
        loc = [step for step in err["loc"] if not (isinstance(step, str) and step.startswith("function-"))]
        dotted = ".".join(str(s) for s in loc)
        path = self.prefix + dotted if dotted else self.prefix.rstrip(".")
        key = str(loc[-1]) if loc else ""
        words = {"key": key, "path": path, "msg": err["msg"].removeprefix("Value error, ")}
        if err["type"] == "extra_forbidden":
            owner = _model_at(self.model, loc[:-1])
            names = [f.alias or n for n, f in owner.model_fields.items()] if owner else []
            hint = did_you_mean(key, names) if names else ""
            template, mark = self.wording.unknown, self.place(loc, of_key=True)
        else:
            hint = (self.hint or default_hint)(err, _named_field(self.model, loc))
            missing = err["type"] == "missing"
            template = self.wording.missing if missing else self.wording.invalid
            mark = self.place(loc[:-1] if missing else loc)
        return Problem(self.wording.say(template, words), self.filename, *mark, path, hint)


def _holds(data: Any, step: Any) -> bool:
    """Whether a mapping has the key ``step`` or a list the index ``step``."""
    if isinstance(data, dict):
        return step in data
    return isinstance(step, int) and 0 <= step < len(data)


def problems_from(
    exc: ValidationError,
    data: Any,
    filename: str,
    model: type[BaseModel],
    prefix: str = "",
    *,
    at: Mark | None = None,
    wording: Wording = Wording(),
    hint: HintRule | None = None,
    skip: Callable[[ErrorDetails], bool] | None = None,
) -> list[Problem]:
    """One :class:`Problem` per pydantic error of validating ``data`` against ``model``, with its
    place in ``filename``, its path (after ``prefix``) and a hint: the one translator of pydantic
    errors into problems. Options for the readers that need them: ``at``, the place of a problem the
    data holds no mark for (a command-line option, an XML element); ``wording``, how the messages
    read; ``hint``, the reader's own hints (default: :func:`default_hint`); ``skip``, errors the
    reader has told otherwise. A union's branch the value is not even the type of is left out when
    another branch says what is wrong inside the value.

    >>> from thymio_bt.robot.noise import NoiseConfig
    >>> try:
    ...     NoiseConfig.model_validate({"wheel": -1})
    ... except ValidationError as exc:
    ...     print(*problems_from(exc, {}, "--set", NoiseConfig, "noise.", at=(0, 0)))
    --set: Input should be greater than or equal to 0 [at noise.wheel] (hint: allowed: >= 0 and <= 0.5)
    """
    found = [err for err in exc.errors(include_url=False) if not (skip and skip(err))]
    source = _Source(data, filename, model, prefix, at, wording, hint)
    return [source.problem(err) for err in found if not _other_branch(err, found, data)]


def _other_branch(err: Any, errors: Sequence[Any], data: Any) -> bool:
    """Whether ``err`` is a union's branch that the value is not even the type of (``str`` for
    ``start: [0.2, 0.1, 90]`` of a ``str | Spawn``) while another branch says what is wrong inside
    the value: then only that one is worth reading."""
    loc = err["loc"]
    if not (loc and isinstance(loc[-1], str) and err["type"].endswith("_type")):
        return False
    parent, step = tuple(loc[:-1]), loc[-1]
    node = data
    for key in parent:
        try:
            node = node[key]
        except (KeyError, IndexError, TypeError):
            return False
    if isinstance(node, dict) and step in node:
        return False  # a real key of the data, not a branch's tag
    return any(
        len(o["loc"]) > len(loc) and tuple(o["loc"][: len(parent)]) == parent and o["loc"][len(parent)] != step
        for o in errors
    )


def validate(model: type[M], data: Any, filename: str, prefix: str = "", context: Any = None) -> M:
    """Validate marked data against a pydantic model, raising :class:`UserError` with places
    (``context``: pydantic's validation context, e.g. how ``$name`` values resolve)."""
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        raise UserError(problems_from(exc, data, filename, model, prefix)) from None
