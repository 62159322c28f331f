"""The validate-and-plan pass: the ``tree:`` of an assembled mission, node by node, into a
:class:`~thymio_bt.plan.model.NodePlan`.

Each node's type is looked up in the registry (a behaviour, a composite, a decorator) or among the
mission's subtrees; its parameters are read by their declared types (thymio_bt.inputs.fields: units,
tuples, spawn names; see :mod:`thymio_bt.mission.parameters`) and validated by its pydantic model,
so every problem is reported where it was written. Subtrees are expanded with their arguments in
place.

Example::

    >>> from thymio_bt.mission.loader import load_mission
    >>> tree = load_mission("maze_part1_2").tree
    >>> tree.kind, [child.name for child in tree.children]
    ('sequence', ['part 1', 'DeleteEntity', 'SpawnEntity', 'part 2'])
    >>> tree.children[0].params.distance          # MoveUntilWall: {distance: $final_stop}, 5cm
    0.05
    >>> part2 = tree.children[3]                   # a use of the subtree to_dead_end, in place
    >>> part2.kind, part2.subtree, part2.path
    ('repeat', 'to_dead_end', 'tree.sequence[3].to_dead_end.repeat')
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from thymio_bt.behaviours import ControlNode
from thymio_bt.errors import did_you_mean, type_name
from thymio_bt.inputs.units import Quantity
from thymio_bt.inputs.yamlio import MarkedDict
from thymio_bt.mission.assemble import Assembly, Subtree
from thymio_bt.mission.parameters import ParameterReader, parse_value_kind
from thymio_bt.mission.pass_base import Scope, Where
from thymio_bt.plan.model import MAX_DEPTH, MAX_NODES, NodePlan

__all__ = ["MAX_DEPTH", "MAX_NODES", "TreePlanner", "parse_value_kind"]


@dataclass(frozen=True)
class _At:
    """Where a node is planned: its type's place, its body's place, its path, the parameters in
    scope, its depth and the subtrees it is inside of (innermost last)."""

    where: Where
    body_where: Where
    path: str
    scope: Scope
    depth: int
    stack: tuple[str, ...]

    @property
    def file(self) -> str:
        """The file the node is written in."""
        return self.where[0]


class TreePlanner(ParameterReader):
    """Runs the planning pass over an :class:`Assembly`'s tree; problems go to the assembly's list."""

    def __init__(self, assembly: Assembly) -> None:
        super().__init__(assembly.problems)
        self.registry = assembly.registry
        self.subtrees = assembly.subtrees
        self.maze = assembly.maze
        self.robot = assembly.robot
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
        used = value.subtree_use if isinstance(value, MarkedDict) else None
        if plan is not None and used is not None:
            plan.subtree = used
        return plan

    def _node(
        self, value: Any, where: Where, path: str, scope: Scope, depth: int, subtree_stack: tuple[str, ...]
    ) -> NodePlan | None:
        """:meth:`node`'s work: the limits, the node's type, then the plan by what the type names."""
        if self._over_limits(where, path, depth):
            return None
        split = self._type_and_body(value, where, path)
        if split is None:
            return None
        kind, body, where, body_where = split
        node_path = f"{path}.{kind}" if path else kind
        at = _At(where, body_where, node_path, scope, depth, subtree_stack)
        if kind in self.registry:
            cls = self.registry[kind]
            if issubclass(cls, ControlNode):
                return self._control(cls, body, at)
            return self._behaviour(kind, body, at)
        if kind in self.subtrees:
            return self._use_subtree(kind, body, at)
        from thymio_bt.btcpp.export import yaml_hint  # the BT.CPP export, for a misspelt node only

        hint = yaml_hint(kind) or did_you_mean(kind, [*self.registry, *self.subtrees])
        self.problem(f"unknown node type '{kind}'", where, node_path, hint)
        return None

    def _over_limits(self, where: Where, path: str, depth: int) -> bool:
        """Whether one more node at ``depth`` is past :data:`MAX_NODES` or :data:`MAX_DEPTH` (said once)."""
        self.node_count += 1
        if self.node_count > MAX_NODES:
            if self.node_count == MAX_NODES + 1:
                self.problem(
                    f"the tree expands to more than {MAX_NODES} nodes",
                    where,
                    path,
                    "subtrees that use other subtrees several times multiply; simplify the tree",
                )
            return True
        if depth > MAX_DEPTH:
            if where not in self.too_deep:  # once per place, not once per subtree expansion
                self.too_deep.add(where)
                self.problem(f"the tree is nested deeper than {MAX_DEPTH} levels", where, path)
            return True
        return False

    def _type_and_body(self, value: Any, where: Where, path: str) -> tuple[str, Any, Where, Where] | None:
        """(type, body, the type's place, the body's place) of a node, or None (and a problem)."""
        file = where[0]
        if isinstance(value, str):
            return value, None, where, where
        if isinstance(value, list):  # e.g. repeat: {do: [a, b]}: one node is expected there
            key = path.rpartition(".")[2]
            self.problem(
                f"a list of {len(value)} nodes where one node is expected: wrap several nodes in a sequence",
                where,
                path,
                f"e.g. '{key}: {{sequence: [...]}}'" if key.isidentifier() else "e.g. '- sequence: [...]'",
            )
            return None
        if not (isinstance(value, MarkedDict) and len(value) == 1):
            keys = f" (found keys: {', '.join(map(str, value))})" if isinstance(value, dict) and value else ""
            self.problem(
                f"a node is a mapping with exactly one key: a behaviour, composite, decorator or subtree name{keys}",
                where,
                path,
                "e.g. '- MoveUntilWall: {distance: 5cm}' or '- sequence: [...]'",
            )
            return None
        kind = next(iter(value))
        where = self.where_key(value, kind, file)
        if not isinstance(kind, str):
            self.problem(f"a node type must be a name, got {type_name(kind)}", where, path)
            return None
        return kind, value[kind], where, self.where_value(value, kind, file)

    def _name(self, body: Any, default: str, file: str, path: str) -> str:
        """The node's ``name:`` (checked), or ``default``: its type or subtree name."""
        if isinstance(body, MarkedDict) and "name" in body:
            name = body["name"]
            if isinstance(name, str) and name and "/" not in name:
                return name
            self.problem("name must be a non-empty string without '/'", self.where_value(body, "name", file), path)
        return default

    def _child(self, value: Any, where: Where, path: str, at: _At) -> NodePlan | None:
        """A node one level below the node planned ``at``."""
        return self.node(value, where, path, at.scope, at.depth + 1, at.stack)

    def _children(self, raw: Any, where: Where, at: _At) -> list[NodePlan]:
        """A composite's ``children``: each one planned, sibling names made unique (``Wait#2``)."""
        if not isinstance(raw, list) or not raw:
            self.problem(
                "children must be a non-empty list of nodes",
                where,
                at.path,
                "e.g. children: [{MoveUntilWall: {distance: 5cm}}, {TurnAngle: {angle: 90deg}}]",
            )
            return []
        children = []
        for i, item in enumerate(raw):
            child = self._child(item, self.where_value(raw, i, where[0]), f"{at.path}[{i}]", at)
            if child is not None:
                children.append(child)
        seen: dict[str, int] = {}
        for child in children:  # unique names among siblings keep node paths unambiguous
            count = seen.get(child.name, 0) + 1
            seen[child.name] = count
            if count > 1:
                child.name = f"{child.name}#{count}"
        return children

    def _control(self, cls: type[ControlNode], body: Any, at: _At) -> NodePlan | None:
        """A composite (``children``) or decorator (``do`` and its other node keys), with its parameters."""
        kind = cls.yaml_name
        composite = cls.category == "composite"
        long_form = isinstance(body, MarkedDict) and ("children" in body if composite else "do" in body)
        if composite and isinstance(body, MarkedDict):
            long_form = True
        elif not composite and not long_form and not cls.short_form:
            self.problem(f"{kind} needs a mapping with {', '.join(cls.keys())}", at.body_where, at.path, cls.example)
            return None
        if long_form:
            self.check_keys(body, ("name", *cls.keys()), at.file, at.path, f"a {kind}", cls.Params)
        fields = cls.Params.model_fields
        params, _ = self._params(
            kind,
            cls.Params,
            body if long_form else MarkedDict(),
            [k for k in body if k in fields] if long_form else [],
            at.where,
            at.path,
            at.scope,
            allow_refs=False,
            missing_hint=cls.example,
        )
        if composite:
            raw_children = body.get("children") if long_form else body
            in_body = long_form and "children" in body
            children = self._children(
                raw_children, self.where_value(body, "children", at.file) if in_body else at.body_where, at
            )
        else:
            decorated = self._decorated(cls, body, long_form, at)
            if decorated is None:
                return None
            children = decorated
        if params is None:
            return None
        return NodePlan(
            kind,
            self._name(body, kind, at.file, at.path),
            at.path,
            params=params,
            children=children,
            where=at.where,
        )

    def _decorated(self, cls: type[ControlNode], body: Any, long_form: bool, at: _At) -> list[NodePlan] | None:
        """A decorator's nodes: ``do`` (the whole body in the short form), then its other node keys
        (``until``...); None when ``do`` is broken or a required node is missing."""
        kind, file = cls.yaml_name, at.file
        if long_form:
            child = self._child(body["do"], self.where_value(body, "do", file), f"{at.path}.do", at)
        else:
            child = self._child(body, at.body_where, f"{at.path}.do", at)
        children = [child] if child is not None else []
        for key in cls.node_keys:
            if long_form and key in body:
                extra = self._child(body[key], self.where_value(body, key, file), f"{at.path}.{key}", at)
                if extra is not None:
                    children.append(extra)
            elif key in cls.required_nodes:
                self.problem(f"{kind} needs a {key}", at.body_where, at.path, cls.example)
                return None
        for first, second in cls.exclusive:
            if long_form and first in body and second in body:
                self.problem(f"{kind} takes either {first} or {second}, not both", at.body_where, at.path)
        return children if child is not None else None

    def _behaviour(self, kind: str, body: Any, at: _At) -> NodePlan | None:
        """A robot behaviour or condition with its parameters (``bb:`` references allowed)."""
        if body is None:
            body = MarkedDict()
        if not isinstance(body, MarkedDict):
            self.problem(
                f"{kind} takes a mapping of parameters, got {type_name(body)}",
                at.body_where,
                at.path,
                f"e.g. '{kind}: {{}}'; see 'thymio-bt behaviours {kind}'",
            )
            return None
        params, refs = self._params(
            kind,
            self.registry[kind].Params,
            body,
            [k for k in body if k != "name"],
            at.where,
            at.path,
            at.scope,
            allow_refs=True,
        )
        if params is None:
            return None
        return NodePlan(
            "behaviour",
            self._name(body, kind, at.file, at.path),
            at.path,
            behaviour=kind,
            params=params,
            blackboard_refs=refs,
            where=at.where,
        )

    def _use_subtree(self, kind: str, body: Any, at: _At) -> NodePlan | None:
        """A use of a subtree: its tree planned in place, in a scope of its parameters."""
        if kind in at.stack:
            self.problem(
                f"subtree '{kind}' uses itself ({' -> '.join([*at.stack, kind])})",
                at.where,
                at.path,
                "a subtree may not contain itself; use repeat: to loop",
            )
            return None
        sub = self.subtrees[kind]
        values = self._subtree_arguments(kind, sub, body, at)
        if values is None:
            return None
        tree = self.node(
            sub.body["tree"],
            self.where_value(sub.body, "tree", sub.where[0]),
            at.path,
            Scope(values, self.root_scope),
            at.depth + 1,
            (*at.stack, kind),
        )
        if tree is not None:
            tree.name = self._name(body, kind, at.file, at.path)
            tree.subtree = kind
        return tree

    def _subtree_arguments(self, kind: str, sub: Subtree, body: Any, at: _At) -> dict[str, Any] | None:
        """A subtree's parameters for one use: its defaults (in the mission's scope), overridden by the
        arguments given (in the caller's); None when the declaration or the arguments are broken."""
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
            values[name] = self.argument(
                raw,
                self.root_scope,
                self.where_value(declared, name, sfile),
                f"subtrees.{kind}.parameters.{name}",
                None,
            )
        if body is not None and not isinstance(body, MarkedDict):
            self.problem(f"subtree '{kind}' takes a mapping of parameters", at.body_where, at.path)
            return None
        for name, raw in (body or {}).items():
            if name == "name":
                continue
            if name not in declared:
                self.problem(
                    f"subtree '{kind}' has no parameter '{name}'",
                    self.where_key(body, name, at.file),
                    f"{at.path}.{name}",
                    did_you_mean(str(name), declared) if declared else f"subtree '{kind}' declares no parameters",
                )
                continue
            old = values.get(name)
            values[name] = self.argument(
                raw,
                at.scope,
                self.where_value(body, name, at.file),
                f"{at.path}.{name}",
                old.kind if isinstance(old, Quantity) else None,
            )
        return values
