"""Missions written in BehaviorTree.CPP v4 XML (as Groot2 edits them), read into the same marked
data as a YAML mission, so the loader's passes check them with the same errors and hints.

The read pass for ``.xml`` files: the ``<BehaviorTree>`` named by ``main_tree_to_execute`` (or the
only one) is the tree, ``<ThymioMission>`` holds the settings (``maze``, ``start``, ``tick_hz``,
``noise.wheel``...), ``<TreeNodesModel>`` gives only the defaults of subtrees' ports. BT.CPP's
built-ins map back to thymio-bt's composites and decorators (each marked element by its kind's
``btcpp_id``, :class:`~thymio_bt.behaviours.flow.node.ControlNode`),
``{key}`` ports to ``bb:key``; each ``<SubTree>`` is a copy of its tree with a blackboard scope of its
own, as in BT.CPP (:mod:`thymio_bt.btcpp.xml_tree`, :mod:`thymio_bt.btcpp.xml_scope`). Elements
and their attributes carry the element's line and column. The file is parsed with expat, with no
DTD: entities are refused, so nothing is expanded or fetched.

Example::

    >>> import tempfile
    >>> from thymio_bt.btcpp.export import mission_xml
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
from pathlib import Path
from typing import Any

from thymio_bt.btcpp.export import MISSION_TAG
from thymio_bt.btcpp.xml_tree import Element, TreeReader, check_json, element_roots, marked, port_value
from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import read_bytes
from thymio_bt.inputs.yamlio import MarkedDict


def _parse(path: Path) -> Element:
    """The element tree of the XML file, with places, under :func:`~thymio_bt.inputs.xmlparse.parse_xml`'s
    guards (no DTD, no entities, bounded depth)."""
    file = str(path)
    hint = "check that every <Node ...> is closed (<Node/> or </Node>)"
    roots = element_roots(read_bytes(path, "mission"), file, "mission", hint)
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
        settings["noise"] = marked(settings["noise"], element or tree)
    by_id = {t.attrs.get("ID", ""): t for t in trees}
    node = TreeReader(file, by_id, _subtree_models(root, file)).tree(tree)
    data = marked({**settings, "tree": node}, element or tree)
    data.marks["tree"] = data.value_marks["tree"] = (tree.line, tree.column)
    return data


def _main_tree(root: Element, trees: list[Element], file: str) -> Element:
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


def _settings(root: Element, file: str) -> tuple[dict[str, Any], Element | None]:
    """The mission's settings from its ``<ThymioMission>`` attributes (``noise.X`` gathered into
    ``noise``), and the last such element (None without one): where the settings are written."""
    settings: dict[str, Any] = {}
    element = None
    for mission in (e for e in root.children if e.tag == MISSION_TAG):
        element = mission
        for key, text in mission.attrs.items():
            if key.startswith("noise."):
                settings.setdefault("noise", {})[key[len("noise.") :]] = port_value(
                    text, file, mission.line, mission.column
                )
            elif text.strip()[:1] == {"plugins": "[", "backend": "{", "expect": "{"}.get(key):
                settings[key] = _json_setting(key, text, file, mission)
            elif key in ("name", "description", "maze", "start", "sensor_model", "robot"):
                settings[key] = text
            else:
                settings[key] = port_value(text, file, mission.line, mission.column)
    return settings, element


def _json_setting(key: str, text: str, file: str, mission: Element) -> Any:
    """A ``<ThymioMission>`` attribute written as JSON (``backend``, ``expect``, ``plugins``)."""
    check_json(text, file, mission.line, mission.column)
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


def _subtree_models(root: Element, file: str) -> dict[str, dict[str, tuple[str | None, Any]]]:
    """The ports of each ``<SubTree ID=...>`` of the ``<TreeNodesModel>`` (port -> (its default or
    None, where it is written)): a ``<SubTree>`` that does not set a port gets its default."""
    models: dict[str, dict[str, tuple[str | None, Any]]] = {}
    for model in (e for e in root.children if e.tag == "TreeNodesModel"):
        for entry in (e for e in model.children if e.tag == "SubTree"):
            ports = models.setdefault(entry.attrs.get("ID", ""), {})
            for port in (p for p in entry.children if p.tag in ("input_port", "output_port", "inout_port")):
                if "name" not in port.attrs:
                    raise UserError(Problem("a port of a <SubTree> model has no name", file, port.line, port.column))
                ports[port.attrs["name"]] = (port.attrs.get("default"), (file, port.line, port.column))
    return models
