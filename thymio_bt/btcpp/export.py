"""A mission tree as BehaviorTree.CPP v4 XML: what Groot2 opens, and what a Groot2 log embeds.

Composites and decorators become BT.CPP's built-ins (``sequence`` is ``Sequence``, ``selector`` is
``Fallback``, ``invert`` is ``Inverter``, ...), each marked ``_thymio="KIND"`` (BT.CPP ignores
attributes that start with ``_``) so that reading the file back gives thymio-bt's node, tick for tick;
a ``repeat`` with ``until`` (a do-while loop, which BT.CPP has no node for) is written with BT.CPP's
built-ins and two scripts (:func:`repeat_until_elements`). Nothing needs a custom control node: the
file loads in BT.CPP 4 with only the leaves registered. Behaviours are Actions, conditions
Conditions, with their parameters as ports; a ``<TreeNodesModel>`` declares every non-built-in node
(plugins' too) with its ports, units and descriptions from the node registry, so Groot2 can show and
edit the tree. Every element carries the ``_uid`` BT.CPP gives it (its pre-order number, 1 = the
root, a subtree's nodes counted after its ``<SubTree>``, a do-while loop's scaffolding counted too),
so a Groot2 log or monitor of ours names the nodes BT.CPP would.

Example::

    >>> from thymio_bt.mission.loader import load_mission
    >>> mission = load_mission("maze_bonus")
    >>> nodes, params, subtrees = mission_nodes(mission)
    >>> subtrees                                  # the tree is one use of the subtree to_dead_end
    {1: 'to_dead_end'}
    >>> node_id(nodes[0], children=2), node_id(nodes[1], children=2), params[4]["distance"]
    ('Sequence', 'Sequence', 0.05)
    >>> tree = btcpp_tree(nodes, mission.registry, params, subtrees=subtrees)
    >>> for line in tree.xml.splitlines()[1:4]:
    ...     print(line)
      <BehaviorTree ID="MainTree">
        <SubTree ID="to_dead_end" name="bonus maze" _autoremap="true" _uid="1" />
      </BehaviorTree>
    >>> tree.wrappers, tree.uids[1], tree.uids[2]  # the loop, then 4 scaffolding nodes before its body
    ({1: 1}, 2, 7)
"""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from thymio_bt.behaviours import ControlNode
from thymio_bt.behaviours.base import RobotBehaviour, UnrunPlugin
from thymio_bt.btcpp.runtime.control import BTCPP_IDS, CONDITION_ATTRS
from thymio_bt.inputs.fields import unit_of
from thymio_bt.logs.entries import TreeNode
from thymio_bt.maze.files import maze_reference
from thymio_bt.plan.model import Mission, NodePlan
from thymio_bt.plan.registry import Registry, control_kind, default_registry

#: the attribute that marks an exported element as thymio-bt's node kind (BT.CPP skips ``_`` attributes)
KIND_ATTR = "_thymio"
#: the element that carries a mission's settings (maze, start, rates, noise); BT.CPP skips it
MISSION_TAG = "ThymioMission"
#: BT.CPP's own node IDs (every one thymio-bt runs as a ``bt_*`` kind, and SubTree): a thymio-bt
#: node of one of these names is exported as Thymio<name> so that it does not clash with the built-in
RESERVED = frozenset({*BTCPP_IDS, "SubTree"})
#: a bt_* node kind -> its BT.CPP ID
_BT_ID = {kind: ident for ident, kind in BTCPP_IDS.items()}


def _do_while(cls: type[ControlNode] | None, children: int) -> bool:
    """Whether a node of kind ``cls`` with that many children is a loop with a condition after its
    body (``repeat`` with ``until``), which an export writes as :func:`repeat_until_elements`."""
    return cls is not None and bool(cls.then) and children == 2


def node_id(node: TreeNode, children: int, registry: Registry | None = None) -> str:
    """The BT.CPP node ID of a logged node (its kind's ``btcpp_id`` for a composite or decorator)."""
    kind = node["kind"]
    if kind in _BT_ID:
        return _BT_ID[kind]
    cls = control_kind(kind, registry)
    if _do_while(cls, children):
        return "Sequence"  # the outer element of a do-while loop (repeat_until_elements)
    if kind in RESERVED:
        return "Thymio" + kind
    return (cls.btcpp_id if cls is not None else "") or kind


def _port_value(value: Any) -> str:
    """A parameter as a port's text: exact (``repr``) numbers, lists as JSON, so a read back is exact."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return json.dumps(value)
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _ports(kind: str, cls: type[ControlNode] | None, params: Mapping[str, Any], children: int) -> dict[str, str]:
    """A node's parameters as the ports of its BT.CPP element (a composite's or decorator's as its
    kind says, :meth:`~thymio_bt.behaviours.flow.node.ControlNode.to_btcpp`)."""
    if _do_while(cls, children):
        return {}  # a do-while loop: it ends by its condition, not a count
    if kind in _BT_ID:  # BT.CPP's own node: its ports, without the time limit every behaviour has
        return {k: _port_value(v) for k, v in params.items() if v is not None and k != "timeout"}
    given = {k: v for k, v in params.items() if v is not None}
    return {k: _port_value(v) for k, v in (cls.to_btcpp(given) if cls is not None else given).items()}


def repeat_until_elements(parent: ET.Element, attrs: dict[str, str]) -> tuple[ET.Element, ET.Element]:
    """``repeat: {until: COND, do: BODY}`` in BT.CPP's built-ins, under ``parent``; returns the loop's
    element and the one BODY and COND go into (COND under an ``Inverter``). The loop's flag is the
    blackboard entry ``__until_UID``, UID the loop's ``_uid`` (set by :func:`_name_flag`)::

        <Sequence _thymio="repeat">                       the loop (name, _uid)
          <Script code="__until_7 := false"/>
          <Fallback>
            <KeepRunningUntilFailure>                      RUNNING after each failed check: again next tick
              <Sequence> BODY <Inverter _onFailure="__until_7 := true"> COND </Inverter> </Sequence>
            </KeepRunningUntilFailure>
            <ScriptCondition code="__until_7"/>           SUCCESS if COND ended it, FAILURE if BODY did
          </Fallback>
        </Sequence>

    Tick for tick in BT.CPP as thymio-bt's loop: BODY, COND in the same tick after each success of
    BODY, BODY again the next tick after a failed check, a BODY failure fails the loop."""
    loop = ET.SubElement(parent, "Sequence", attrs)
    ET.SubElement(loop, "Script", code="")
    fallback = ET.SubElement(loop, "Fallback")
    keep = ET.SubElement(fallback, "KeepRunningUntilFailure")
    body = ET.SubElement(keep, "Sequence")
    ET.SubElement(fallback, "ScriptCondition", code="")
    return loop, body


def _name_flag(loop: ET.Element, uid: int) -> None:
    """Write the flag ``__until_UID`` into the scripts of a loop of :func:`repeat_until_elements`."""
    flag = f"__until_{uid}"
    script, fallback = loop
    script.set("code", f"{flag} := false")
    fallback[1].set("code", flag)
    fallback[0][0][1].set("_onFailure", f"{flag} := true")


@dataclass(frozen=True)
class BtcppTree:
    """A tree as BT.CPP XML, and the ``_uid`` BT.CPP gives each planned node's element."""

    #: the XML text
    xml: str
    #: a planned node's uid -> its element's ``_uid`` (every node but a ``bt_conditions``, whose
    #: conditions are attributes of the node under it)
    uids: dict[int, int]
    #: a subtree instance root's uid -> the ``_uid`` of the ``<SubTree>`` node that uses it
    wrappers: dict[int, int]
    #: how many nodes BT.CPP counts (their ``_uid``s are 1 to ``size``)
    size: int


def btcpp_tree(
    nodes: list[TreeNode],
    registry: Registry,
    params: Mapping[int, Mapping[str, Any]] | None = None,
    tree_id: str = "MainTree",
    settings: Mapping[str, str] | None = None,
    subtrees: Mapping[int, str] | None = None,
) -> BtcppTree:
    """BT.CPP v4 XML of a tree given in pre-order (as :func:`~thymio_bt.logs.entries.tree_nodes`
    lists it), with each node's parameters (by uid) as ports and a complete TreeNodesModel.
    ``subtrees`` maps the uid of a subtree instance's root to a BehaviorTree ID: that part of the
    tree becomes its own ``<BehaviorTree>``, used through a ``<SubTree>`` node."""
    root = ET.Element("root", BTCPP_format="4", main_tree_to_execute=tree_id)
    if settings:
        ET.SubElement(root, MISSION_TAG, dict(settings))
    writer = _TreeWriter(root, ET.SubElement(root, "BehaviorTree", ID=tree_id), registry, params or {}, subtrees or {})
    for n in nodes:
        writer.children[n["uid"]] = 0
        if n["parent"] is not None:
            writer.children[n["parent"]] += 1
    for n in nodes:
        writer.add(n)
    number = {element: i for i, element in enumerate(_btcpp_order(root, tree_id), 1)}
    uids = {uid: number[element] for uid, element in writer.own.items()}
    for uid in writer.loops:
        _name_flag(writer.own[uid], uids[uid])
    for element, i in number.items():
        element.set("_uid", str(i))
    _model(ET.SubElement(root, "TreeNodesModel"), writer.used, registry)
    ET.indent(root)
    wrappers = {uid: number[element] for uid, element in writer.uses.items()}
    return BtcppTree(ET.tostring(root, encoding="unicode") + "\n", uids, wrappers, len(number))


class _TreeWriter:
    """The elements of a tree being written, node by node in pre-order, under ``root``'s main tree ``tree``."""

    def __init__(
        self,
        root: ET.Element,
        tree: ET.Element,
        registry: Registry,
        params: Mapping[int, Mapping[str, Any]],
        subtrees: Mapping[int, str],
    ) -> None:
        self.root, self.tree, self.registry, self.params, self.subtrees = root, tree, registry, params, subtrees
        #: a node's uid -> how many children it has
        self.children: dict[int, int] = {}
        #: a node's uid -> the element its children go into
        self.elements: dict[int, ET.Element] = {}
        #: a node's uid -> its element (a do-while loop's outer one)
        self.own: dict[int, ET.Element] = {}
        #: a subtree instance root's uid -> its <SubTree> element
        self.uses: dict[int, ET.Element] = {}
        #: the do-while loops' uids (their body and condition go in elements[uid])
        self.loops: set[int] = set()
        #: each node ID used -> a node kind of it and the ports given to it
        self.used: dict[str, tuple[str, set[str]]] = {}
        #: a bt_conditions node's uid -> the attributes of its child
        self.conditions: dict[int, dict[str, str]] = {}

    def add(self, n: TreeNode) -> None:
        """Write node ``n`` (its parent is written already)."""
        uid, kind = n["uid"], n["kind"]
        parent = self._parent(n)
        if kind == "bt_conditions":  # BT.CPP's _skipIf=... attributes, on the node under it
            names = {name: attr for attr, name in CONDITION_ATTRS.items()}
            given = self.params.get(uid, {}).items()
            self.conditions[uid] = {names[k]: str(v) for k, v in given if v is not None}
            self.elements[uid] = parent
            return
        cls = control_kind(kind, self.registry)
        ident = node_id(n, self.children[uid], self.registry)
        ports = _ports(kind, cls, self.params.get(uid, {}), self.children[uid])
        self.used.setdefault(ident, (kind, set()))[1].update(ports)
        marked = {KIND_ATTR: kind} if cls is not None and not cls.btcpp_native else {}
        scripts = self.conditions.get(n["parent"], {}) if n["parent"] is not None else {}
        attrs = {"name": n["name"], **ports, **marked, **scripts}
        if _do_while(cls, self.children[uid]):
            self.own[uid], self.elements[uid] = repeat_until_elements(parent, attrs)
            self.loops.add(uid)
        else:
            self.own[uid] = self.elements[uid] = ET.SubElement(parent, ident, attrs)

    def _parent(self, n: TreeNode) -> ET.Element:
        """The element ``n``'s element goes into: its parent's (under the Inverter of a do-while loop's
        condition), or a new ``<BehaviorTree>`` for a subtree instance's root, used by a ``<SubTree>``."""
        parent = self.tree if n["parent"] is None else self.elements[n["parent"]]
        if n["parent"] in self.loops and len(parent) == 1:  # the loop's condition, under its Inverter
            parent = ET.SubElement(parent, "Inverter", _onFailure="")
        if n["uid"] in self.subtrees:
            sid = self.subtrees[n["uid"]]
            attrs = {"ID": sid, "name": n["name"], "_autoremap": "true"}
            self.uses[n["uid"]] = ET.SubElement(parent, "SubTree", attrs)  # a YAML subtree shares the run's blackboard
            parent = ET.SubElement(self.root, "BehaviorTree", ID=sid)
        return parent


def _btcpp_order(root: ET.Element, tree_id: str) -> list[ET.Element]:
    """The node elements of ``root``'s tree ``tree_id`` in the order BT.CPP numbers them: pre-order,
    each ``<SubTree>`` followed by the nodes of the ``<BehaviorTree>`` it uses."""
    trees = {tree.get("ID"): tree for tree in root.iter("BehaviorTree")}
    order: list[ET.Element] = []
    stack = list(trees[tree_id])[::-1]
    while stack:
        element = stack.pop()
        order.append(element)
        stack.extend(list(trees[element.get("ID")] if element.tag == "SubTree" else element)[::-1])
    return order


def _model(model: ET.Element, used: Mapping[str, tuple[str, set[str]]], registry: Registry) -> None:
    """The ``<TreeNodesModel>``: every node ID ``used`` that is not BT.CPP's, with its ports (a
    plugin that was not imported declares the ports the tree gives it)."""
    for ident, (kind, ports) in sorted(used.items()):
        if ident in BTCPP_IDS:  # BT.CPP's own: no TreeNodesModel entry
            continue
        cls = registry.get(kind)
        entry = ET.SubElement(model, _category(cls), ID=ident)
        fields = cls.Params.model_fields if cls is not None else {}
        for name, field in fields.items():
            unit = unit_of(field)
            text = (field.description or "") + (f" [{unit}]" if unit else "")
            # an optional port without a value (None) has no default: Groot2 would write its text, "None"
            given = not field.is_required() and field.default is not None
            default = {"default": _port_value(field.default)} if given else {}
            port = ET.SubElement(entry, "input_port", {"name": name, **default})
            port.text = text
        for name in sorted(ports - set(fields)):
            ET.SubElement(entry, "input_port", {"name": name})


def _category(cls: Any) -> str:
    """The ``<TreeNodesModel>`` element of a node class: Control, Decorator, Condition or Action."""
    if isinstance(cls, type) and issubclass(cls, ControlNode) and cls.category == "composite":
        return "Control"
    if isinstance(cls, type) and issubclass(cls, ControlNode):
        return "Decorator"
    if isinstance(cls, type) and issubclass(cls, RobotBehaviour) and cls.condition:
        return "Condition"
    return "Action"


def mission_settings(mission: Mission, folder: Path) -> dict[str, str]:
    """A mission's settings as ``<ThymioMission>`` attributes (a shipped maze by its name, another by
    its path relative to ``folder``)."""
    pose = mission.start
    settings = {
        "name": mission.name,
        "description": mission.description,
        "maze": maze_reference(mission.maze_file, folder) if mission.maze_file else mission.maze.name,
        "start": f"{pose.x!r}, {pose.y!r}, {pose.yaw!r}",
        "tick_hz": repr(mission.tick_hz),
        "time_limit": repr(mission.time_limit),
        "seed": str(mission.seed),
        "sensor_model": mission.sensor_model,
        **({"robot": mission.robot} if mission.robot is not None else {}),
        **{f"noise.{k}": repr(v) for k, v in mission.noise.model_dump().items()},
    }
    if mission.backend != "sim" or mission.backend_options:
        settings["backend"] = json.dumps({"name": mission.backend, **mission.backend_options})
    if mission.expect is not None:
        settings["expect"] = json.dumps(mission.expect.model_dump(mode="json"))
    plugins = mission_plugins(mission, folder)
    if plugins:
        settings["plugins"] = json.dumps(plugins)
    return settings


def mission_plugins(mission: Mission, folder: Path) -> list[str]:
    """The plugins a mission loaded, as an export's ``plugins``: ``.py`` files relative to
    ``folder``, then ``module:Class`` for each imported plugin node from an installed module that
    is not an entry point's (those load by themselves)."""
    registry = mission.registry
    refs = [os.path.relpath(path, folder) for path in dict.fromkeys(registry.plugin_files)]
    defaults = set(default_registry())
    for name, cls in registry.items():
        module = cls.__module__
        if name in defaults or module.startswith(("thymio_bt.", "thymio_bt_plugin_")) or module == "builtins":
            continue
        if not issubclass(cls, UnrunPlugin):
            refs.append(f"{module}:{cls.__name__}")
    return refs


def mission_xml(mission: Mission, output: Path | None = None) -> str:
    """The BT.CPP XML of a loaded mission: its tree as planned, parameters as ports (in SI units),
    each subtree instance as its own ``<BehaviorTree>`` used by a ``<SubTree>`` node, its settings
    in a ``<ThymioMission>`` element (BT.CPP ignores it) so that the file runs as the mission did
    (``thymio-bt run mission.xml``)."""
    return mission_btcpp(mission, output).xml


def mission_btcpp(mission: Mission, output: Path | None = None) -> BtcppTree:
    """:func:`mission_xml`'s XML with the ``_uid`` of each planned node (see :class:`BtcppTree`)."""
    nodes, params, subtrees = mission_nodes(mission)
    folder = (output or Path("mission.xml")).resolve().parent
    return btcpp_tree(nodes, mission.registry, params, settings=mission_settings(mission, folder), subtrees=subtrees)


def mission_nodes(mission: Mission) -> tuple[list[TreeNode], dict[int, dict[str, Any]], dict[int, str]]:
    """A mission's planned tree in pre-order (uids from 1, as the built py_trees tree walks), each
    node's parameters, and the BehaviorTree ID of each subtree instance's root (``NAME``, then
    ``NAME_2``... when a subtree is used several times)."""
    nodes: list[TreeNode] = []
    params: dict[int, dict[str, Any]] = {}
    subtrees: dict[int, str] = {}
    uses: dict[str, int] = {}

    def visit(plan: NodePlan, parent: int | None, prefix: str) -> None:
        uid = len(nodes) + 1
        path = f"{prefix}/{plan.name}" if prefix else plan.name
        nodes.append(TreeNode(uid=uid, path=path, name=plan.name, kind=plan.behaviour or plan.kind, parent=parent))
        if plan.subtree is not None:
            uses[plan.subtree] = uses.get(plan.subtree, 0) + 1
            subtrees[uid] = plan.subtree if uses[plan.subtree] == 1 else f"{plan.subtree}_{uses[plan.subtree]}"
        if plan.params is not None:
            values = plan.params.model_dump()
            values.update({key: "{" + ref + "}" for key, ref in plan.blackboard_refs.items()})
            params[uid] = values
        for child in plan.children:
            visit(child, uid, path)

    visit(mission.tree, None, "")
    return nodes, params, subtrees


def palette_xml(registry: Registry | None = None) -> str:
    """A Groot2 palette: a ``<TreeNodesModel>`` of every robot behaviour and condition of ``registry``
    (the default: the built-ins and installed plugins) with their ports, to import in Groot2 beside
    its own built-ins (BT.CPP's control nodes, which run here with BT.CPP's semantics).

    Example::

        >>> text = palette_xml()
        >>> '<Action ID="MoveUntilWall">' in text, '<Condition ID="WallAhead">' in text, "bt_sequence" in text
        (True, True, False)
    """
    registry = registry or default_registry()
    root = ET.Element("root", BTCPP_format="4")
    used = {
        (("Thymio" + name) if name in RESERVED else name): (name, set[str]())
        for name, cls in registry.behaviours()
        if not name.startswith("bt_")
    }
    _model(ET.SubElement(root, "TreeNodesModel"), used, registry)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def yaml_hint(kind: str) -> str | None:
    """The hint for a BT.CPP node name written in a YAML mission (``Fallback:``): thymio-bt's own
    node of that role, and BT.CPP's semantics as ``bt_*``; None for another name.

    Example::

        >>> yaml_hint("Fallback")
        "Fallback is `selector` here (BT.CPP's own Fallback, tick for tick: `bt_fallback`)"
        >>> yaml_hint("IfThenElse"), yaml_hint("MoveUntilWal")
        ("IfThenElse is `bt_if_then_else` in YAML (BT.CPP's own IfThenElse)", None)
    """
    ours = next((name for name, cls in default_registry().items() if _exported_as(cls, kind)), None)
    bt = BTCPP_IDS.get(kind)
    if ours is not None:
        return f"{kind} is `{ours}` here (BT.CPP's own {kind}, tick for tick: `{bt}`)"
    if bt is not None:
        return f"{kind} is `{bt}` in YAML (BT.CPP's own {kind})"
    return None


def _exported_as(cls: Any, ident: str) -> bool:
    """Whether node class ``cls`` is thymio-bt's composite or decorator that an export writes as BT.CPP's ``ident``."""
    return isinstance(cls, type) and issubclass(cls, ControlNode) and not cls.btcpp_native and cls.btcpp_id == ident
