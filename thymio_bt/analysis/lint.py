"""A teaching lint for missions (``thymio-bt lint``): trees that load and run but cannot do what
their author meant, each finding at its file:line with a hint.

The rules, by id (the first four, on the tree's structure, are :mod:`thymio_bt.analysis.tree_rules`):

- ``unreachable``: a child that can never run: after a child that never succeeds in a sequence
  (it always fails, or never ends: a ``repeat: forever``), after one that never fails in a selector
  (it always succeeds, or never ends); a ``repeat``'s ``until`` after a body that never succeeds,
  a ``guard``'s child behind a condition that never holds.
- ``reactive-restart``: the classic trap of reactive composites, which tick their children from the
  first one at every tick. A child of a reactive sequence that runs over several ticks (an action)
  before another child that does too: once the later child runs, the earlier one, which had
  succeeded, is started again at every tick and halts the later one (py_trees and BT.CPP 4 alike;
  BT.CPP asks for a single asynchronous child). A child of a reactive selector that starts an
  action without a condition first, before a child that runs: once it fails, it is started again
  at every tick and halts the lower-priority child. A condition before an action is the intended use: conditions
  are checked at every tick, a running action goes on.
- ``forever``: a ``repeat: forever`` whose child never fails, with nothing above it to stop it (a
  timeout, a guard, a parallel, a reactive composite's condition): the run can only end at its time limit.
- ``checked-once``: in a plain ``sequence``, a check that the way ahead is clear (``invert: WallAhead``,
  ``invert: ObstacleAhead``) before a drive that goes farther than the check saw (``MoveDistance``,
  ``MoveCells``, ``GoToPose``, ``FollowWaypoints``): checked once, before the drive, the run ends
  in a collision. Told apart from the intended uses of a condition in a sequence (a decision before a
  turn, ``SideOpen`` then ``TurnAngle``; a check before an instant action; a drive no farther than
  the clearance checked) by what the condition vouches for and how far the action after it drives.
- ``unused-subtree``, ``unused-parameter``: a subtree of the mission file that no tree uses, an
  included file none of whose subtrees is used; a parameter of the mission or of a subtree that no
  ``$name`` refers to.
- ``edge-of-range``: a value written within 5 % of a bound of its parameter (a pydantic Field's
  ``gt``/``ge``/``lt``/``le``, relative to the bound: bounds of 0 are left out).
- ``never-true``, ``never-ticked`` (from runs' coverage, ``--assignment``): a condition that was never
  true, nodes that never ran.

Example::

    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> (folder / "m.yaml").write_text('''
    ... maze: arena
    ... start: [0.45, 0.45, 0]
    ... tree:
    ...   selector:
    ...     - Stop
    ...     - MoveDistance: {distance: 10cm}
    ... ''') and None
    >>> [finding] = lint_mission(folder / "m.yaml")
    >>> finding.line, finding.rule, finding.message
    (7, 'unreachable', "'MoveDistance' never runs: 'Stop' before it in selector 'selector' always succeeds")
    >>> finding.hint
    'a selector tries its next child only when one fails: put the child that always succeeds last'
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

from thymio_bt.analysis.tree_rules import Finding, TreeRules, condition_names, finding_at, is_condition
from thymio_bt.inputs.fields import within_sensor_range
from thymio_bt.inputs.yamlio import MarkedDict
from thymio_bt.plan.model import Mission, NodePlan
from thymio_bt.robot.model import robot_model

#: the rule ids, with what each finds (docs/lint.md has an example of each)
RULES = {
    "unreachable": "a child that can never run",
    "reactive-restart": "a reactive composite that starts a long action again at every tick",
    "forever": "a repeat: forever with no way out",
    "checked-once": "a sequence that checks the way is clear once, then drives farther",
    "unused-subtree": "a subtree (or an included file) that no tree uses",
    "unused-parameter": "a parameter that no $name refers to",
    "edge-of-range": "a value within 5 % of a bound of its parameter",
    "never-true": "a condition never true in any run (--assignment)",
    "never-ticked": "nodes that never ran in any run (--assignment)",
}

_REFERENCE = re.compile(r"\$([A-Za-z_]\w*)")
#: how close to a bound a value is at the edge of its range, relative to the bound
EDGE = 0.05


def lint_mission(path: str | Path, run_plugins: bool = False) -> list[Finding]:
    """The findings of the mission at ``path``, in file order; its plugins are read, not run, unless
    ``run_plugins`` (then the rules know their composites and decorators). A file that does not load
    raises its :class:`~thymio_bt.errors.UserError`."""
    from thymio_bt.inputs.yamlio import load_yaml
    from thymio_bt.mission.assemble import Assembler
    from thymio_bt.mission.loader import load_mission, resolve_mission

    mission = load_mission(path, run_plugins=run_plugins)
    source = resolve_mission(path)
    if source.suffix.lower() == ".xml":
        from thymio_bt.btcpp.xml_reader import read_xml_mission

        data = read_xml_mission(source)
    else:
        data = load_yaml(source)
    assembler = Assembler(run_plugins=run_plugins)
    assembly = assembler.assemble(source, data)
    findings = [*TreeRules(mission).findings(), *_edges(mission.tree, robot_model(mission.robot).range_max)]
    findings += _unused(mission, assembly, assembler.included_parameters)
    return sorted(set(findings), key=lambda f: (f.file != str(mission.file), f.file, f.line, f.rule, f.message))


def _uses(node: NodePlan, use: str = "") -> Iterator[tuple[NodePlan, str]]:
    """Every node below ``node`` with the innermost use of a subtree it is in (``" in 'NAME'"``, or "")."""
    use = f" in '{node.name}'" if node.subtree else use
    yield node, use
    for child in node.children:
        yield from _uses(child, use)


def _edges(tree: NodePlan, sensor_range: float) -> Iterator[Finding]:
    """``edge-of-range``: each value written within :data:`EDGE` of a bound of its parameter (in a
    subtree, the use whose value it is is named); a sensed length's upper bound is ``sensor_range``,
    the mission's robot's."""
    for node, use in _uses(tree):
        params = node.params
        if params is None:
            continue
        fields = type(params).model_fields
        for name in sorted(params.model_fields_set - set(node.blackboard_refs)):
            value, field = getattr(params, name, None), fields.get(name)
            if field is None or isinstance(value, bool) or not isinstance(value, int | float):
                continue
            for bound, sign in _bounds(field, sensor_range):
                if bound and abs(value - bound) <= EDGE * abs(bound):
                    yield finding_at(
                        node,
                        "edge-of-range",
                        f"{name} of '{node.name}'{use} is {value:g}, at the edge of its range ({sign} {bound:g})",
                        f"near a limit a small change makes it invalid or useless; see thymio-bt behaviours "
                        f"{node.behaviour or node.kind}",
                    )


def _bounds(field: Any, sensor_range: float) -> Iterator[tuple[float, str]]:
    """The numeric bounds of a pydantic field, with their sign (``> 0``, ``<= 0.2``...); a sensed
    length's upper bound is the ``sensor_range`` of the robot, when that is nearer."""
    sensed = within_sensor_range(field)
    for meta in field.metadata:
        for attr, sign in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
            bound = getattr(meta, attr, None)
            if isinstance(bound, int | float) and not isinstance(bound, bool):
                yield (min(float(bound), sensor_range) if sensed and sign == "<=" else float(bound)), sign


def _unused(mission: Mission, assembly: Any, included: list[tuple[MarkedDict, str]]) -> Iterator[Finding]:
    """``unused-subtree`` and ``unused-parameter``: what the mission and its includes define and
    nothing uses."""
    file = str(mission.file)
    used = {node.subtree for node in mission.tree.walk() if node.subtree}
    defined = assembly.data.get("subtrees") if isinstance(assembly.data, MarkedDict) else None
    marks = defined.marks if isinstance(defined, MarkedDict) else {}
    for name, sub in assembly.subtrees.items():
        if name not in used and sub.where[0] == file:
            yield Finding(
                file,
                marks.get(name, sub.where[1:])[0],
                "unused-subtree",
                f"subtree '{name}' is never used",
                f"use it in the tree ({name}: {{...}}) or remove it",
            )
    for other in sorted({sub.where[0] for sub in assembly.subtrees.values()} - {file}):
        mine = [n for n, sub in assembly.subtrees.items() if sub.where[0] == other]
        if not any(n in used for n in mine):
            yield Finding(
                file,
                _include_line(assembly.data),
                "unused-subtree",
                f"none of the subtrees of the included {Path(other).name} ({', '.join(mine)}) is used",
                "use one of them in the tree, or remove the include",
            )
    yield from _unused_parameters(assembly, [*included, (assembly.data, file)])


def _include_line(data: Any) -> int:
    """The line of the mission's ``include:``."""
    return data.marks.get("include", data.mark)[0] if isinstance(data, MarkedDict) else 0


def _unused_parameters(assembly: Any, sources: list[tuple[Any, str]]) -> Iterator[Finding]:
    """The mission's parameters (``sources``: each file's data) and the subtrees' that no ``$name``
    refers to. A ``$name`` inside a subtree's tree is its own parameter when it declares one."""
    mission_refs: set[str] = set()
    subtree_refs: dict[str, set[str]] = {}
    for data, _ in sources:
        if isinstance(data, MarkedDict):
            mission_refs |= _references({k: v for k, v in data.items() if k != "subtrees"})
    for name, sub in assembly.subtrees.items():
        declared = _declared(sub.body)
        mission_refs |= _references(declared)
        inside = _references({k: v for k, v in sub.body.items() if k != "parameters"})
        subtree_refs[name] = inside & set(declared)
        mission_refs |= inside - set(declared)
    for data, file in sources:
        params = data.get("parameters") if isinstance(data, MarkedDict) else None
        if not isinstance(params, MarkedDict):
            continue
        for name in params:
            if name not in mission_refs:
                yield Finding(
                    file,
                    params.marks.get(name, params.mark)[0],
                    "unused-parameter",
                    f"parameter '{name}' is never used",
                    f"refer to it as ${name} in the tree, or remove it",
                )
    for name, sub in assembly.subtrees.items():
        declared = _declared(sub.body)
        for param in declared:
            if param not in subtree_refs[name]:
                yield Finding(
                    sub.where[0],
                    declared.marks.get(param, declared.mark)[0],
                    "unused-parameter",
                    f"parameter '{param}' of subtree '{name}' is never used in its tree",
                    f"refer to it as ${param} in the subtree's tree, or remove it",
                )


def _declared(body: Any) -> MarkedDict:
    """A subtree's ``parameters:`` (empty when it has none or they are not a mapping)."""
    declared = body.get("parameters") if isinstance(body, MarkedDict) else None
    return declared if isinstance(declared, MarkedDict) else MarkedDict()


def _references(value: Any) -> set[str]:
    """Every parameter name a ``$name`` in the strings of ``value`` (and what it holds) refers to."""
    if isinstance(value, str):
        return set(_REFERENCE.findall(value))
    if isinstance(value, Mapping):
        return set().union(*(_references(v) for v in value.values()))
    if isinstance(value, Iterable) and not isinstance(value, bytes):
        return set().union(*(_references(v) for v in value))
    return set()


def coverage_findings(mission: Mission, coverage: Mapping[str, Any]) -> list[Finding]:
    """``never-true`` and ``never-ticked`` from a coverage JSON of the mission's runs: each condition
    that ran but was never true, and the topmost node of each part of the tree that never ran."""
    conditions = condition_names(mission.registry)
    runs = coverage.get("runs", 0)
    findings = []
    silent: list[str] = []  # the never-ticked nodes reported so far: their subtrees are said with them
    for node in coverage["nodes"]:
        file, _, line = str(node["where"]).rpartition(":")
        if not node["ticks"]:
            if any(node["path"].startswith(p + "/") for p in silent):
                continue
            silent.append(node["path"])
            below = "" if node["kind"] == "behaviour" else " (nor anything below it)"
            findings.append(
                Finding(
                    file,
                    int(line or 0),
                    "never-ticked",
                    f"'{node['name']}' never ran in {runs} run{'s' * (runs != 1)}{below}",
                    "no variant of the assignment needs it: check the conditions that lead to it, or remove it",
                )
            )
        elif node["behaviour"] in conditions and not node["success"]:
            findings.append(
                Finding(
                    file,
                    int(line or 0),
                    "never-true",
                    f"condition '{node['name']}' was never true in {runs} run{'s' * (runs != 1)} "
                    f"({node['ticks']} checks)",
                    f"what it guards never ran; check its parameters (thymio-bt behaviours {node['behaviour']})",
                )
            )
    return findings


__all__ = ["EDGE", "RULES", "Finding", "condition_names", "coverage_findings", "is_condition", "lint_mission"]
