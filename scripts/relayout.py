"""Move thymio_bt's modules to the layout of docs/architecture.md and rewrite every reference to them.

Re-appliable: run on a tree where some modules already moved and some files (new ones, say, from a
branch merged after the move) still name the old modules, it moves what is left and rewrites what is
left, and changes nothing the second time. Run from anywhere: ``python scripts/relayout.py``.

What it does, in order:

1. ``git mv`` each module of :data:`MOVES` whose old file is still there (new packages get an
   ``__init__.py`` from :data:`PACKAGES` first);
2. in every tracked text file (Python, Markdown, YAML, TOML, JSON, HTML, JS; not this script,
   ``_moved.py`` or ``CHANGELOG.md``, which name the old modules on purpose), rewrites the old names:
   dotted (``thymio_bt.mission.btcpp``, ``"thymio_bt.mission.btcpp:attr"``, ``mock.patch`` targets),
   as paths (``thymio_bt/mission/btcpp.py``, ``mission/btcpp.py``), ``from thymio_bt.behaviours
   import btcpp_nodes as bn``; and the names of :data:`NAMES` (a class or constant that moved to
   another module) in ``from M import NAME`` lines (a dotted ``M.NAME`` stays: M still has it);
3. puts every move in ``thymio_bt/_moved.py``'s table (old names still import, with a warning);
4. sorts and formats the Python files it changed with ruff, when ruff is installed.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: old module -> new module (dotted, under thymio_bt)
MOVES: dict[str, str] = {
    # BehaviorTree.CPP compatibility in one package: its nodes and script language (below the plan)...
    "behaviours.btcpp_nodes": "btcpp.runtime.nodes",
    "behaviours.btcpp_control": "btcpp.runtime.control",
    "behaviours.btcpp_decorators": "btcpp.runtime.decorators",
    "behaviours.btcpp_scripted": "btcpp.runtime.scripted",
    "behaviours.btcpp_script": "btcpp.runtime.script",
    "behaviours.btcpp_values": "btcpp.runtime.values",
    # ... and its XML in and out, its log and its monitor (above the plan)
    "mission.btcpp": "btcpp.export",
    "mission.xml_reader": "btcpp.xml_reader",
    "mission.xml_tree": "btcpp.xml_tree",
    "mission.xml_scope": "btcpp.xml_scope",
    "logs.btlog": "btcpp.btlog",
    "viz.groot2": "btcpp.groot2",
    # thymio-bt's control-flow nodes apart from the robot behaviours, with names that do not blur
    "behaviours.control_node": "behaviours.flow.node",
    "behaviours.control": "behaviours.flow.primitives",
    "behaviours.composites": "behaviours.flow.composites",
    "behaviours.decorators": "behaviours.flow.decorators",
    "behaviours.ticking": "behaviours.flow.ticking",
    # helpers that are no nodes, where what they are lives
    "behaviours.cellmap": "maze.cellmap",
    "behaviours.corridor": "robot.corridor",
    "behaviours.pid": "robot.pid",
    # the analyses of a mission apart from its loader
    "mission.lint": "analysis.lint",
    "mission.tree_rules": "analysis.tree_rules",
    "mission.schema": "analysis.schema",
    "mission.node_docs": "analysis.node_docs",
    # a mission as data, below the loader and the BT.CPP XML that both make one
    "mission.plan": "plan.model",
    "mission.registry": "plan.registry",
    "mission.unrun_plugins": "plan.unrun_plugins",
    # the verdict on a run beside the run (what a mission expects is a mission's data: NAMES)
    "mission.expect": "run.verdict",
    # names that misled
    "mission.checker": "mission.pass_base",
    "logs.records": "logs.entries",
    "robot.calibration": "sensor_tables",
    "cli.calibration": "cli.calibrating",
}

#: (module, name) -> the module that now defines the name (its old module still imports it)
NAMES: dict[tuple[str, str], str] = {
    ("run.runner", "StopRun"): "errors",
    ("mission.planner", "MAX_DEPTH"): "plan.model",
    ("mission.planner", "MAX_NODES"): "plan.model",
    **{
        ("mission.expect", name): "plan.expect"
        for name in ("Expect", "GoalRegion", "GapExpectation", "DeadEnd", "Duration")
    },
}

#: new package -> the docstring of its __init__.py
PACKAGES: dict[str, str] = {
    "btcpp": "BehaviorTree.CPP 4 compatibility: XML in and out, the .btlog, the Groot2 monitor, and (in\n"
    "``runtime``) BT.CPP's built-in nodes and script language, tick for tick.",
    "btcpp.runtime": "BT.CPP 4's built-in nodes and script language, tick for tick, as registered node kinds.",
    "behaviours.flow": "thymio-bt's control-flow nodes: composites, decorators, their contract, and ticking a tree.",
    "analysis": "What is said of a mission without running it: the lint, the JSON Schema, the node help.",
    "plan": "A mission as data (no py_trees object, no robot), and the node kinds it may name.",
}

SUFFIXES = {".py", ".md", ".yml", ".yaml", ".toml", ".json", ".html", ".js", ".cfg", ".ini", ".txt", ".sh"}
SKIP = {"scripts/relayout.py", "thymio_bt/_moved.py", "CHANGELOG.md"}


def _path(module: str) -> Path:
    """The file of ``module`` (dotted, under thymio_bt), a package's ``__init__.py`` if it is one."""
    base = ROOT / "thymio_bt" / Path(*module.split("."))
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, check=True, capture_output=True, text=True).stdout


def move_files() -> list[str]:
    """``git mv`` what is left to move; the moves made."""
    done = []
    for package, doc in PACKAGES.items():
        init = ROOT / "thymio_bt" / Path(*package.split(".")) / "__init__.py"
        if not init.exists():
            init.parent.mkdir(parents=True, exist_ok=True)
            init.write_text(f'"""{doc}"""\n')
            _git("add", str(init))
    for old, new in MOVES.items():
        source = ROOT / "thymio_bt" / Path(*old.split(".")).with_suffix(".py")
        target = ROOT / "thymio_bt" / Path(*new.split(".")).with_suffix(".py")
        if not source.exists():
            continue
        if target.exists():
            raise SystemExit(f"both {source} and {target} exist: merge them by hand, then re-run")
        target.parent.mkdir(parents=True, exist_ok=True)
        _git("mv", str(source.relative_to(ROOT)), str(target.relative_to(ROOT)))
        done.append(f"{old} -> {new}")
    return done


def _patterns() -> list[tuple[re.Pattern[str], str]]:
    """Regexes for the old names (longest first, so that a name is never rewritten by a prefix of it)."""
    rules = []  # a moved name's dotted references stay: its old module still has it (mock.patch targets it there)
    for old, new in sorted(MOVES.items(), key=lambda kv: -len(kv[0])):
        dotted, path = old, old.replace(".", "/")
        new_path = new.replace(".", "/")
        rules.append((re.compile(rf"(?<![\w.])thymio_bt\.{re.escape(dotted)}(?!\w)"), f"thymio_bt.{new}"))
        rules.append((re.compile(rf"(?<![\w/])thymio_bt/{re.escape(path)}\.py"), f"thymio_bt/{new_path}.py"))
        rules.append((re.compile(rf"(?<![\w/.]){re.escape(path)}\.py"), f"{new_path}.py"))
    return rules


def _module_of_alias(node: ast.ImportFrom, alias: ast.alias) -> str | None:
    """``from thymio_bt.P import M``: the old module ``P.M`` it imports, if ``P.M`` moved."""
    if node.level or not node.module or not node.module.startswith("thymio_bt."):
        return None
    full = f"{node.module.removeprefix('thymio_bt.')}.{alias.name}"
    return full if full in MOVES else None


def _rewrite_imports(text: str) -> str:
    """``from thymio_bt.P import M`` of a moved module ``P.M``, and ``from M import NAME`` of a moved
    name, rewritten as imports from the new places (one statement per module, ruff sorts them)."""
    try:
        tree = ast.parse(text)
    except SyntaxError:
        return text
    lines = text.splitlines(keepends=True)
    edits = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ImportFrom) or node.level or not (node.module or "").startswith("thymio_bt"):
            continue
        module = (node.module or "").removeprefix("thymio_bt.")
        groups: dict[str, list[str]] = {}
        changed = False
        for alias in node.names:
            spelled = alias.name + (f" as {alias.asname}" if alias.asname else "")
            old = _module_of_alias(node, alias)
            moved_name = NAMES.get((module, alias.name))
            if old is not None:
                new_package, _, new_name = MOVES[old].rpartition(".")
                bound = alias.asname or alias.name
                spelled = new_name if bound == new_name else f"{new_name} as {bound}"
                groups.setdefault(new_package, []).append(spelled)
                changed = True
            elif moved_name is not None:
                groups.setdefault(moved_name, []).append(spelled)
                changed = True
            else:
                groups.setdefault(module, []).append(spelled)
        if not changed:
            continue
        indent = " " * node.col_offset
        last = lines[node.end_lineno - 1]
        tail = last[node.end_col_offset :].rstrip("\n")  # a comment after the statement
        statements = [
            f"{indent}from {'thymio_bt.' + m if m else 'thymio_bt'} import {', '.join(names)}"
            for m, names in groups.items()
        ]
        statements[0] += tail
        edits.append((node.lineno - 1, node.end_lineno, "\n".join(statements) + "\n"))
    for start, end, replacement in sorted(edits, reverse=True):
        lines[start:end] = [replacement]
    return "".join(lines)


def rewrite_references() -> list[str]:
    """Rewrite the old names in every tracked text file; the files changed."""
    rules = _patterns()
    changed = []
    for name in _git("ls-files", "-co", "--exclude-standard").splitlines():
        path = ROOT / name
        if name in SKIP or path.suffix not in SUFFIXES or not path.is_file():
            continue
        try:
            text = path.read_text()
        except UnicodeDecodeError:
            continue
        new = _rewrite_imports(text) if path.suffix == ".py" else text
        for pattern, replacement in rules:
            new = pattern.sub(replacement, new)
        if new != text:
            path.write_text(new)
            changed.append(name)
    return changed


def update_moved_table() -> bool:
    """Every move in ``_moved.py``'s :data:`MOVED` table, and no entry pointing at a module that moved."""
    path = ROOT / "thymio_bt" / "_moved.py"
    text = path.read_text()
    entry = re.compile(r'^(\s+)"([\w.]+)": "([\w.]+)",\n', re.M)
    entries = {m.group(2): m.group(3) for m in entry.finditer(text)}
    indent = next((m.group(1) for m in entry.finditer(text)), "        ")

    def resolve(name: str) -> str:
        for old, new in sorted(MOVES.items(), key=lambda kv: -len(kv[0])):
            if name == old or name.startswith(old + "."):
                return new + name[len(old) :]
        return name

    def fixed(m: re.Match[str]) -> str:
        if _path(m.group(2)).exists():  # the old name is a module again (the btcpp package): no alias
            return ""
        return f'{m.group(1)}"{m.group(2)}": "{resolve(m.group(3))}",\n'

    new_text = entry.sub(fixed, text)
    missing = [old for old in MOVES if old not in entries]
    if missing:
        end = new_text.index("    }.items()")
        added = "".join(f'{indent}"{old}": "{MOVES[old]}",\n' for old in missing)
        new_text = new_text[:end] + added + new_text[end:]
    if new_text != text:
        path.write_text(new_text)
    return new_text != text


def format_python(files: list[str]) -> None:
    """Sort the imports of the changed Python files and format them, if ruff is there."""
    python = [f for f in files if f.endswith(".py")]
    if not python:
        return
    ruff = [sys.executable, "-m", "ruff"]
    try:
        subprocess.run([*ruff, "check", "--select", "I", "--fix", "-q", *python], cwd=ROOT, check=False)
        subprocess.run([*ruff, "format", "-q", *python], cwd=ROOT, check=False)
    except OSError:
        print("ruff not found: sort and format the changed files yourself", file=sys.stderr)


def main() -> None:
    moved = move_files()
    changed = rewrite_references()
    if update_moved_table():
        changed.append("thymio_bt/_moved.py")
    format_python(changed)
    print(f"moved {len(moved)} modules, rewrote {len(changed)} files")
    for line in moved:
        print("  moved", line)
    for name in changed:
        print("  rewrote", name)


if __name__ == "__main__":
    main()
