"""Turn pydantic validation errors into :class:`Problem` s that point at file:line:col.

The data must come from :func:`thymio_bt.inputs.yamlio.load_yaml`, whose dicts and lists carry marks.

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

from collections.abc import Sequence
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.yamlio import Mark, MarkedDict, MarkedList, mark_of

M = TypeVar("M", bound=BaseModel)


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


def _model_at(model: type[BaseModel], loc: Sequence[Any]) -> type[BaseModel] | None:
    """The (nested) model that holds the value at ``loc``, for its field names and descriptions."""
    current: Any = model
    for step in loc:
        if isinstance(step, int) or current is None:
            continue
        field = _field(current, step) if isinstance(current, type) and issubclass(current, BaseModel) else None
        if field is None:
            return None
        annotation = field.annotation
        args = getattr(annotation, "__args__", ())
        candidates = [annotation, *args, *(a for x in args for a in getattr(x, "__args__", ()))]
        current = next((c for c in candidates if isinstance(c, type) and issubclass(c, BaseModel)), None)
    return current if isinstance(current, type) else None


def problems_from(
    exc: ValidationError, data: Any, filename: str, model: type[BaseModel], prefix: str = ""
) -> list[Problem]:
    """One :class:`Problem` per pydantic error, with place, path and hint."""
    problems = []
    errors = exc.errors(include_url=False)
    for err in errors:
        if _other_branch(err, errors, data):
            continue
        loc = [step for step in err["loc"] if not (isinstance(step, str) and step.startswith("function-"))]
        path = prefix + ".".join(str(s) for s in loc)
        kind = err["type"]
        hint = ""
        if kind == "extra_forbidden":
            owner = _model_at(model, loc[:-1])
            names = [f.alias or n for n, f in owner.model_fields.items()] if owner else []
            message = f"unknown key '{loc[-1]}'"
            hint = did_you_mean(str(loc[-1]), names) if names else ""
            line, col = key_mark(data, loc)
        elif kind == "missing":
            message = f"missing required key '{loc[-1]}'"
            owner = _model_at(model, loc[:-1])
            field = _field(owner, str(loc[-1])) if owner else None
            hint = (field.description or "") if field else ""
            line, col = locate(data, loc[:-1])
        else:
            message = err["msg"].removeprefix("Value error, ")
            ctx = err.get("ctx") or {}
            if "hint" in ctx:
                hint = str(ctx["hint"])
            elif "ge" in ctx or "le" in ctx or "gt" in ctx or "lt" in ctx:
                hint = "allowed range: " + ", ".join(f"{k} {v}" for k, v in ctx.items())
            elif kind == "too_short" and loc:  # an empty list: say what it is for
                owner = _model_at(model, loc[:-1])
                field = _field(owner, str(loc[-1])) if owner else None
                hint = f"{loc[-1]}: {field.description}" if field and field.description else ""
            line, col = locate(data, loc)
        problems.append(Problem(message, filename, line, col, path, hint))
    return problems


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
