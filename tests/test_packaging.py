"""What a stranger gets from ``pip install``: the wheel, installed into a fresh environment outside the
checkout, runs a shipped mission by name and a mission of its own that names a shipped maze;
``python -m thymio_bt`` is the same CLI; the version is written in one place."""

import subprocess
import sys
from pathlib import Path

import pytest
import tomllib

import thymio_bt

ROOT = Path(__file__).resolve().parents[1]
OWN_MISSION = """\
name: own
maze: two_parts_maze
start: part1
tree:
  MoveUntilWall: {distance: 5cm}
"""


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """A fresh virtual environment with thymio-bt installed from a wheel built from this checkout."""
    tmp = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", str(ROOT), "-w", str(tmp / "dist")],
        check=True,
        capture_output=True,
    )
    wheel = next((tmp / "dist").glob("thymio_bt-*.whl"))
    subprocess.run([sys.executable, "-m", "venv", str(tmp / "env")], check=True)
    subprocess.run([str(tmp / "env/bin/pip"), "install", "-q", str(wheel)], check=True, capture_output=True)
    return tmp / "env/bin"


def run_in(folder: Path, *cmd: str) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, cwd=folder, capture_output=True, text=True, timeout=120)


def test_the_wheel_runs_a_shipped_mission_by_name_from_any_folder(installed, tmp_path):
    thymio_bt = str(installed / "thymio-bt")
    done = run_in(tmp_path, thymio_bt, "run", "maze_part1_2", "--report", "r.json", "--html", "r.html")
    assert done.returncode == 0, done.stderr
    assert "SUCCESS" in done.stdout and (tmp_path / "r.json").is_file()
    assert "class Run" in (tmp_path / "r.html").read_text()  # the viewer's script parts are in the wheel
    imported = run_in(tmp_path, str(installed / "python"), "-c", "import thymio_bt; print(thymio_bt.__file__)")
    assert str(ROOT) not in imported.stdout  # the installed copy, not this checkout


def test_the_wheel_runs_an_own_mission_naming_a_shipped_maze(installed, tmp_path):
    (tmp_path / "own.yaml").write_text(OWN_MISSION)
    done = run_in(tmp_path, str(installed / "thymio-bt"), "run", "own.yaml")
    assert done.returncode == 0, done.stderr
    assert "own: SUCCESS" in done.stdout


def test_python_dash_m_is_the_same_cli(installed, tmp_path):
    module = run_in(tmp_path, str(installed / "python"), "-m", "thymio_bt", "--version")
    script = run_in(tmp_path, str(installed / "thymio-bt"), "--version")
    assert module.returncode == 0 and module.stdout == script.stdout == f"thymio-bt, version {thymio_bt.__version__}\n"


def test_an_unknown_mission_name_suggests_the_nearest(installed, tmp_path):
    done = run_in(tmp_path, str(installed / "thymio-bt"), "run", "maze_part12")
    assert done.returncode == 2 and "did you mean 'maze_part1_2'?" in done.stderr and "Traceback" not in done.stderr


def test_metadata_has_one_version_a_licence_and_the_python_ci_runs():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert "version" in project["dynamic"] and "version" not in project
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert (
        f"Programming Language :: Python :: {sys.version_info.major}.{sys.version_info.minor}" in project["classifiers"]
    )
    low = tuple(int(part) for part in project["requires-python"].removeprefix(">=").split("."))
    assert low <= sys.version_info[:2]
