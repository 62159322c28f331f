"""The tree of a BehaviorTree.CPP 4 XML mission, read into the YAML form (``{Type: body}`` nodes):
BT.CPP's elements as nodes, each ``<SubTree>`` replaced by a copy of its ``<BehaviorTree>`` whose
blackboard keys are renamed for that instance (:mod:`thymio_bt.btcpp.xml_scope`).

Hostile files are bounded: subtrees nest :data:`MAX_SUBTREE_DEPTH` deep at most, the expanded tree
holds at most :data:`~thymio_bt.plan.model.MAX_NODES` nodes, nests at most
:data:`~thymio_bt.plan.model.MAX_DEPTH` levels and holds at most :data:`MAX_TEXT` characters of
attributes (a subtree used twice by a subtree used twice... doubles at each level), and a port's JSON
nests :data:`MAX_JSON_NESTING` deep at most; past any of them the file is a located error.

Example::

    >>> main = Element("BehaviorTree", {"ID": "Main"}, 3, 3, [Element("SubTree", {"ID": "Leg", "n": "{laps}"}, 4, 5)])
    >>> leg = Element("BehaviorTree", {"ID": "Leg"}, 6, 3, [Element("Script", {"code": "n += 1; k := n"}, 7, 5)])
    >>> node = TreeReader("m.xml", {"Main": main, "Leg": leg}, {}).tree(main)
    >>> node, node.subtree_use
    ({'bt_script': {'code': 'laps += 1; __1_Leg__k := laps'}}, 'Leg')
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cache
from typing import Any

from thymio_bt.behaviours.flow.node import ControlNode
from thymio_bt.btcpp.export import KIND_ATTR, RESERVED
from thymio_bt.btcpp.runtime.control import BTCPP_IDS, CONDITION_ATTRS
from thymio_bt.btcpp.xml_scope import Literal, Ports, Scope, pointer, rename_script, subtree_ports
from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.fields import Entry, ScriptText, port_roles
from thymio_bt.inputs.xmlparse import parse_xml
from thymio_bt.inputs.yamlio import MAX_NESTING, MarkedDict, MarkedList
from thymio_bt.plan.model import MAX_DEPTH, MAX_NODES
from thymio_bt.plan.registry import control_kind

#: the deepest nesting of subtrees (a subtree using a subtree ... ): far beyond any mission
MAX_SUBTREE_DEPTH = 64
#: the most characters of attributes (names and values) the expanded tree holds: four times the
#: largest mission file, so the checks after reading stay as fast as on the largest file
MAX_TEXT = 1 << 20
#: the deepest nesting of a JSON value in a port (a YAML mission's own limit)
MAX_JSON_NESTING = MAX_NESTING

#: BT.CPP built-in -> the node kind of BT.CPP's semantics (an element without _thymio)
_FROM_BUILTIN = dict(BTCPP_IDS)
#: BT.CPP's nodes whose port is a script


@dataclass
class Element:
    """An XML element with its place (1-based line and column) and its child elements."""

    tag: str
    attrs: dict[str, str]
    line: int
    column: int
    children: list[Element] = field(default_factory=list)


def element_roots(data: bytes, file: str, what: str, hint: str) -> list[Element]:
    """The top-level elements of ``data`` (the XML of ``file``, a ``what``) with their children and
    places, under :func:`~thymio_bt.inputs.xmlparse.parse_xml`'s guards (no DTD, no entities,
    bounded depth); ``hint`` goes with a syntax error.

    >>> [(e.tag, [c.tag for c in e.children]) for e in element_roots(b"<root><A/><B/></root>", "t.xml", "test", "")]
    [('root', ['A', 'B'])]
    """
    stack: list[Element] = []
    roots: list[Element] = []

    def start(tag: str, attrs: dict[str, str], line: int, column: int) -> None:
        element = Element(tag, attrs, line, column)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    parse_xml(data, file, what, start, lambda tag: stack.pop(), hint=hint)
    return roots


@dataclass(frozen=True)
class _Shape:
    """What an element reads as, whatever the scope: its ID (``RepeatUntil`` for an export's
    do-while loop), the node kind, the element read (that loop's), its ports but ``name``, its name,
    whether it has condition attributes, and how many characters its attributes hold."""

    ident: str
    kind: str
    element: Element
    attrs: dict[str, str]
    name: str | None
    conditioned: bool
    size: int


def json_depth(text: str) -> int:
    """How deep the JSON ``text`` nests its lists and objects (brackets in strings do not count)."""
    depth = deepest = 0
    in_string = escaped = False
    for char in text:
        if in_string:
            escaped, in_string = (False, True) if escaped else (char == "\\", char != '"')
        elif char == '"':
            in_string = True
        elif char in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif char in "]}":
            depth -= 1
    return deepest


def check_json(text: str, file: str, line: int, column: int) -> None:
    """Refuse JSON nested deeper than :data:`MAX_JSON_NESTING` (decoding it would overflow the stack)."""
    if json_depth(text) > MAX_JSON_NESTING:
        raise UserError(
            Problem(
                f"a JSON value nested deeper than {MAX_JSON_NESTING} levels",
                file,
                line,
                column,
                hint="flatten the value",
            )
        )


def port_value(text: str, file: str, line: int, column: int) -> Any:
    """A port's text as the YAML scalar it stands for: numbers, true/false, JSON lists, {key}."""
    stripped = text.strip()
    if stripped in ("true", "false"):
        return stripped == "true"
    if stripped.startswith("{") and stripped.endswith("}") and stripped[1:-1].strip():
        return "bb:" + stripped[1:-1].strip()
    if stripped.startswith("["):
        check_json(stripped, file, line, column)
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


def marked(mapping: dict[str, Any], element: Element) -> MarkedDict:
    """``mapping`` as a :class:`MarkedDict` whose keys and values all carry ``element``'s place."""
    out = MarkedDict(mapping)
    out.mark = (element.line, element.column)
    for key in mapping:
        out.marks[key] = out.value_marks[key] = (element.line, element.column)
    return out


@cache
def _roles(kind: str) -> dict[str, Entry | ScriptText]:
    """The ports of node ``kind`` that name a blackboard entry or hold a script, as its parameter
    model declares them (:func:`~thymio_bt.inputs.fields.port_roles`)."""
    from thymio_bt.plan.registry import default_registry

    cls = default_registry().get(kind)
    return {} if cls is None or cls.Params is None else port_roles(cls.Params)


class TreeReader:
    """Reads the tree of one file: ``trees`` by ID, ``models`` the ports of each subtree's
    ``<TreeNodesModel>`` entry (port -> (default or None, where))."""

    def __init__(
        self, file: str, trees: dict[str, Element], models: dict[str, dict[str, tuple[str | None, Any]]]
    ) -> None:
        self.file, self.trees, self.models = file, trees, models
        self.nodes = self.text = self.instances = 0
        self._ports: dict[int, Ports] = {}
        self._shapes: dict[int, _Shape] = {}

    def tree(self, tree: Element) -> MarkedDict:
        """The main tree ``tree`` (a ``<BehaviorTree>``) as one node, subtrees expanded."""
        return self.node(tree.children[0], Scope(), 0, ((tree.attrs.get("ID", ""), tree),))

    def _where(self, element: Element) -> tuple[str, int, int]:
        return (self.file, element.line, element.column)

    def _check(self, element: Element, shape: _Shape, depth: int, stack: tuple[tuple[str, Element], ...]) -> None:
        """Refuse the tree past the expansion limits, at the innermost ``<SubTree>`` being expanded
        (the depth: at ``element``, of ``shape``, at ``depth``)."""
        if self.nodes > MAX_NODES or self.text > MAX_TEXT:
            at = stack[-1][1] if len(stack) > 1 else element
            what = f"{MAX_NODES} nodes" if self.nodes > MAX_NODES else f"{MAX_TEXT} characters of attributes"
            raise UserError(
                Problem(
                    f"the tree expands to more than {what}{_chain(stack, 'at')}",
                    self.file,
                    at.line,
                    at.column,
                    hint="each <SubTree> is a copy of its tree: subtrees that use subtrees several times multiply",
                )
            )
        if depth + shape.conditioned > MAX_DEPTH:
            raise UserError(
                Problem(
                    f"the tree is nested deeper than {MAX_DEPTH} levels{_chain(stack, 'in')}",
                    self.file,
                    element.line,
                    element.column,
                    hint="split it into a sequence of shallower parts",
                )
            )

    def _shape(self, element: Element) -> _Shape:
        """What ``element`` is, whatever the scope: read once, however many times it is expanded."""
        shape = self._shapes.get(id(element))
        if shape is not None:
            return shape
        ident = element.tag
        attrs = {k: v for k, v in element.attrs.items() if not k.startswith("_")}
        conditioned = not CONDITION_ATTRS.keys().isdisjoint(element.attrs)
        size = sum(len(k) + len(v) for k, v in element.attrs.items())
        mark, do_while = _mark(element)
        read = element
        if ident == "SubTree":
            kind = ""
        elif do_while:
            read, ident, kind = _repeat_until(element, self.file), "RepeatUntil", mark
        elif mark:
            kind = mark
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
        name = attrs.pop("name", None)
        shape = self._shapes[id(element)] = _Shape(ident, kind, read, attrs, name, conditioned, size)
        return shape

    def node(self, element: Element, scope: Scope, depth: int, stack: tuple[tuple[str, Element], ...]) -> MarkedDict:
        """One element as a ``{Type: body}`` node of the YAML form (under a ``bt_conditions`` node
        when it has BT.CPP's condition attributes); a ``<SubTree ID=...>`` is replaced by the root of
        that ``<BehaviorTree>`` (named as the SubTree, when it is)."""
        shape = self._shape(element)
        self.nodes += (shape.ident != "SubTree") + shape.conditioned  # a SubTree is its tree's root
        self.text += shape.size
        self._check(element, shape, depth, stack)
        inner = depth + shape.conditioned
        if shape.ident == "SubTree":
            node = self._subtree(element, scope, inner, stack)
        else:
            children = [self.node(child, scope, inner + 1, stack) for child in shape.element.children]
            body: dict[str, Any] = {} if shape.name is None else {"name": shape.name}
            body.update(self._body(shape.ident, shape.kind, dict(shape.attrs), children, element, scope))
            node = marked({shape.kind: marked(body, element)}, element)
        if shape.conditioned:
            node = self._with_conditions(node, element, scope)
        self._check(element, shape, depth, stack)  # renamed scripts are longer
        return node

    def _script(self, text: str, scope: Scope, where: tuple[str, int, int]) -> str:
        """:func:`~thymio_bt.btcpp.xml_scope.rename_script`, counting the characters it adds."""
        renamed = rename_script(text, scope, where)
        self.text += len(renamed) - len(text)
        return renamed

    def _body(
        self, ident: str, kind: str, attrs: dict[str, str], children: list[MarkedDict], element: Element, scope: Scope
    ) -> dict[str, Any]:
        """A node's body but its name, from its ports (``attrs``, keys renamed for ``scope``) and its
        child nodes: a composite's ``children``, a decorator's ``do`` (and ``condition``, ``until``),
        a behaviour's parameters."""
        cls = control_kind(kind)
        if ident == "RepeatUntil" and cls is not None:
            if len(children) != 2:
                raise UserError(
                    Problem(
                        "RepeatUntil takes two children: the body, then the condition",
                        self.file,
                        element.line,
                        element.column,
                    )
                )
            return {"do": children[0], cls.then: children[1]}
        if kind.startswith("bt_"):  # BT.CPP's own node: its ports as written (the node's model reads them)
            ports = self._bt_ports(kind, attrs, element, scope)
            if cls is None:  # a leaf
                return ports
            nodes = (
                {"do": children[0]}
                if cls.category == "decorator" and children
                else {"children": _list(children, element)}
            )
            return {**ports, **nodes}
        keys = {port for port, role in _roles(kind).items() if role == Entry()} if not children else set()
        # a port left empty is not given (Groot2 writes a port left blank in its editor as an empty text)
        values = {k: self._value(k, v, element, scope, k in keys) for k, v in attrs.items() if v.strip()}
        if cls is not None and cls.category == "composite":
            return {**cls.from_btcpp(values), "children": _list(children, element)}
        if not children:  # a behaviour or condition
            return values
        decorator = cls or ControlNode  # a kind the default registry lacks (a plugin's): a decorator
        body = {**decorator.from_btcpp(values), "do": children[0]}  # and its other nodes
        body.update(zip(decorator.node_keys, children[1:], strict=False))
        return body

    def _value(self, port: str, text: str, element: Element, scope: Scope, names_key: bool) -> Any:
        """A port of thymio-bt's node as its value, a ``{key}`` as ``bb:`` and the key renamed (a
        literal port: its value); ``names_key``: the port is a leaf's key parameter (an entry it writes)."""
        where = self._where(element)
        if text.strip() == "{=}":  # BT.CPP: the entry named as the port
            text = "{" + port + "}"
        value = port_value(text, *where)
        if names_key and isinstance(value, str) and not value.startswith("bb:"):
            return scope.write(value, where)
        if not (isinstance(value, str) and value.startswith("bb:")):
            return value
        found = scope.read(value[3:])
        if isinstance(found, Literal):
            return port_value(found.text, *found.where)
        return "bb:" + found

    def _bt_ports(self, kind: str, attrs: dict[str, str], element: Element, scope: Scope) -> dict[str, str]:
        """The ports of BT.CPP's node ``kind`` as written, keys renamed for ``scope``: in scripts, in
        ``{key}`` pointers and in the entries the node writes or removes (its model's port roles)."""
        where = self._where(element)
        roles = _roles(kind)
        ports: dict[str, str] = {}
        for port, text in attrs.items():
            role = roles.get(port)
            if isinstance(role, ScriptText):
                ports[port] = self._script(text, scope, where)
            elif role == Entry("removed"):
                ports[port] = scope.local(text.strip("{}"), where)
            elif role == Entry():
                braced = pointer(text) is not None
                new = scope.write(text.strip().strip("{}").strip(), where)
                ports[port] = "{" + new + "}" if braced else new
            else:
                key = port if text.strip() == "{=}" else pointer(text)
                found = scope.read(key) if key is not None else text
                ports[port] = found.text if isinstance(found, Literal) else "{" + found + "}" if key else found
        return ports

    def _with_conditions(self, node: MarkedDict, element: Element, scope: Scope) -> MarkedDict:
        """``node`` under a ``bt_conditions`` node when its element has BT.CPP's pre/post-condition
        attributes (``_skipIf``, ``_while``, ``_onSuccess``...), else ``node``."""
        where = self._where(element)
        scripts = {
            CONDITION_ATTRS[k]: self._script(v, scope, where) for k, v in element.attrs.items() if k in CONDITION_ATTRS
        }
        if not scripts:
            return node
        body = next(iter(node.values()))
        name = body.get("name", element.tag) if isinstance(body, dict) else element.tag
        return marked({"bt_conditions": marked({"name": name, **scripts, "do": node}, element)}, element)

    def _subtree(
        self, element: Element, scope: Scope, depth: int, stack: tuple[tuple[str, Element], ...]
    ) -> MarkedDict:
        """A ``<SubTree ID=...>``: the root of that ``<BehaviorTree>`` read in a scope of its own,
        marked as its use."""
        ident = element.attrs.get("ID", "")
        line, column = element.line, element.column
        if ident not in self.trees:
            raise UserError(
                Problem(
                    f'<SubTree> names no <BehaviorTree ID="{ident}">',
                    self.file,
                    line,
                    column,
                    hint=f"the file's trees: {', '.join(sorted(self.trees)) or 'none'}",
                )
            )
        if any(name == ident for name, _ in stack):
            used = [name for name, _ in stack]
            raise UserError(
                Problem(
                    f"subtree '{ident}' uses itself ({' -> '.join([*used, ident])})",
                    self.file,
                    line,
                    column,
                    hint="a subtree may not contain itself",
                )
            )
        if len(stack) > MAX_SUBTREE_DEPTH:
            raise UserError(
                Problem(
                    f"subtrees nest more than {MAX_SUBTREE_DEPTH} deep"
                    f" ({stack[0][0]} -> {stack[1][0]} -> ... -> {ident})",
                    self.file,
                    line,
                    column,
                    hint="flatten the chain of subtrees",
                )
            )
        tree = self.trees[ident]
        if len(tree.children) != 1:
            raise UserError(Problem("a <BehaviorTree> holds exactly one root node", self.file, tree.line, tree.column))
        ports = self._ports.get(id(element))
        if ports is None:  # read once per element, however many times it is expanded
            ports = self._ports[id(element)] = subtree_ports(
                element.attrs, self.models.get(ident), ident, self._where(element)
            )
        self.instances += 1
        node = self.node(tree.children[0], scope.child(self.instances, ident, ports), depth, (*stack, (ident, element)))
        node.subtree_use = ident  # the plan remembers it: the report's phases, the export's <SubTree>
        if "name" in element.attrs:
            body = next(iter(node.values()))
            if isinstance(body, MarkedDict):
                body["name"] = element.attrs["name"]
        return node


def _chain(stack: tuple[tuple[str, Element], ...], word: str) -> str:
    """`` (at Main -> A -> B)``: the subtrees being expanded, the middle left out when there are
    many; "" outside any."""
    if len(stack) < 2:
        return ""
    names = [ident if len(ident) <= 40 else ident[:37] + "..." for ident, _ in stack]
    if len(names) > 8:
        names = [*names[:3], "...", *names[-4:]]
    return f" ({word} {' -> '.join(names)})"


def _mark(element: Element) -> tuple[str, bool]:
    """The node kind ``element``'s :data:`~thymio_bt.btcpp.export.KIND_ATTR` names ("" when it names
    none, or not the kind an export writes as this element), and whether the element is the
    do-while loop an export writes for it (:func:`~thymio_bt.btcpp.export.repeat_until_elements`)."""
    mark = element.attrs.get(KIND_ATTR, "")
    cls = control_kind(mark) if mark else None
    if cls is None or cls.btcpp_native:
        return "", False
    do_while = bool(cls.then) and element.tag == "Sequence"
    return (mark, do_while) if do_while or cls.btcpp_id == element.tag else ("", False)


def _repeat_until(element: Element, file: str) -> Element:
    """The do-while loop an export writes (:func:`~thymio_bt.btcpp.export.repeat_until_elements`)
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
    return Element("RepeatUntil", element.attrs, element.line, element.column, [body, condition])


def _list(items: list[MarkedDict], element: Element) -> MarkedList:
    """``items`` as a :class:`MarkedList` at ``element``'s place."""
    out = MarkedList(items)
    out.mark = (element.line, element.column)
    out.marks = [item.mark for item in items]
    return out
