"""Missions written in BehaviorTree.CPP v4 XML (as Groot2 edits them), read into the same marked
data as a YAML mission, so the loader's passes check them with the same errors and hints.

The read pass for ``.xml`` files: the ``<BehaviorTree>`` named by ``main_tree_to_execute`` (or the
only one) is the tree, ``<ThymioMission>`` holds the settings (``maze``, ``start``, ``tick_hz``,
``noise.wheel``...), ``<TreeNodesModel>`` is ignored. BT.CPP's built-ins map back to thymio-bt's
composites and decorators (:data:`thymio_bt.mission.btcpp.BUILTIN`), ``{key}`` ports to ``bb:key``.
Elements and their attributes carry the element's line and column. The file is parsed with
expat, with no DTD: entities are refused, so nothing is expanded or fetched.

Example::

    >>> import tempfile
    >>> from thymio_bt.mission.btcpp import mission_xml
    >>> from thymio_bt.mission.loader import load_mission
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     xml = Path(folder) / "bonus.xml"
    ...     _ = xml.write_text(mission_xml(load_mission("maze_bonus"), xml))
    ...     data = read_xml_mission(xml)                # a MarkedDict, as load_yaml reads a mission
    >>> data["start"], data["tree"].subtree_use, data.marks["tree"]
    ('1.3, 0.1, 3.141592653589793', 'to_dead_end', (3, 3))
    >>> sorted(data["tree"]["repeat"])                  # the exported do-while loop is a repeat with until:
    ['do', 'name', 'until']
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from thymio_bt.behaviours.btcpp_control import BTCPP_IDS, CONDITION_ATTRS
from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import read_bytes
from thymio_bt.inputs.xmlparse import parse_xml
from thymio_bt.inputs.yamlio import MarkedDict, MarkedList
from thymio_bt.mission.btcpp import BUILTIN, KIND_ATTR, MISSION_TAG, RESERVED

#: BT.CPP built-in -> the node kind of BT.CPP's semantics (an element without _thymio)
_FROM_BUILTIN = dict(BTCPP_IDS)
#: BT.CPP nodes that thymio-bt cannot run, with what to use instead
_UNSUPPORTED: dict[str, str] = {}


@dataclass
class _Element:
    tag: str
    attrs: dict[str, str]
    line: int
    column: int
    children: list[_Element] = field(default_factory=list)


def _parse(path: Path) -> _Element:
    """The element tree of the XML file, with places, under :func:`~thymio_bt.inputs.xmlparse.parse_xml`'s
    guards (no DTD, no entities, bounded depth)."""
    file = str(path)
    stack: list[_Element] = []
    roots: list[_Element] = []

    def start(tag: str, attrs: dict[str, str], line: int, column: int) -> None:
        element = _Element(tag, attrs, line, column)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    parse_xml(
        read_bytes(path, "mission"),
        file,
        "mission",
        start,
        lambda tag: stack.pop(),
        hint="check that every <Node ...> is closed (<Node/> or </Node>)",
    )
    if not roots or roots[0].tag != "root":
        raise UserError(
            Problem(
                'a BT.CPP XML mission starts with <root BTCPP_format="4">',
                file,
                1,
                1,
                hint="export one with: thymio-bt tree MISSION.yaml --btcpp OUT.xml",
            )
        )
    return roots[0]


def _value(text: str) -> Any:
    """A port's text as the YAML scalar it stands for: numbers, true/false, JSON lists, {key}."""
    stripped = text.strip()
    if stripped in ("true", "false"):
        return stripped == "true"
    if stripped.startswith("{") and stripped.endswith("}") and stripped[1:-1].strip():
        return "bb:" + stripped[1:-1].strip()
    if stripped.startswith("["):
        try:
            return json.loads(stripped)
        except ValueError:
            return text
    for convert in (int, float):
        try:
            return convert(stripped)
        except ValueError:
            pass
    return text


def _marked(mapping: dict[str, Any], element: _Element) -> MarkedDict:
    """``mapping`` as a :class:`MarkedDict` whose keys and values all carry ``element``'s place."""
    out = MarkedDict(mapping)
    out.mark = (element.line, element.column)
    for key in mapping:
        out.marks[key] = out.value_marks[key] = (element.line, element.column)
    return out


def _node(element: _Element, file: str, trees: dict[str, _Element], stack: tuple[str, ...] = ()) -> MarkedDict:
    """One element as a ``{Type: body}`` node of the YAML form; a ``<SubTree ID=...>`` is replaced by
    the root of that ``<BehaviorTree>`` (named as the SubTree, when it is)."""
    ident = element.tag
    marked = element.attrs.get(KIND_ATTR, "")
    if BUILTIN.get(marked) != ident and not (marked == "repeat" and ident == "Sequence"):
        marked = ""  # the mark of thymio-bt's node applies to the element the export writes for it only
    if ident in _UNSUPPORTED and not marked:
        raise UserError(
            Problem(
                f"BT.CPP node <{ident}> is not supported", file, element.line, element.column, hint=_UNSUPPORTED[ident]
            )
        )
    if ident == "SubTree":
        return _subtree(element, file, trees, stack)
    attrs = {k: v for k, v in element.attrs.items() if not k.startswith("_")}
    if marked == "repeat" and ident == "Sequence":
        element = _repeat_until(element, file)
        ident = "RepeatUntil"
    children = [_node(child, file, trees, stack) for child in element.children]
    if ident == "RepeatUntil":
        kind = "repeat"
    elif marked:
        kind = marked
    else:
        unprefixed = ident[len("Thymio") :]
        thymio_style = ident == "SetBlackboard" and "output_key" not in attrs  # thymio-bt's (key, value)
        kind = (
            "SetBlackboard"
            if thymio_style
            else _FROM_BUILTIN.get(
                ident, unprefixed if ident.startswith("Thymio") and unprefixed in RESERVED else ident
            )
        )
    body: dict[str, Any] = {"name": attrs.pop("name")} if "name" in attrs else {}
    body.update(_body(ident, kind, attrs, children, element, file))
    return _with_conditions(_marked({kind: _marked(body, element)}, element), element)


def _body(
    ident: str, kind: str, attrs: dict[str, str], children: list[MarkedDict], element: _Element, file: str
) -> dict[str, Any]:
    """A node's body but its name, from its ports (``attrs``) and its child nodes: a composite's
    ``children``, a decorator's ``do`` (and ``condition``, ``until``), a behaviour's parameters."""
    if ident == "RepeatUntil":
        if len(children) != 2:
            raise UserError(
                Problem(
                    "RepeatUntil takes two children: the body, then the condition", file, element.line, element.column
                )
            )
        return {"do": children[0], "until": children[1]}
    if kind == "parallel":
        policy = "success_on_one" if attrs.pop("success_count", "-1").strip() == "1" else "success_on_all"
        attrs.pop("failure_count", None)
        return {"policy": policy, **{k: _value(v) for k, v in attrs.items()}, "children": _list(children, element)}
    if kind in ("sequence", "reactive_sequence", "selector", "reactive_selector"):
        return {**{k: _value(v) for k, v in attrs.items()}, "children": _list(children, element)}
    if kind.startswith("bt_"):  # BT.CPP's own node: its ports as written (the node's model reads them)
        category = _category(ident)
        if category == "leaf":
            return dict(attrs)
        nodes = {"do": children[0]} if category == "decorator" and children else {"children": _list(children, element)}
        return {**attrs, **nodes}
    if not children:  # a behaviour or condition
        return {k: _value(v) for k, v in attrs.items()}
    renamed = {"num_cycles": "times", "num_attempts": "times"}  # a decorator
    body = {renamed.get(k, k): _value(v) for k, v in attrs.items()}
    if body.get("times") == -1:
        body["times"] = "forever"
    extra = {"guard": "condition"}.get(kind)
    body["do"] = children[0]
    if extra and len(children) > 1:
        body[extra] = children[1]
    return body


def _category(ident: str) -> str:
    """What BT.CPP's node ``ident`` is here: "decorator" (one child, under ``do``), "composite"
    (``children``) or "leaf" (ports only)."""
    from thymio_bt.behaviours.btcpp_control import BTCPP_CONTROL, BTCPP_SCRIPTED

    for cls in (*BTCPP_CONTROL, *BTCPP_SCRIPTED):
        if cls.btcpp_id == ident:  # type: ignore[attr-defined]
            return cls.category
    return "leaf"


def _with_conditions(node: MarkedDict, element: _Element) -> MarkedDict:
    """``node`` under a ``bt_conditions`` node when its element has BT.CPP's pre/post-condition
    attributes (``_skipIf``, ``_while``, ``_onSuccess``...), else ``node``."""
    scripts = {CONDITION_ATTRS[k]: v for k, v in element.attrs.items() if k in CONDITION_ATTRS}
    if not scripts:
        return node
    body = next(iter(node.values()))
    name = body.get("name", element.tag) if isinstance(body, dict) else element.tag
    return _marked({"bt_conditions": _marked({"name": name, **scripts, "do": node}, element)}, element)


def _repeat_until(element: _Element, file: str) -> _Element:
    """The do-while loop an export writes (:func:`~thymio_bt.mission.btcpp.repeat_until_elements`)
    as one ``RepeatUntil`` element of two children: the body, then the condition."""
    try:
        script, fallback = element.children
        keep, check = fallback.children
        (sequence,) = keep.children
        body, inverter = sequence.children
        (condition,) = inverter.children
        tags = [script.tag, fallback.tag, keep.tag, check.tag, sequence.tag, inverter.tag]
        if tags != ["Script", "Fallback", "KeepRunningUntilFailure", "ScriptCondition", "Sequence", "Inverter"]:
            raise ValueError(tags)
    except ValueError:
        raise UserError(
            Problem(
                f'<Sequence {KIND_ATTR}="repeat"> is not the do-while loop thymio-bt exports',
                file,
                element.line,
                element.column,
                hint=f"export the loop again (thymio-bt tree MISSION.yaml --btcpp OUT.xml), or remove {KIND_ATTR}",
            )
        ) from None
    return _Element("RepeatUntil", element.attrs, element.line, element.column, [body, condition])


def _subtree(element: _Element, file: str, trees: dict[str, _Element], stack: tuple[str, ...]) -> MarkedDict:
    """A ``<SubTree ID=...>``: the root of that ``<BehaviorTree>``, marked as its use."""
    ident = element.attrs.get("ID", "")
    ports = sorted(k for k in element.attrs if k not in ("ID", "name") and not k.startswith("_"))
    if ports:
        raise UserError(
            Problem(
                f'<SubTree ID="{ident}"> with ports ({", ".join(ports)}) is not supported',
                file,
                element.line,
                element.column,
                hint="write the values in the subtree's nodes (one <BehaviorTree> per use)",
            )
        )
    if ident not in trees:
        raise UserError(
            Problem(
                f'<SubTree> names no <BehaviorTree ID="{ident}">',
                file,
                element.line,
                element.column,
                hint=f"the file's trees: {', '.join(sorted(trees)) or 'none'}",
            )
        )
    if ident in stack:
        raise UserError(
            Problem(
                f"subtree '{ident}' uses itself ({' -> '.join([*stack, ident])})",
                file,
                element.line,
                element.column,
                hint="a subtree may not contain itself",
            )
        )
    tree = trees[ident]
    if len(tree.children) != 1:
        raise UserError(Problem("a <BehaviorTree> holds exactly one root node", file, tree.line, tree.column))
    node = _node(tree.children[0], file, trees, (*stack, ident))
    node.subtree_use = ident  # the plan remembers it: the report's phases, the export's <SubTree>
    if "name" in element.attrs:
        body = next(iter(node.values()))
        if isinstance(body, MarkedDict):
            body["name"] = element.attrs["name"]
    return node


def _list(items: list[MarkedDict], element: _Element) -> MarkedList:
    """``items`` as a :class:`MarkedList` at ``element``'s place."""
    out = MarkedList(items)
    out.mark = (element.line, element.column)
    out.marks = [item.mark for item in items]
    return out


def read_xml_mission(path: Path) -> MarkedDict:
    """The mission in a BT.CPP v4 XML file, as the marked mapping a YAML mission file reads as."""
    file = str(path)
    root = _parse(path)
    if root.attrs.get("BTCPP_format", "4") != "4":
        raise UserError(
            Problem(
                f"BTCPP_format {root.attrs['BTCPP_format']} is not supported",
                file,
                root.line,
                root.column,
                hint="Groot2 and BehaviorTree.CPP 4 write format 4",
            )
        )
    trees = [e for e in root.children if e.tag == "BehaviorTree"]
    tree = _main_tree(root, trees, file)
    settings, element = _settings(root, file)
    if "noise" in settings:
        settings["noise"] = _marked(settings["noise"], element or tree)
    by_id = {t.attrs.get("ID", ""): t for t in trees}
    node = _node(tree.children[0], file, by_id, (tree.attrs.get("ID", ""),))
    data = _marked({**settings, "tree": node}, element or tree)
    data.marks["tree"] = data.value_marks["tree"] = (tree.line, tree.column)
    return data


def _main_tree(root: _Element, trees: list[_Element], file: str) -> _Element:
    """The ``<BehaviorTree>`` that is the mission: the one ``main_tree_to_execute`` names, or the only one."""
    main = root.attrs.get("main_tree_to_execute")
    chosen = [t for t in trees if t.attrs.get("ID") == main] if main else trees
    if len(chosen) != 1:
        raise UserError(
            Problem(
                "cannot tell which <BehaviorTree> is the mission" if chosen else "no <BehaviorTree> to run",
                file,
                root.line,
                root.column,
                hint="one <BehaviorTree ID=...>, or main_tree_to_execute naming one",
            )
        )
    tree = chosen[0]
    if len(tree.children) != 1:
        raise UserError(Problem("a <BehaviorTree> holds exactly one root node", file, tree.line, tree.column))
    return tree


def _settings(root: _Element, file: str) -> tuple[dict[str, Any], _Element | None]:
    """The mission's settings from its ``<ThymioMission>`` attributes (``noise.X`` gathered into
    ``noise``), and the last such element (None without one): where the settings are written."""
    settings: dict[str, Any] = {}
    element = None
    for mission in (e for e in root.children if e.tag == MISSION_TAG):
        element = mission
        for key, text in mission.attrs.items():
            if key.startswith("noise."):
                settings.setdefault("noise", {})[key[len("noise.") :]] = _value(text)
            elif text.strip()[:1] == {"plugins": "[", "backend": "{", "expect": "{"}.get(key):
                settings[key] = _json_setting(key, text, file, mission)
            elif key in ("name", "description", "maze", "start", "sensor_model", "robot"):
                settings[key] = text
            else:
                settings[key] = _value(text)
    return settings, element


def _json_setting(key: str, text: str, file: str, mission: _Element) -> Any:
    """A ``<ThymioMission>`` attribute written as JSON (``backend``, ``expect``, ``plugins``)."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        example = '["my_nodes.py"]' if key == "plugins" else '{"name": "sim"}'
        raise UserError(
            Problem(
                f"{key}: invalid JSON: {exc.msg}",
                file,
                mission.line,
                mission.column,
                hint=f"write {key} as JSON, e.g. {key}='{example}'",
            )
        ) from None
