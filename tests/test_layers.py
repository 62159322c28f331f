"""The layers: docs/architecture.md's rooms import only the rooms below them (every import, those
inside functions and under ``if TYPE_CHECKING:`` too), no two modules import each other, the
mission language and the behaviours never load the physics engine, and no command pays at start-up
for libraries only some commands need."""

import ast
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    "modules, absent",
    [
        ("thymio_bt.mission, thymio_bt.behaviours", ("pymunk",)),
        ("thymio_bt.cli", ("pymunk", "py_trees", "pydantic", "matplotlib", "pygame", "numpy", "tdmclient")),
        ("thymio_bt.cli, thymio_bt.run.runner, thymio_bt.mission", ("matplotlib", "pygame", "numpy", "tdmclient")),
    ],
)
def test_imports_stay_in_their_layer(modules, absent):
    code = f"import sys, {modules}; print(','.join(m for m in {absent!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


@pytest.mark.parametrize(
    "args",
    [
        ["validate", f"{ROOT}/missions/maze_part1_2.yaml", f"{ROOT}/mazes/two_parts_maze.yaml"],
        ["tree", f"{ROOT}/missions/maze_bonus.yaml", "-o", "{tmp}/t.dot"],
        ["schema"],
        ["behaviours", "parallel"],
        ["backends"],
    ],
)
def test_commands_that_run_nothing_load_no_physics_engine(args, tmp_path):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    code = (
        "import sys\nfrom thymio_bt.cli import main\n"
        f"sys.argv = ['thymio-bt', *{args!r}]\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        "print('pymunk' in sys.modules, file=sys.stderr)\n"
        "print(sorted(m for m in sys.modules if m.startswith('thymio_bt.backends.')), file=sys.stderr)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    engine, backends = done.stderr.strip().splitlines()[-2:]
    assert engine == "False", args
    # a backend's package and its settings (``thymio-bt backends`` lists them), none of its code
    code_loaded = [m for m in ast.literal_eval(backends) if m.count(".") > 2 and not m.endswith(".options")]
    assert code_loaded == [], f"{args}: loads backend modules {code_loaded}"


#: what ``thymio-bt run`` of a plain mission has no use for, made lazy so that its start-up does not pay
#: for them (benchmarks/README.md, "Start-up of run"): other commands' modules and what they import
RUN_DOES_NOT_LOAD = (
    "asyncio",
    "thymio_bt.cli.sweeps",
    "thymio_bt.cli.grading",
    "thymio_bt.cli.inspection",
    "thymio_bt.grade",
    "thymio_bt.btcpp.export",
    "xml.etree.ElementTree",
    # node families the mission names none of: the registry imports a family when a node of it is named
    "thymio_bt.behaviours.mapping",
    "thymio_bt.behaviours.move_cells",
    "thymio_bt.behaviours.navigation",
    "thymio_bt.behaviours.places",
    "thymio_bt.btcpp.runtime.control",
    "thymio_bt.btcpp.runtime.scripted",
    "thymio_bt.maze.cellmap",
    # the other backends' settings, and the simulation's sensor models the course robot's metres need not
    "thymio_bt.backends.real",
    "thymio_bt.backends.playground",
    "thymio_bt.backends.ros2",
    "thymio_bt.backends.sim.cone",
    "thymio_bt.backends.sim.sensor_models",
    # a grid maze's reader, and a robot profile's models: the mission has a maze of walls and no robot:
    "thymio_bt.maze.grid",
    "thymio_bt.robot.profile",
    # the per-node counting of --coverage, and BT.CPP's node types it tells apart
    "thymio_bt.run.coverage",
    "thymio_bt.btcpp.runtime.nodes",
)


def test_run_loads_only_what_it_needs(tmp_path):
    code = (
        "import sys\nfrom thymio_bt.cli import main\n"
        f"sys.argv = ['thymio-bt', 'run', {str(ROOT / 'missions/maze_part1_2.yaml')!r}, '--quiet']\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        "import gc\nprint(gc.get_freeze_count() > 0, file=sys.stderr)\n"
        f"print(sorted(m for m in {RUN_DOES_NOT_LOAD!r} if m in sys.modules), file=sys.stderr)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    frozen, unneeded = done.stderr.strip().splitlines()[-2:]
    assert unneeded == "[]"
    assert frozen == "True"  # what lives until the end (modules, mission, world) is out of the collector's passes


def test_every_command_is_found_where_the_group_looks_for_it():
    """``main`` imports a command's module when the command is asked for (``app.COMMANDS``): each
    module registers exactly the commands the table gives it."""
    import importlib

    from thymio_bt.cli.app import COMMANDS, main

    for module in sorted(set(COMMANDS.values())):
        importlib.import_module(f"thymio_bt.cli.{module}")
    assert sorted(main.commands) == sorted(COMMANDS)
    assert {name: cmd.callback.__module__ for name, cmd in main.commands.items()} == {
        name: f"thymio_bt.cli.{module}" for name, module in COMMANDS.items()
    }


@dataclass(frozen=True)
class Import:
    """One ``import`` of a module: the module (or package) it names, and where it is written."""

    name: str
    file: str
    line: int
    #: named in a ``"module:attribute"`` string: an edge between rooms, not an import at load time
    named: bool = False


#: a lazy import named as data: ``"thymio_bt.module:attribute"`` (the registries' tables)
NAMED = re.compile(r"(thymio_bt(?:\.\w+)+):[\w.]+")


def _import_graph(root: Path = ROOT) -> tuple[dict[str, Path], dict[str, list[Import]]]:
    """thymio_bt's modules under ``root`` and what each imports, anywhere in the module: inside
    functions, under ``if TYPE_CHECKING:`` (never run, but a type named from a room above is an
    edge upward all the same: mypy, the docs and the reader follow it), and named in a
    ``"module:attribute"`` string that a registry imports when asked (an edge like any other)."""
    files = {
        ".".join(p.relative_to(root).with_suffix("").parts).removesuffix(".__init__"): p
        for p in (root / "thymio_bt").rglob("*.py")
    }
    assert files, "no module found"
    graph = {}
    for module, path in files.items():
        tree = ast.parse(path.read_text())
        package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
        where = str(path.relative_to(root))
        imported = []
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                imported += [Import(a.name, where, node.lineno) for a in node.names]
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) and module != "thymio_bt._moved":
                if named := NAMED.fullmatch(node.value):
                    imported.append(Import(named[1], where, node.lineno, named=True))
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package[: len(package) - node.level + 1] + ([base] if base else []))
                imported += [
                    Import(f"{base}.{a.name}" if f"{base}.{a.name}" in files else base, where, node.lineno)
                    for a in node.names
                ]
        graph[module] = imported
    return files, graph


def _cycle(edges: dict[str, set[str]]) -> list[str] | None:
    """A circle in ``edges`` (node -> the nodes it depends on), as the path round it; None if none."""
    state: dict[str, int] = {}

    def visit(node: str, trail: list[str]) -> list[str] | None:
        state[node] = 1
        for dep in sorted(edges.get(node, ())):
            if state.get(dep) == 1:
                return [*trail, node, dep]
            if dep not in state and (found := visit(dep, [*trail, node])):
                return found
        state[node] = 2
        return None

    for node in sorted(edges):
        if node not in state and (found := visit(node, [])):
            return found
    return None


def test_no_import_cycle_among_the_package_modules():
    files, graph = _import_graph()
    edges = {m: {i.name for i in deps if i.name in files and i.name != m and not i.named} for m, deps in graph.items()}
    cycle = _cycle(edges)
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def rooms(page: str) -> list[str]:
    """The rooms of the architecture page's table, top down, as module names: `cli/` is
    ``thymio_bt.cli``, `btcpp/runtime/` ``thymio_bt.btcpp.runtime``, `errors.py` ``thymio_bt.errors``,
    `__init__.py` ``thymio_bt``."""
    table = page.split("| room |", 1)[1].split("\n\n", 1)[0]
    names = []
    for row in table.splitlines()[2:]:
        for cell in re.findall(r"`([\w/.]+)`", row.split("|")[1]):
            dotted = cell.removesuffix("/").removesuffix(".py").replace("/", ".")
            names.append("thymio_bt" if dotted == "__init__" else f"thymio_bt.{dotted}")
    return names


def room_of(module: str, order: list[str]) -> str | None:
    """The room a module is in: the longest room name it is, or is inside of."""
    inside = [r for r in order if module == r or (r != "thymio_bt" and module.startswith(r + "."))]
    return max(inside, key=len) if inside else None


def layer_violations(files: dict[str, Path], graph: dict[str, list[Import]], order: list[str]) -> list[str]:
    """Every import of a room above the importer's (``file:line: ...``), every module in no room, and
    a circle between rooms if there is one. A room may import itself and every room below it."""
    rank = {room: i for i, room in enumerate(order)}
    found = [f"{files[m]}: {m} is in no room of the table" for m in sorted(files) if room_of(m, order) is None]
    edges: dict[str, set[str]] = {}
    for module, imports in sorted(graph.items()):
        mine = room_of(module, order)
        for imp in imports:
            if not imp.name.startswith("thymio_bt.") or mine is None:
                continue
            theirs = room_of(imp.name, order)
            if theirs is None or theirs == mine:
                continue
            edges.setdefault(mine, set()).add(theirs)
            if rank[theirs] < rank[mine]:
                found.append(f"{imp.file}:{imp.line}: {module} imports {imp.name} ({theirs} is above {mine})")
    found = list(dict.fromkeys(found))  # one line per import statement, not per name it imports
    if cycle := _cycle(edges):
        found.append("a circle between rooms: " + " -> ".join(cycle))
    return found


def test_each_room_imports_only_the_rooms_below_it():
    """docs/architecture.md's order holds: no import of a room above (inside functions too), no circle."""
    files, graph = _import_graph()
    order = rooms((ROOT / "docs/architecture.md").read_text())
    assert len(order) == len(set(order)) > 10, order
    assert layer_violations(files, graph, order) == []


def _plant(root: Path, files: dict[str, str]) -> None:
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)


def test_an_upward_import_inside_a_function_is_reported_with_its_place(tmp_path: Path):
    """A synthetic package: ``low`` below ``high``; low imports high in a function (reported, at its
    line), and high imports low (downward: fine)."""
    _plant(
        tmp_path,
        {
            "thymio_bt/__init__.py": "",
            "thymio_bt/high/__init__.py": "from thymio_bt.low import a\n",
            "thymio_bt/high/b.py": "X = 1\n",
            "thymio_bt/low/__init__.py": "",
            "thymio_bt/low/a.py": "X = 0\n\n\ndef f():\n    from thymio_bt.high.b import X\n    return X\n",
        },
    )
    files, graph = _import_graph(tmp_path)
    found = layer_violations(files, graph, ["thymio_bt.high", "thymio_bt.low", "thymio_bt"])
    assert (
        found[0]
        == "thymio_bt/low/a.py:5: thymio_bt.low.a imports thymio_bt.high.b (thymio_bt.high is above thymio_bt.low)"
    )
    assert found[1:] == ["a circle between rooms: thymio_bt.high -> thymio_bt.low -> thymio_bt.high"]
    assert layer_violations(files, graph, ["thymio_bt.low", "thymio_bt.high", "thymio_bt"])[:1] == [
        "thymio_bt/high/__init__.py:1: thymio_bt.high imports thymio_bt.low.a (thymio_bt.low is above thymio_bt.high)"
    ]


def test_an_upward_import_planted_in_a_copy_of_the_package_is_reported(tmp_path: Path):
    """The real package copied, and the bottom module (geometry) made to import a command in a function."""
    for path in (ROOT / "thymio_bt").rglob("*.py"):
        _plant(tmp_path, {str(path.relative_to(ROOT)): path.read_text()})
    planted = tmp_path / "thymio_bt/geometry.py"
    lines = planted.read_text().splitlines()
    planted.write_text("\n".join([*lines, "", "", "def _planted():", "    from thymio_bt.cli import main", ""]))
    files, graph = _import_graph(tmp_path)
    order = rooms((ROOT / "docs/architecture.md").read_text())
    found = layer_violations(files, graph, order)
    assert found[0] == (
        f"thymio_bt/geometry.py:{len(lines) + 4}: thymio_bt.geometry imports thymio_bt.cli "
        "(thymio_bt.cli is above thymio_bt.geometry)"
    )
    assert found[1].startswith("a circle between rooms: ") and len(found) == 2


def test_a_room_above_named_in_a_module_attr_string_is_an_edge_upward(tmp_path: Path):
    """A registry's ``"module:attr"`` string is imported when asked: logs' format table named
    ``thymio_bt.btcpp.btlog:read_btlog``, an edge up that no import statement showed."""
    _plant(
        tmp_path,
        {
            "thymio_bt/__init__.py": "",
            "thymio_bt/logs/__init__.py": 'READERS = ("thymio_bt.btcpp.btlog:read_btlog",)\n',
            "thymio_bt/btcpp/__init__.py": "",
            "thymio_bt/btcpp/btlog.py": "import thymio_bt.logs\n",
        },
    )
    files, graph = _import_graph(tmp_path)
    found = layer_violations(files, graph, ["thymio_bt.btcpp", "thymio_bt.logs", "thymio_bt"])
    assert found[0] == (
        "thymio_bt/logs/__init__.py:1: thymio_bt.logs imports thymio_bt.btcpp.btlog "
        "(thymio_bt.btcpp is above thymio_bt.logs)"
    )
    assert not [i for i in graph["thymio_bt.logs"] if not i.named]  # no import at load time: no module cycle


def test_an_import_for_types_only_is_held_to_the_order_too(tmp_path: Path):
    """A type named from a room above under ``if TYPE_CHECKING:`` is an edge upward (backends once
    named the mission's ``Mission`` so), and two modules naming each other's types are a circle
    (robot's interface, model and profile once were)."""
    planted = "from typing import TYPE_CHECKING\n\nif TYPE_CHECKING:\n    from thymio_bt.high.b import X\n"
    _plant(
        tmp_path,
        {
            "thymio_bt/__init__.py": "",
            "thymio_bt/high/__init__.py": "",
            "thymio_bt/high/b.py": "from thymio_bt.low.a import Y\n\nX = Y\n",
            "thymio_bt/low/__init__.py": "",
            "thymio_bt/low/a.py": planted + "\nY = 1\n",
        },
    )
    files, graph = _import_graph(tmp_path)
    assert layer_violations(files, graph, ["thymio_bt.high", "thymio_bt.low", "thymio_bt"])[0] == (
        "thymio_bt/low/a.py:4: thymio_bt.low.a imports thymio_bt.high.b (thymio_bt.high is above thymio_bt.low)"
    )
    edges = {m: {i.name for i in deps if i.name in files and i.name != m} for m, deps in graph.items()}
    assert _cycle(edges) == ["thymio_bt.high.b", "thymio_bt.low.a", "thymio_bt.high.b"]


def test_only_the_simulator_imports_pymunk():
    _, graph = _import_graph()
    users = sorted(m for m, deps in graph.items() if any(i.name.split(".")[0] == "pymunk" for i in deps))
    assert users and all(m.startswith("thymio_bt.backends.sim.") for m in users), users


def test_no_module_is_over_500_lines():
    """Python modules and the viewer's script parts alike (viz/web/viewer/*.js)."""
    sources = [*(ROOT / "thymio_bt").rglob("*.py"), *(ROOT / "thymio_bt").rglob("*.js")]
    long = {str(p): n for p in sources if (n := len(p.read_text().splitlines())) > 500}
    assert not long, long


def test_the_architecture_page_names_every_package_and_root_module():
    """docs/architecture.md is drawn from the code: every package and root module has its row."""

    page = (ROOT / "docs/architecture.md").read_text()
    package = ROOT / "thymio_bt"
    rooms = [p.name + "/" for p in package.iterdir() if (p / "__init__.py").exists() and p.name != "data"]
    rooms += [p.name for p in package.glob("*.py")]
    modules = [
        p.stem for p in (ROOT / "thymio_bt").rglob("*.py") if not p.stem.startswith("__") and "data" not in p.parts
    ]
    missing = [room for room in sorted(rooms) if f"`{room}`" not in page]
    missing += [module for module in sorted(set(modules)) if f"`{module}`" not in page and f"`{module}.py`" not in page]
    assert not missing, f"docs/architecture.md does not describe {missing}"
