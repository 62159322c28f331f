"""The CLI contract of DESIGN.md: exit codes, the run report's fields, --maze/--start, and validate."""

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.robot.interface import SENSOR_NAMES

ROOT = Path(__file__).resolve().parents[1]


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_run_writes_the_report_of_the_contract_and_exits_0(tmp_path):
    out = tmp_path / "report.json"
    result = invoke("run", f"{ROOT}/missions/square.yaml", "--report", out, "--quiet", "--seed", 3)
    assert result.exit_code == 0 and result.output == ""
    report = json.loads(out.read_text())
    assert report["status"] == "SUCCESS" and report["reason"] is None and report["seed"] == 3
    assert (
        report["ticks"] == round(report["sim_time"] * 10) + 1 and report["wall_time"] > 0
    )  # ticks at 0 and at the end
    assert set(report["final_pose"]) == {"x", "y", "yaw"}
    assert set(report["final_proximity"]) == set(SENSOR_NAMES)
    assert report["collisions"] == 0 and report["min_clearance"] > 0
    times = [e["t"] for e in report["events"]]
    assert times == sorted(times)
    ends = [e for e in report["events"] if e["kind"] == "behaviour_end"]
    assert ends and all({"name", "path", "status", "pose", "proximity"} <= set(e) for e in ends)
    turns = [e for e in ends if e["name"] == "TurnAngle"]
    assert [round(e["angle"], 3) for e in turns] == [round(math.pi / 2, 3)] * len(turns) and turns


def test_a_run_that_hits_its_time_limit_exits_1_and_names_the_running_node(tmp_path):
    out = tmp_path / "report.json"
    result = invoke("run", f"{ROOT}/missions/maze_part1_2.yaml", "--set", "time_limit=3", "--report", out)
    assert result.exit_code == 1
    report = json.loads(out.read_text())
    assert report["status"] == "TIMEOUT" and "time limit" in report["reason"]
    assert report["failed_path"] == "course/part 1"  # the MoveUntilWall named 'part 1'
    assert report["code"] == "TIMEOUT"
    assert "failed at:" in result.output


def test_maze_and_start_override_the_mission(tmp_path):
    out = tmp_path / "report.json"
    result = invoke(
        "run",
        f"{ROOT}/missions/square.yaml",
        "--maze",
        f"{ROOT}/mazes/report_arena.yaml",
        "--start=-0.3,-0.3,pi/2",
        "--report",
        out,
        "-q",
    )
    assert result.exit_code == 0, result.output
    report = json.loads(out.read_text())
    t, x, y, yaw = report["trajectory"][0]
    assert (t, x, y) == (0.0, -0.3, -0.3) and math.isclose(yaw, math.pi / 2, abs_tol=1e-6)
    assert report["final_pose"]["x"] == -0.3 or abs(report["final_pose"]["x"] + 0.3) < 0.01


def test_validate_checks_missions_and_maze_files():
    result = invoke(
        "validate",
        f"{ROOT}/missions/maze_part1_2.yaml",
        f"{ROOT}/mazes/two_parts_maze.yaml",
        f"{ROOT}/mazes/arena.yaml",
    )
    assert result.exit_code == 0, result.output
    assert (
        f"ok: {ROOT}/mazes/two_parts_maze.yaml (maze: 21 walls, 0 obstacles, spawns part1, part2, bonus)"
        in result.output
    )
    assert f"ok: {ROOT}/missions/maze_part1_2.yaml (16 nodes, maze two_parts_maze)" in result.output


def test_validate_reports_every_impossible_spawn_of_a_maze_with_its_line(tmp_path):
    maze = tmp_path / "maze.yaml"
    maze.write_text(
        "name: box\nwalls:\n  - {from: [0, 0], to: [0.4, 0]}\n  - {from: [0, 0.4], to: [0.4, 0.4]}\n"
        "spawns:\n  inside: [0.2, 0.2, 0]\n  in_wall: [0.2, 0.01, 0]\n  outside: [0.9, 0.2, 0]\n"
    )
    result = invoke("validate", maze)
    assert result.exit_code == 2
    assert f"{maze}:7:3: spawn 'in_wall' is impossible" in result.output
    assert f"{maze}:8:3: spawn 'outside' is impossible" in result.output
    assert "'inside'" not in result.output and "Traceback" not in result.output


def test_validate_gives_the_line_of_an_impossible_start_pose(tmp_path):
    mission = tmp_path / "m.yaml"
    mission.write_text("name: m\nmaze: arena\nstart: [0.0, 0.0, 0]\ntree:\n  Stop: {}\n")
    result = invoke("validate", mission)
    assert result.exit_code == 2
    assert f"{mission}:3:8: impossible start pose" in result.output


def test_colour_follows_no_color_and_the_color_option(monkeypatch):
    def status_line(*args, color=False):
        return (
            CliRunner().invoke(main, [*args, "run", f"{ROOT}/missions/square.yaml"], color=color).output.splitlines()[0]
        )

    assert "\x1b[" in status_line(color=True)  # a terminal: coloured
    assert "\x1b[" not in status_line("--color", "never", color=True)
    monkeypatch.setenv("NO_COLOR", "1")
    assert "\x1b[" not in status_line(color=True)
    assert "\x1b[" in status_line("--color", "always", color=False)


def test_replay_prints_the_summary_run_prints_not_a_python_dict(tmp_path):
    log = tmp_path / "run.jsonl"
    ran = invoke("run", f"{ROOT}/missions/square.yaml", "--log", log)
    replayed = invoke("replay", log)
    assert replayed.exit_code == 0 and "{'x'" not in replayed.output
    pose_line = next(line for line in ran.output.splitlines() if "final pose" in line)
    assert pose_line in replayed.output.splitlines()  # '  final pose: x=0.4500 m  y=...'
    assert replayed.output.startswith("square: SUCCESS after 22.7 s simulated, 228 ticks\n")


def test_behaviour_help_fits_the_terminal_width():
    import os
    import subprocess
    import sys

    for columns in (60, 80, 120):
        done = subprocess.run(
            [sys.executable, "-m", "thymio_bt", "behaviours", "MoveUntilWall"],
            env={**os.environ, "COLUMNS": str(columns)},
            capture_output=True,
            text=True,
            check=True,
        )
        lines = done.stdout.splitlines()
        assert max(len(line) for line in lines) <= columns, (columns, max(lines, key=len))
        text = " ".join(done.stdout.split())
        for words in ("centre_gain", "steer to the middle of the corridor", "front_center_right", "do not stop"):
            assert words in text, words


def test_tree_draws_to_the_mission_file_s_name_as_documented(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_square.yaml").write_text("name: another_name\nmaze: arena\nstart: centre\ntree: Stop\n")
    assert invoke("tree", "my_square.yaml", "--dot").exit_code == 0
    assert (tmp_path / "my_square.dot").is_file() and not (tmp_path / "another_name.dot").exists()
    assert "the MISSION file's name" in " ".join(invoke("tree", "--help").output.split())


def test_tree_reads_the_mission_once_and_the_terminal_tree_loads_none(tmp_path, monkeypatch):
    """viz/terminal.py loaded the mission itself (and ``tree --dot`` loaded it twice: once for the
    text, once for the picture); now the command loads it, the terminal draws it, viz/graph exports it."""
    import thymio_bt.mission as mission_package
    import thymio_bt.viz.terminal as terminal

    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.yaml").write_text("maze: arena\nstart: centre\ntree: Stop\n")
    loads = []
    real = mission_package.load_mission
    monkeypatch.setattr(mission_package, "load_mission", lambda *a, **k: loads.append(a) or real(*a, **k))
    result = invoke("tree", "m.yaml", "--dot")
    assert (
        result.exit_code == 0 and "--> Stop" in result.output and (tmp_path / "m.dot").read_text().startswith("digraph")
    )
    assert len(loads) == 1
    assert terminal.tree_text.__annotations__ == {"mission": "Mission", "return": "str"}  # a loaded mission


@pytest.mark.parametrize("flag", ["--dot", "--png"])
def test_a_default_output_name_never_replaces_a_file(tmp_path, monkeypatch, flag):
    """issue 46 item 11: 'tree bonus.yaml --png' wrote bonus.png over the --plot bonus.png just made.
    A name the command chose is refused when taken (exit 2, before anything is drawn); -o replaces."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bonus.yaml").write_text("maze: arena\nstart: centre\ntree: Stop\n")
    picture = tmp_path / f"bonus.{flag[2:]}"
    picture.write_bytes(b"the path plot")
    refused = invoke("tree", "bonus.yaml", flag)
    assert refused.exit_code == 2 and picture.read_bytes() == b"the path plot"
    assert f"bonus.{flag[2:]} exists, and a file named by default is never replaced" in refused.output
    assert f"hint: -o bonus.{flag[2:]} replaces it" in refused.output
    if flag == "--dot":  # the file named by the user is replaced, as asked (PNG needs Graphviz)
        assert invoke("tree", "bonus.yaml", flag, "-o", "bonus.dot").exit_code == 0
        assert picture.read_text().startswith("digraph")


def test_a_failure_with_no_node_to_blame_prints_no_failed_at_line(capsys):
    """A run that ends outside the tree (nothing answered on ROS 2, a robot lost before the first
    tick) has no failing node: the summary says why, not 'failed at: None'."""
    from dataclasses import replace

    from thymio_bt.cli.running import _summary
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    result = Run(load_mission("square")).run()
    lost = replace(result, status="FAILURE", code="ROBOT_LOST", reason="nothing answered", failed_path=None)
    _summary(lost)
    out = capsys.readouterr()
    assert "reason: [ROBOT_LOST] nothing answered" in out.err and "failed at" not in out.out + out.err


@pytest.mark.parametrize("mission", sorted(p.name for p in (ROOT / "missions").glob("*.yaml")))
def test_tree_draws_every_shipped_mission(mission):
    """Drawing builds the tree without a robot: no behaviour may need one to be built."""
    result = CliRunner().invoke(main, ["tree", f"{ROOT}/missions/{mission}"])
    assert result.exit_code == 0, result.output
    assert len(result.output.splitlines()) >= 2  # the root and its children


@pytest.mark.parametrize(
    "args",
    [
        ["run", "square", "--report", "-", "--log", "-"],
        ["sweep", "square", "--runs", "2", "--workers", "2", "--dask", "tcp://127.0.0.1:1"],
        ["grade", "course_bonus", f"{ROOT}/missions/maze_bonus.yaml", "--workers", "1", "--dask", "tcp://127.0.0.1:1"],
        ["tree", "square", "--svg", "--png"],
    ],
    ids=["report and log on stdout", "sweep workers and dask", "grade workers and dask", "two drawings"],
)
def test_options_that_exclude_each_other_are_refused_not_one_quietly_dropped(args):
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2 and "exclude each other (hint: " in result.output, result.output


def test_the_package_hands_out_every_command_s_function():
    """``thymio_bt.cli``'s names are read from the group's table (``app.COMMANDS``): every command
    is one of them (``palette`` was missing from a table of its own)."""
    import thymio_bt.cli as cli
    from thymio_bt.cli.app import COMMANDS

    handed = {id(getattr(cli, name)) for name in cli.__all__}
    commands = {name: main.get_command(None, name) for name in COMMANDS}
    assert [name for name, command in commands.items() if id(command) not in handed] == []


def test_commands_that_choose_a_backend_do_not_import_the_run_command():
    """calibrate and compare imported cli/running.py (the whole run command) for ``backend_for``, and
    sweep for ``CoverageRequest``: both live in cli/option_values.py, which they share with run."""
    import subprocess
    import sys

    code = (
        "import sys, thymio_bt.cli.calibrating, thymio_bt.cli.comparing, thymio_bt.cli.sweeps\n"
        "print('thymio_bt.cli.running' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"
