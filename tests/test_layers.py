"""DESIGN.md's layers: the mission language and the behaviours never load the physics engine, and
no command pays at start-up for libraries only some commands need."""

import subprocess
import sys
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
    assert backends == "[]", f"{args}: loads backend modules {backends}"


#: what ``thymio-bt run`` of a plain mission has no use for, made lazy so that its start-up does not pay
#: for them (benchmarks/README.md, "Start-up of run"): other commands' modules and what they import
RUN_DOES_NOT_LOAD = (
    "asyncio",
    "thymio_bt.cli.sweeps",
    "thymio_bt.cli.grading",
    "thymio_bt.cli.inspection",
    "thymio_bt.grade",
    "thymio_bt.mission.btcpp",
    "xml.etree.ElementTree",
)


def test_run_loads_only_what_it_needs(tmp_path):
    code = (
        "import sys\nfrom thymio_bt.cli import main\n"
        f"sys.argv = ['thymio-bt', 'run', {str(ROOT / 'missions/maze_part1_2.yaml')!r}, '--quiet']\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        f"print(sorted(m for m in {RUN_DOES_NOT_LOAD!r} if m in sys.modules), file=sys.stderr)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "[]"


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


def _import_graph():
    """thymio_bt's modules and what each imports (anywhere in the module, TYPE_CHECKING blocks aside)."""
    import ast

    files = {
        ".".join(p.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__"): p
        for p in (ROOT / "thymio_bt").rglob("*.py")
    }
    assert files, "no module found"
    graph = {}
    for module, path in files.items():
        tree = ast.parse(path.read_text())
        hidden = {
            id(n)
            for node in ast.walk(tree)
            if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
            for n in ast.walk(node)
        }
        package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
        imported = set()
        for node in ast.walk(tree):
            if id(node) in hidden:
                continue
            if isinstance(node, ast.Import):
                imported |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    base = ".".join(package[: len(package) - node.level + 1] + ([base] if base else []))
                imported |= {f"{base}.{a.name}" if f"{base}.{a.name}" in files else base for a in node.names}
        graph[module] = imported
    return files, graph


def test_no_import_cycle_among_the_package_modules():
    files, graph = _import_graph()
    edges = {m: {d for d in deps if d in files and d != m} for m, deps in graph.items()}
    state: dict[str, int] = {}

    def visit(module, trail):
        state[module] = 1
        for dep in sorted(edges[module]):
            assert state.get(dep) != 1, "import cycle: " + " -> ".join([*trail, module, dep])
            if dep not in state:
                visit(dep, [*trail, module])
        state[module] = 2

    for module in sorted(edges):
        if module not in state:
            visit(module, [])


def test_only_the_simulator_imports_pymunk():
    _, graph = _import_graph()
    users = sorted(m for m, deps in graph.items() if any(d == "pymunk" or d.startswith("pymunk.") for d in deps))
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
