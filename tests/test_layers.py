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
