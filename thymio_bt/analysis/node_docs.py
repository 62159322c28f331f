"""Text documentation of every node, generated from the registry (for ``thymio-bt behaviours``).

Example::

    >>> from thymio_bt.plan.registry import default_registry
    >>> parameter_rows(default_registry()["Wait"])[1]
    ('seconds', 'float', 's', 'required', '>= 0 <= 3600', 'how long to wait')
    >>> print(behaviour_help(default_registry()["Wait"]).splitlines()[0])
    Wait
"""

from __future__ import annotations

import inspect
import math
import typing
from typing import Any

from thymio_bt.behaviours import ControlNode
from thymio_bt.inputs.fields import unit_of, within_sensor_range


def _type_name(annotation: Any) -> str:
    """A parameter's type as the docs show it: ``float``, ``left | right``, ``[float, float]``..."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is typing.Literal:
        return " | ".join(str(a) for a in args)
    if origin is typing.Annotated:
        return _type_name(args[0])
    if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
        return " | ".join(_type_name(a) for a in args if a is not type(None)) + " (optional)"
    if origin is tuple:
        return "[" + ", ".join(_type_name(a) for a in args) + "]"
    return getattr(annotation, "__name__", str(annotation))


def _range(field: Any) -> str:
    """A field's bounds: ``> 0 <= 3600``."""
    parts = []
    for meta in field.metadata:
        for attr, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
            value = getattr(meta, attr, None)
            if value is not None:
                parts.append(f"{sym} {value:.4g}")
    if within_sensor_range(field):
        parts.append("and within the robot's sensor range")
    return " ".join(parts)


def _default(field: Any) -> str:
    """A field's default as the docs show it, or ``required``."""
    if field.is_required():
        return "required"
    value = field.default
    if isinstance(value, float):
        return f"{value:.4g}" if math.isfinite(value) else str(value)
    return "none" if value is None else str(value)


def parameter_rows(cls: Any) -> list[tuple[str, str, str, str, str, str]]:
    """(name, type, unit, default, range, description) for each parameter."""
    rows = []
    for name, field in cls.Params.model_fields.items():
        rows.append(
            (
                name,
                _type_name(field.annotation),
                unit_of(field),
                _default(field),
                _range(field),
                field.description or "",
            )
        )
    return rows


def _summary(cls: Any) -> str:
    """The first line of a node class's docstring."""
    return (inspect.getdoc(cls) or "").splitlines()[0] if cls.__doc__ else ""


def behaviour_list(registry: Any) -> str:
    """Every node of ``registry``: behaviours, then composites and decorators, one line each."""
    width = max(len(n) for n in registry)
    lines = ["Behaviours (thymio-bt behaviours NAME for details):", ""]
    lines += [f"  {name:<{width}}  {_summary(cls)}" for name, cls in registry.behaviours()]
    for category, title in (("composite", "Composites"), ("decorator", "Decorators")):
        lines += ["", f"{title}:"]
        lines += [f"  {name:<{width}}  {_summary(cls)}" for name, cls in registry.control(category)]
    return "\n".join(lines)


def behaviour_help(cls: Any) -> str:
    """A node's documentation: what it does, how it is written, its parameters with units and ranges."""
    doc = inspect.getdoc(cls) or ""
    rows = parameter_rows(cls)
    lines = [f"{cls.yaml_name}", "", doc]
    if issubclass(cls, ControlNode):
        lines += [
            "",
            f"A {cls.category}: "
            + (
                "children: [NODE, ...]"
                if cls.category == "composite"
                else ", ".join(f"{k}: NODE" for k in ("do", *cls.node_keys))
                + (" (or written 'NAME: NODE')" if cls.short_form else "")
            ),
            cls.example,
        ]
    if rows:
        header = ("parameter", "type", "unit", "default", "range", "description")
        widths = [max(len(r[i]) for r in [header, *rows]) for i in range(5)]
        lines += [
            "",
            "Parameters:",
            "  " + "  ".join(h.ljust(w) for h, w in zip(header[:5], widths, strict=True)) + "  " + header[5],
        ]
        for row in rows:
            lines.append("  " + "  ".join(c.ljust(w) for c, w in zip(row[:5], widths, strict=True)) + "  " + row[5])
    if not issubclass(cls, ControlNode):
        lines += [
            "",
            "Values accept units and expressions: 5cm, 0.1 m/s, 90deg, pi/2, $parameter; "
            "bb:KEY reads a value from the blackboard when the behaviour starts.",
        ]
    return "\n".join(lines)
