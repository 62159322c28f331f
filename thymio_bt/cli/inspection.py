"""The commands that look at missions and the installation without running anything.

``validate`` checks mission and maze files, ``tree`` prints or draws a mission's tree (or writes it as
BehaviorTree.CPP XML), ``behaviours`` documents the nodes, ``backends`` lists the backends and robot
models, ``schema`` prints the JSON Schema of mission files. None of them loads the physics engine.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> from thymio_bt.maze import resolve_maze
    >>> print(CliRunner().invoke(main, ["validate", str(resolve_maze("two_parts_maze"))]).output, end="")
    ok: .../two_parts_maze.yaml (maze: 21 walls, 0 obstacles, spawns part1, part2, bonus)
    >>> result = CliRunner().invoke(main, ["tree", "maze_part1_2"])
    >>> result.exit_code, result.output.splitlines()[:2]
    (0, ['{-} course', '    --> part 1'])
"""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from thymio_bt.cli.app import fail, main, not_both, parse_overrides, path_option
from thymio_bt.errors import UserError
from thymio_bt.outputs import STDOUT, Output

if TYPE_CHECKING:
    from thymio_bt.errors import Problem
    from thymio_bt.maze import Maze
    from thymio_bt.mission import Registry


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Check missions with these overrides.")
@click.option(
    "--robot",
    default=None,
    metavar="NAME",
    help="Check missions for this robot (course, enki, real or a profile FILE.yaml), as 'run --robot' "
    "would run them: its sensor range bounds stop distances, its size the spawn poses.",
)
@click.option(
    "--plugins",
    is_flag=True,
    help="Import the missions' plugins to check their nodes' parameters too (runs their code).",
)
def validate(files: tuple[Path, ...], sets: tuple[str, ...], robot: str | None, plugins: bool) -> None:
    """Check mission FILES (and the mazes they name), maze files or assignment files without running
    anything (not even the missions' plugins, unless --plugins)."""
    from thymio_bt.mission.settings import ROBOT_OPTION

    bad = 0
    for path in files:
        try:
            overrides = parse_overrides(sets)
            if robot is not None:
                overrides[ROBOT_OPTION] = robot  # as run's --robot: its problems said at --robot
            summary, note = _check_file(path, overrides, plugins)
            click.echo(f"ok: {path} ({summary})" + (f"; {note}" if note else ""))
        except UserError as exc:
            bad += 1
            for problem in exc.problems:
                click.echo(f"error: {problem}", err=True)
    sys.exit(2 if bad else 0)


def _check_file(path: Path, overrides: dict[str, str], plugins: bool = False) -> tuple[str, str]:
    """Validate one mission or maze file (a maze has ``walls:`` or ``grid:`` and no ``tree:``); what it
    holds, and what was not checked ("" when everything was)."""
    from thymio_bt.inputs.yamlio import load_yaml

    micromouse = path.suffix.lower() == ".txt"  # a micromouse contest maze
    data = None if path.suffix.lower() == ".xml" or micromouse else load_yaml(path)  # .xml: a BT.CPP mission
    if micromouse or isinstance(data, dict) and "tree" not in data and ("walls" in data or "grid" in data):
        return _check_maze(path, data), ""
    if isinstance(data, dict) and "tree" not in data and "criteria" in data:
        return _check_assignment(path), ""
    return _check_mission(path, overrides, plugins)


def _check_assignment(path: Path) -> str:
    """Validate an assignment file of ``thymio-bt grade``, its variants' worlds made."""
    import tempfile

    from thymio_bt.grade.worlds import load_worlds

    with tempfile.TemporaryDirectory() as folder:
        assignment, _ = load_worlds(path, Path(folder))
    runs = sum(len(v.seed_list) for v in assignment.variants)
    return (
        f"assignment: {len(assignment.variants)} variants ({runs} runs a submission), "
        f"{len(assignment.criteria)} criteria, {assignment.max_points:g} points"
    )


def _check_maze(path: Path, data: Any) -> str:
    """Validate the maze file ``path`` (``data``: its YAML, ``None`` for a micromouse maze), spawns included."""
    from thymio_bt.inputs.yamlio import MarkedDict
    from thymio_bt.maze import load_maze

    maze = load_maze(path)
    spawns = data.get("spawns") if isinstance(data, dict) and "grid" not in data else None
    problems = _spawn_problems(path, maze, spawns.marks if isinstance(spawns, MarkedDict) else {})
    if problems:
        raise UserError(problems)
    goal = f", goal {len(maze.goal)} cell{'s' * (len(maze.goal) != 1)}" if maze.goal else ""
    return (
        f"maze: {len(maze.walls)} walls, {len(maze.obstacles)} obstacles, "
        f"spawns {', '.join(maze.spawns) or 'none'}{goal}"
    )


def _spawn_problems(path: Path, maze: Maze, marks: dict[str, tuple[int, int]]) -> list[Problem]:
    """The spawns of ``maze`` where the course's robot cannot stand; ``marks``: where each is in the file."""
    from thymio_bt.errors import Problem
    from thymio_bt.robot.model import COURSE
    from thymio_bt.robot.placement import placement_problem

    problems = []
    for name, spawn in maze.spawns.items():
        if why := placement_problem(maze, COURSE, spawn.pose()):
            line, column = marks.get(name, (0, 0))
            problems.append(
                Problem(
                    f"spawn '{name}' is impossible: {why}",
                    str(path),
                    line,
                    column,
                    f"spawns.{name}",
                    "move it into a free cell, away from the walls",
                )
            )
    return problems


def _check_mission(path: Path, overrides: dict[str, str], plugins: bool) -> tuple[str, str]:
    """Validate the mission file ``path``; its node count and maze, and the plugin nodes left unchecked."""
    from thymio_bt.behaviours.base import UnrunPlugin
    from thymio_bt.mission import load_mission

    spec = load_mission(path, overrides, run_plugins=plugins)  # checks the start pose against the maze too
    nodes = sum(1 for _ in spec.tree.walk())
    unchecked = [
        (n, plugin)
        for n in spec.tree.walk()
        if n.behaviour and issubclass(plugin := spec.registry[n.behaviour], UnrunPlugin)
    ]
    summary = f"{nodes} node{'s' * (nodes != 1)}, maze {spec.maze.name}"
    if not unchecked:
        return summary, ""
    # 'ok' must not read as 'run will accept it': a misspelt parameter of a plugin node is only found
    # once its plugin is imported, so say which nodes were not checked and the command that checks them
    shown = ", ".join(f"{n.behaviour} (line {n.where[1]})" for n, _ in unchecked[:5]) + ", ..." * (len(unchecked) > 5)
    # a plugin whose source says its parameters' names had them checked, not their values
    names_read = all(plugin.Params.model_config.get("extra") == "forbid" for _, plugin in unchecked)
    what = "parameter values" if names_read else "parameters"
    return summary, (
        f"not checked: the {what} of {len(unchecked)} plugin node{'s' * (len(unchecked) != 1)}, {shown}: "
        f"their plugins were read, not run\n  check them with: thymio-bt validate --plugins {path} "
        "(it imports the plugins: runs their code)"
    )


@main.command()
@click.argument("mission", type=click.Path(path_type=Path))
@click.option("--dot", "formats", flag_value="dot", multiple=True, help="Write a Graphviz .dot file.")
@click.option("--svg", "formats", flag_value="svg", multiple=True, help="Write an SVG (needs Graphviz's dot program).")
@click.option("--png", "formats", flag_value="png", multiple=True, help="Write a PNG (needs Graphviz's dot program).")
@path_option(
    "--output",
    "-o",
    help="File to write (- = standard output); its suffix picks the format when no flag does. "
    "Default with a format flag: the MISSION file's name with that suffix (missions/square.yaml: square.dot), "
    "in the current folder; a default name never replaces a file (the command is refused: give -o).",
)
@path_option(
    "--btcpp",
    metavar="OUT.xml",
    help="Write the tree as BehaviorTree.CPP v4 XML (Groot2 opens it) instead of a drawing.",
)
@path_option(
    "--coverage",
    "coverage_report",
    metavar="REPORT.json",
    help="Show the tree with the coverage that REPORT holds: the JSON of 'run --coverage --report' or "
    "'sweep --coverage --out' for this mission.",
)
@click.option("--plugins", is_flag=True, help="Import the mission's plugins (runs their code; default: read only).")
def tree(
    mission: Path,
    formats: tuple[str, ...],
    output: Path | None,
    btcpp: Path | None,
    coverage_report: Path | None,
    plugins: bool,
) -> None:
    """Print the tree of MISSION; write it as .dot/.svg/.png or BT.CPP XML when asked.

    With --coverage, the tree shows how often each node ran and with what result, from a report
    written earlier (no run now).
    """
    try:
        kinds = sorted(set(formats))
        if len(kinds) > 1:
            not_both(f"--{kinds[0]}", f"--{kinds[1]}", True, "one drawing at a time: run tree once per format")
        fmt = kinds[0] if kinds else None
        if btcpp is not None:
            if coverage_report is not None:
                raise UserError("--btcpp writes the tree alone (hint: drop --coverage, or --btcpp)")
            _write_btcpp(mission, btcpp, plugins)
        else:
            _draw_tree(mission, fmt, output, plugins, coverage_report)
    except UserError as exc:
        fail(exc)


def _write_btcpp(mission: Path, btcpp: Path, plugins: bool) -> None:
    """``tree --btcpp``: the mission's tree as BehaviorTree.CPP v4 XML."""
    from thymio_bt.btcpp.export import mission_xml
    from thymio_bt.mission import load_mission

    out = Output(btcpp, "--btcpp")
    out.write_text(mission_xml(load_mission(mission, run_plugins=plugins), btcpp))
    if not out.is_stdout:
        click.echo(f"wrote {out}", err=True)


def _draw_tree(mission: Path, fmt: str | None, output: Path | None, plugins: bool, report: Path | None) -> None:
    """``tree``: print the tree and, with a format (a flag, or ``output``'s suffix), write it as
    .dot/.svg/.png; with a ``report``, the tree with the coverage it holds."""
    from thymio_bt.mission import load_mission
    from thymio_bt.viz.graph import coverage_dot, plan_dot, write_graph
    from thymio_bt.viz.terminal import coverage_text, tree_text

    if fmt is None and output is not None:
        fmt = output.suffix.lower().lstrip(".")
        if fmt not in ("dot", "svg", "png"):
            raise UserError(
                f"--output {output}: cannot tell the format from '{output.suffix or 'no extension'}' "
                f"(hint: end the name with .dot, .svg or .png, or add --dot/--svg/--png)"
            )
    coverage, conditions, registry = (
        _coverage_of(report, mission, plugins) if report is not None else (None, set(), None)
    )
    if coverage is None:
        loaded = load_mission(mission, run_plugins=plugins)
        text, source = tree_text(loaded), lambda: plan_dot(loaded.tree, loaded.registry)
    else:
        text, source = (
            coverage_text(coverage, conditions, registry),
            lambda: coverage_dot(coverage, conditions, registry),
        )
    if fmt is None:
        click.echo(text)
        return
    if output is None:  # a name of our choosing: it never replaces a file (the --plot just drawn, say)
        out = Output.by_default(Path(mission.stem).with_suffix(f".{fmt}"), "--output")
    else:
        out = Output(output, "--output")
    if not out.is_stdout:
        click.echo(text)
    write_graph(source(), out, fmt, f"thymio-bt tree {mission} --dot -o {Path(str(out)).stem}.dot")
    if not out.is_stdout:
        click.echo(f"wrote {out}", err=True)


def _coverage_of(report: Path, mission: Path, plugins: bool) -> tuple[dict[str, Any], set[str], Any]:
    """The coverage ``report`` holds, checked to be of ``mission``'s tree, the mission's condition
    names and its node registry."""
    from thymio_bt.analysis.tree_rules import condition_names
    from thymio_bt.inputs.reading import read_text
    from thymio_bt.mission import load_mission
    from thymio_bt.run.coverage import plan_paths

    text = read_text(report, "report")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise UserError(f"{report}:{exc.lineno}:{exc.colno}: not JSON: {exc.msg}") from None
    coverage = data.get("coverage") if isinstance(data, dict) else None
    if not (isinstance(coverage, dict) and isinstance(coverage.get("nodes"), list) and "runs" in coverage):
        raise UserError(
            f"{report}: holds no tree coverage (hint: write one with 'thymio-bt run {mission} --coverage "
            f"--report {report.name}' or 'thymio-bt sweep {mission} --coverage --out {report.name}')"
        )
    spec = load_mission(mission, run_plugins=plugins)
    ours = [path for _, path, _ in plan_paths(spec.tree)]
    theirs = [node.get("path") if isinstance(node, dict) else None for node in coverage["nodes"]]
    if ours != theirs:
        pairs = zip(ours, theirs, strict=False)  # the first difference, if the shorter list has one
        differs = next((f"'{a}' here, '{b}' there" for a, b in pairs if a != b), "a node more or less")
        raise UserError(
            f"{report}: its coverage is of another tree than {mission}'s ({differs}) "
            "(hint: run the mission as it is now with --coverage)"
        )
    return coverage, condition_names(spec.registry), spec.registry


@main.command()
@path_option("--output", "-o", help="File to write (default: standard output).")
@path_option("--mission", help="Include the behaviours of this mission's plugins (runs their code).")
def palette(output: Path | None, mission: Path | None) -> None:
    """Write the Groot2 palette: a TreeNodesModel of every robot behaviour and condition, to import in
    Groot2 beside its own built-ins (docs/btcpp.md)."""
    from thymio_bt.btcpp.export import palette_xml

    try:
        out = Output(output if output is not None else Path("-"), "--output")
        out.write_text(palette_xml(_registry(mission)))
    except UserError as exc:
        fail(exc)
    if not out.is_stdout:
        click.echo(f"wrote {out}", err=True)


def _registry(mission: Path | None) -> Registry:
    """The node registry: the installed nodes, plus the ``plugins:`` of ``mission`` when one is given
    (their code runs: that is what naming the mission asks for)."""
    from thymio_bt.mission import default_registry, load_mission

    return default_registry() if mission is None else load_mission(mission).registry


@main.command()
@click.argument("name", required=False)
@path_option("--mission", help="Include the behaviours of this mission's plugins (runs their code).")
def behaviours(name: str | None, mission: Path | None) -> None:
    """List the behaviours, or document one (its parameters, units, defaults, ranges)."""
    from thymio_bt.analysis.node_docs import behaviour_help, behaviour_list, parameter_rows

    try:
        registry = _registry(mission)
    except UserError as exc:
        fail(exc)
    if name is None:
        click.echo(behaviour_list(registry))
        return
    if name not in registry:
        from thymio_bt.errors import did_you_mean

        fail(UserError(f"no behaviour named '{name}' (hint: {did_you_mean(name, registry)})"))
    click.echo(fit_help(behaviour_help(registry[name]), parameter_rows(registry[name]), _terminal_width()))


def _terminal_width() -> int:
    """The terminal's width in columns (``COLUMNS`` when set; 80 when not a terminal), at least 60."""
    import shutil

    return max(60, shutil.get_terminal_size().columns)


def fit_help(text: str, rows: Sequence[tuple[str, ...]], width: int) -> str:
    r"""A node's help (:func:`~thymio_bt.analysis.node_docs.behaviour_help`) fitted to ``width``
    columns: its parameter table (``rows``) laid out again with the type and description wrapped in
    their columns, its prose wrapped as paragraphs; the indented examples as they are.

    >>> rows = [("speed", "float", "m/s", "0.1", "> 0 <= 0.2", "cruise speed, until the wall comes in range")]
    >>> text = "Move\n\nParameters:\n  (the table, one line per row)\n  speed ...\n\nValues accept units."
    >>> print(fit_help(text, rows, 72))
    Move
    <BLANKLINE>
    Parameters:
      parameter  type   unit  default  range       description
      speed      float  m/s   0.1      > 0 <= 0.2  cruise speed, until the wall
                                                   comes in range
    <BLANKLINE>
    Values accept units.
    >>> print(fit_help(text, rows, 50))  # too narrow for the table: a block per parameter
    Move
    <BLANKLINE>
    Parameters:
      speed: float, m/s, default 0.1, > 0 <= 0.2
          cruise speed, until the wall comes in range
    <BLANKLINE>
    Values accept units.
    >>> print(fit_help("Drive until\nthe wall.\n\n    - MoveUntilWall: {}", [], 72))  # a paragraph, an example
    Drive until the wall.
    <BLANKLINE>
        - MoveUntilWall: {}
    """
    import textwrap

    lines = text.split("\n")
    if rows and "Parameters:" in lines:
        at = lines.index("Parameters:") + 1
        lines[at : at + 1 + len(rows)] = _table(rows, width)
    out: list[str] = []
    prose: list[str] = []  # the lines of the paragraph being read: a docstring's breaks are not the reader's
    for line in [*lines, ""]:
        if line and not line.startswith(" "):
            prose.append(line)
            continue
        if prose:
            out += textwrap.wrap(" ".join(prose), width)
            prose = []
        out.append(line)
    return "\n".join(out[:-1])


def _table(rows: Sequence[tuple[str, ...]], width: int) -> list[str]:
    """The parameter table in ``width`` columns: each cell wrapped in its column (the type and the
    default at most 20 wide, the description what is left), a row over as many lines as its cells
    need; where that leaves the description under 24 columns, one block per parameter instead."""
    import textwrap

    header = ("parameter", "type", "unit", "default", "range", "description")
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(6)]
    widths[1], widths[3] = min(widths[1], 20), min(widths[3], 20)
    widths[5] = width - 2 - sum(widths[:5]) - 2 * 5
    if widths[5] < 24:
        return _blocks(rows, width)
    out = []
    for row in [header, *rows]:
        cells = [textwrap.wrap(cell, w, break_on_hyphens=False) or [""] for cell, w in zip(row, widths, strict=True)]
        for i in range(max(len(c) for c in cells)):
            parts = [(c[i] if i < len(c) else "").ljust(w) for c, w in zip(cells, widths, strict=True)]
            out.append(("  " + "  ".join(parts)).rstrip())
    return out


def _blocks(rows: Sequence[tuple[str, ...]], width: int) -> list[str]:
    """The parameters one block each, for a narrow terminal: ``name: type, unit, default, range``,
    then the description indented, both wrapped to ``width``."""
    import textwrap

    out = []
    for name, kind, unit, default, limits, description in rows:
        facts = ", ".join(f for f in (kind, unit, f"default {default}" if default else "", limits) if f)
        out += textwrap.wrap(f"{name}: {facts}", width, initial_indent="  ", subsequent_indent="      ")
        out += textwrap.wrap(description, width, initial_indent="      ", subsequent_indent="      ")
    return out


@main.command("backends")
def backends_command() -> None:
    """List the backends (--backend NAME, with their --backend-opt settings) and robot models (--robot NAME)."""
    from thymio_bt.backends import backend_kinds
    from thymio_bt.robot.model import ROBOTS

    try:
        kinds = backend_kinds()
    except UserError as exc:
        fail(exc)
    click.echo("backends (--backend NAME --backend-opt KEY=VALUE):")
    for kind in kinds.values():
        click.echo(f"  {kind.name:10} {kind.summary}")
        for key, field in kind.options_model().model_fields.items():
            default = "" if field.default is None else f" [default {field.default}]"
            click.echo(f"  {'':10}   {key}: {field.description}{default}")
    click.echo("robot models (--robot NAME):")
    for model in ROBOTS.values():
        click.echo(f"  {model.name:10} {model.description}")
    click.echo(f"  {'FILE.yaml':10} a profile measured on your robot by 'thymio-bt calibrate'")


@main.command()
@path_option("--output", "-o", default=STDOUT, show_default=True, help="File to write (- = standard output).")
@path_option("--mission", help="Include the behaviours of this mission's plugins (runs their code).")
@click.option("--assignment", is_flag=True, help="The schema of assignment files (thymio-bt grade) instead.")
def schema(output: Path, mission: Path | None, assignment: bool) -> None:
    """Print the JSON Schema of mission files, or of assignment files (for editors with
    yaml-language-server)."""
    from thymio_bt.analysis.schema import mission_schema

    try:
        out = Output(output, "--output")
        if assignment:
            from thymio_bt.grade.assignment import assignment_schema

            out.write_text(json.dumps(assignment_schema(), indent=1) + "\n")
            return
        out.write_text(json.dumps(mission_schema(_registry(mission)), indent=1) + "\n")
    except UserError as exc:
        fail(exc)
