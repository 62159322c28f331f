"""DESIGN.md's layers: the mission language and the behaviours never load the physics engine, and
no command pays at start-up for libraries only some commands need."""

import subprocess
import sys

import pytest


@pytest.mark.parametrize("modules, absent", [
    ("thymio_bt.mission, thymio_bt.behaviours", ("pymunk",)),
    ("thymio_bt.cli", ("pymunk", "py_trees", "pydantic", "matplotlib", "pygame", "numpy", "tdmclient")),
    ("thymio_bt.cli, thymio_bt.runner, thymio_bt.mission", ("matplotlib", "pygame", "numpy", "tdmclient")),
])
def test_imports_stay_in_their_layer(modules, absent):
    code = f"import sys, {modules}; print(','.join(m for m in {absent!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


@pytest.mark.parametrize("args", [
    ["validate", "missions/maze_part1_2.yaml", "mazes/two_parts_maze.yaml"],
    ["tree", "missions/maze_bonus.yaml", "-o", "{tmp}/t.dot"],
    ["schema"],
    ["behaviours", "parallel"],
    ["backends"],
])
def test_commands_that_run_nothing_load_no_physics_engine(args, tmp_path):
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    code = ("import sys\nfrom thymio_bt.cli import main\n"
            f"sys.argv = ['thymio-bt', *{args!r}]\n"
            "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
            "print('pymunk' in sys.modules, file=sys.stderr)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "False", args
