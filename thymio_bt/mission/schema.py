"""A JSON Schema of mission files, generated from the registry's parameter models.

Editors with yaml-language-server complete and check missions that start with
``# yaml-language-server: $schema=../schema/mission.schema.json``.
"""

from __future__ import annotations

import copy
from typing import Any

from ..sim.noise import NoiseConfig
from .loader import COMPOSITES, DECORATOR_KEYS
from .registry import Registry, default_registry

_VALUE = {"anyOf": [{"type": "number"}, {"type": "string"}],
          "description": "a number, optionally with a unit (5cm, 0.1 m/s, 90deg, pi/2) or a $parameter"}
_REF = {"type": "string", "pattern": r"^(\$[A-Za-z_][A-Za-z0-9_]*|bb:.+)$"}


def _loosen(prop: dict[str, Any]) -> dict[str, Any]:
    """Let a parameter also be written as text: units, expressions, $parameters or bb: references."""
    prop = copy.deepcopy(prop)
    description = prop.pop("description", None)
    title = prop.pop("title", None)
    is_number = prop.get("type") in ("number", "integer") or any(
        p.get("type") in ("number", "integer") for p in prop.get("anyOf", []))
    alternatives = [prop, {"type": "string"} if is_number else _REF]
    if prop.get("type") == "array" or any(p.get("type") == "array" for p in prop.get("anyOf", [])):
        alternatives.append({"type": "string"})
        for item in prop.get("prefixItems", []):
            item.clear()
            item.update(_VALUE)
    out: dict[str, Any] = {"anyOf": alternatives}
    if description:
        out["description"] = description
    elif title:
        out["title"] = title
    return out


def behaviour_schema(cls: Any) -> dict[str, Any]:
    model = cls.Params.model_json_schema()
    props = {name: _loosen(p) for name, p in model.get("properties", {}).items()}
    for name, field in cls.Params.model_fields.items():
        unit = (field.json_schema_extra or {}).get("unit") if isinstance(field.json_schema_extra, dict) else None
        if unit and name in props:
            props[name]["description"] = f"{props[name].get('description', '')} [{unit}]".strip()
    props["name"] = {"type": "string", "description": "the node's name in the tree"}
    body: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    required = [r for r in model.get("required", [])]
    if required:
        body["required"] = required
    body["description"] = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else ""
    return {"anyOf": [body, {"type": "null"}]} if not required else body


def mission_schema(registry: Registry | None = None) -> dict[str, Any]:
    registry = registry or default_registry()
    node_ref = {"$ref": "#/$defs/node"}
    node_props: dict[str, Any] = {}
    for name, cls in registry.items():
        node_props[name] = behaviour_schema(cls)
    composite_body = {"anyOf": [
        {"type": "array", "items": node_ref, "minItems": 1},
        {"type": "object", "properties": {"name": {"type": "string"},
                                          "children": {"type": "array", "items": node_ref, "minItems": 1},
                                          "policy": {"enum": ["success_on_all", "success_on_one"]},
                                          "synchronise": {"type": "boolean"}},
         "required": ["children"], "additionalProperties": False}]}
    for name in COMPOSITES:
        node_props[name] = composite_body
    for name, keys in DECORATOR_KEYS.items():
        props: dict[str, Any] = {"name": {"type": "string"}, "do": node_ref}
        if "times" in keys:
            props["times"] = {"anyOf": [{"type": "integer", "minimum": 1}, {"const": "forever"}]}
        if "until" in keys:
            props["until"] = node_ref
        if "seconds" in keys:
            props["seconds"] = _VALUE
        if "status" in keys:
            props["status"] = {"enum": ["success", "failure"]}
        if "condition" in keys:
            props["condition"] = node_ref
        if "on" in keys:
            props["on"] = {"enum": ["success", "completion"]}
        long_form = {"type": "object", "properties": props, "required": ["do"], "additionalProperties": False}
        node_props[name] = long_form if keys != ("do",) and name != "one_shot" else {"anyOf": [long_form, node_ref]}
    node = {
        "anyOf": [
            {"type": "string", "description": "a behaviour or subtree without parameters"},
            {"type": "object", "minProperties": 1, "maxProperties": 1, "properties": node_props,
             "additionalProperties": {"anyOf": [{"type": "object"}, {"type": "null"}],
                                      "description": "a subtree defined under subtrees:, with its parameters"}},
        ]}
    pose = {"anyOf": [{"type": "string"}, {"type": "array", "prefixItems": [_VALUE, _VALUE, _VALUE],
                                           "minItems": 3, "maxItems": 3}]}
    noise = NoiseConfig.model_json_schema()
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://thymio-bt.invalid/mission.schema.json",
        "title": "thymio-bt mission",
        "type": "object",
        "additionalProperties": False,
        "required": ["maze", "start", "tree"],
        "properties": {
            "name": {"type": "string"},
            "description": {"type": "string"},
            "maze": {"type": "string", "description": "a maze name (mazes/) or a path relative to this file"},
            "start": {**pose, "description": "a named spawn of the maze or [x, y, yaw]"},
            "tick_hz": _VALUE, "time_limit": _VALUE,
            "seed": {"type": "integer", "minimum": 0},
            "sensor_model": {"enum": ["metres", "raw"],
                             "description": "metres: the course's ideal rays; raw: a real Thymio's readings"},
            "noise": {"type": "object", "properties": noise["properties"], "additionalProperties": False},
            "parameters": {"type": "object", "additionalProperties": {"type": ["number", "string", "boolean"]}},
            "include": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]},
            "plugins": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]},
            "subtrees": {"type": "object", "additionalProperties": {
                "type": "object", "required": ["tree"], "additionalProperties": False,
                "properties": {"description": {"type": "string"},
                               "parameters": {"type": "object"}, "tree": node_ref}}},
            "tree": node_ref,
        },
        "$defs": {"node": node},
    }
