"""A JSON Schema of mission files, generated from the registry's parameter models.

Editors with yaml-language-server complete and check missions that start with
``# yaml-language-server: $schema=../schema/mission.schema.json``.

Example::

    >>> schema = mission_schema()
    >>> schema["required"], schema["$defs"]["node"]["anyOf"][0]["type"]
    (['maze', 'start', 'tree'], 'string')
    >>> distance = behaviour_schema(default_registry()["MoveUntilWall"])["anyOf"][0]["properties"]["distance"]
    >>> distance["description"], distance["anyOf"][1]           # 5cm or $stop: text is accepted too
    ('stop when the sensor reads this [m]', {'type': 'string'})
"""

from __future__ import annotations

import copy
from typing import Any

from thymio_bt.behaviours import ControlNode
from thymio_bt.inputs.fields import unit_of
from thymio_bt.plan.registry import Registry, default_registry
from thymio_bt.robot.model import ROBOTS
from thymio_bt.robot.noise import NoiseConfig

_VALUE = {
    "anyOf": [{"type": "number"}, {"type": "string"}],
    "description": "a number, optionally with a unit (5cm, 0.1 m/s, 90deg, pi/2) or a $parameter",
}
_REF = {"type": "string", "pattern": r"^(\$[A-Za-z_][A-Za-z0-9_]*|bb:.+)$"}


def _loosen(prop: dict[str, Any]) -> dict[str, Any]:
    """Let a parameter also be written as text: units, expressions, $parameters or bb: references."""
    prop = copy.deepcopy(prop)
    description = prop.pop("description", None)
    title = prop.pop("title", None)
    is_number = prop.get("type") in ("number", "integer") or any(
        p.get("type") in ("number", "integer") for p in prop.get("anyOf", [])
    )
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


def _parameters(model: Any, loosen: Any) -> tuple[dict[str, Any], list[str]]:
    """The JSON Schema properties of a parameter model (each through ``loosen``) and its required keys."""
    schema = model.model_json_schema()
    props = {name: loosen(p) for name, p in schema.get("properties", {}).items()}
    for name, field in model.model_fields.items():
        unit = unit_of(field)
        if unit and name in props:
            props[name]["description"] = f"{props[name].get('description', '')} [{unit}]".strip()
    props["name"] = {"type": "string", "description": "the node's name in the tree"}
    return props, list(schema.get("required", []))


def _summary(cls: Any) -> str:
    """The first line of a node class's docstring."""
    return (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else ""


def behaviour_schema(cls: Any) -> dict[str, Any]:
    """A behaviour's body: its parameters (each also as text: units, $parameters, bb: keys); nothing
    at all when none is required."""
    props, required = _parameters(cls.Params, _loosen)
    body: dict[str, Any] = {"type": "object", "properties": props, "additionalProperties": False}
    if required:
        body["required"] = required
    body["description"] = _summary(cls)
    return {"anyOf": [body, {"type": "null"}]} if not required else body


def _units_only(prop: dict[str, Any]) -> dict[str, Any]:
    """A composite's or decorator's parameter: numbers may carry units, other values are as declared."""
    is_number = prop.get("type") == "number"
    return {"anyOf": [prop, _VALUE], "description": prop.get("description", "")} if is_number else prop


def control_schema(cls: type[ControlNode], node_ref: dict[str, Any]) -> dict[str, Any]:
    """A composite's or decorator's body: its long form, and its short form where it has one."""
    props, required = _parameters(cls.Params, _units_only)
    if cls.category == "composite":
        props["children"] = {"type": "array", "items": node_ref, "minItems": 1}
        long_form = {
            "type": "object",
            "properties": props,
            "required": ["children", *required],
            "additionalProperties": False,
        }
        return {"anyOf": [{"type": "array", "items": node_ref, "minItems": 1}, long_form], "description": _summary(cls)}
    props.update({key: node_ref for key in (*cls.node_keys, "do")})
    long_form = {
        "type": "object",
        "properties": props,
        "additionalProperties": False,
        "required": ["do", *cls.required_nodes, *required],
    }
    if cls.short_form:
        return {"anyOf": [long_form, node_ref], "description": _summary(cls)}
    return {**long_form, "description": _summary(cls)}


#: ``expect:`` (thymio_bt.plan.expect): what counts as success besides the tree's status
_EXPECT = {
    "type": "object",
    "additionalProperties": False,
    "description": "success criteria checked after the run",
    "properties": {
        "goal": {
            "type": "object",
            "additionalProperties": False,
            "required": ["centre"],
            "properties": {
                "centre": {"type": "array", "prefixItems": [_VALUE, _VALUE], "minItems": 2, "maxItems": 2},
                "radius": _VALUE,
            },
        },
        "no_collision": {"type": "boolean"},
        "leaves_maze": {"type": "boolean"},
        "dead_end": {
            "type": "object",
            "additionalProperties": False,
            "required": ["distance"],
            "properties": {"distance": _VALUE, "tolerance": _VALUE, "side": _VALUE},
        },
        "max_time": _VALUE,
        "gaps": {
            "type": "array",
            "items": {
                "type": "object",
                "additionalProperties": False,
                "required": ["after", "distance"],
                "properties": {"after": {"type": "string"}, "distance": _VALUE, "tolerance": _VALUE},
            },
        },
    },
}


def mission_schema(registry: Registry | None = None) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a mission file, with every node of ``registry``."""
    registry = registry or default_registry()
    node_ref = {"$ref": "#/$defs/node"}
    node_props: dict[str, Any] = {
        name: control_schema(cls, node_ref) if issubclass(cls, ControlNode) else behaviour_schema(cls)
        for name, cls in registry.items()
    }
    node = {
        "anyOf": [
            {"type": "string", "description": "a behaviour or subtree without parameters"},
            {
                "type": "object",
                "minProperties": 1,
                "maxProperties": 1,
                "properties": node_props,
                "additionalProperties": {
                    "anyOf": [{"type": "object"}, {"type": "null"}],
                    "description": "a subtree defined under subtrees:, with its parameters",
                },
            },
        ]
    }
    pose = {
        "anyOf": [
            {"type": "string"},
            {"type": "array", "prefixItems": [_VALUE, _VALUE, _VALUE], "minItems": 3, "maxItems": 3},
        ]
    }
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
            "tick_hz": _VALUE,
            "time_limit": _VALUE,
            "seed": {"type": "integer", "minimum": 0},
            "sensor_model": {
                "enum": ["metres", "rays", "raw", "cone"],
                "description": "metres (or rays): the course's ideal rays; raw: a real Thymio's "
                "readings; cone: Enki's three-ray cones; default: the robot's own",
            },
            "robot": {
                "anyOf": [{"enum": list(ROBOTS)}, {"type": "string", "pattern": "\\.ya?ml$"}],
                "description": "the robot model (thymio-bt backends lists them), or a profile file "
                "written by thymio-bt calibrate",
            },
            "backend": {
                "anyOf": [
                    {"type": "string"},
                    {"type": "object", "required": ["name"], "properties": {"name": {"type": "string"}}},
                ],
                "description": "where the mission runs: a backend name, or {name: NAME, OPTION: VALUE}",
            },
            "noise": {"type": "object", "properties": noise["properties"], "additionalProperties": False},
            "expect": _EXPECT,
            "parameters": {"type": "object", "additionalProperties": {"type": ["number", "string", "boolean"]}},
            "include": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]},
            "plugins": {"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]},
            "subtrees": {
                "type": "object",
                "additionalProperties": {
                    "type": "object",
                    "required": ["tree"],
                    "additionalProperties": False,
                    "properties": {
                        "description": {"type": "string"},
                        "parameters": {"type": "object"},
                        "tree": node_ref,
                    },
                },
            },
            "tree": node_ref,
        },
        "$defs": {"node": node},
    }
