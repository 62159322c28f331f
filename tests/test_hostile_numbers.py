"""Hostile numbers and poses: every number from a file, ``--set`` or an option is checked for type,
finiteness and range before anything runs, the same way whichever way it came in; a start pose in
or over any obstacle is refused and a yaw is normalised or refused."""

import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.mission import load_mission

ROOT = Path(__file__).resolve().parents[1]

SQUARE = f"{ROOT}/missions/square.yaml"


def invoke(*args):
    return CliRunner().invoke(main, list(args))


@pytest.mark.parametrize(
    "setting, message",
    [
        ("time_limit=-5", "time_limit must be between 0.1 and 36000, got -5"),
        ("time_limit=0", "time_limit must be between"),
        ("time_limit=99999999999999999999999", "time_limit must be between 0.1 and 36000, got 1e+23"),
        ("time_limit=1e400", "is not a finite number"),
        ("time_limit=nan", "expected a number"),
        ("tick_hz=0", "tick_hz must be between 1 and 100, got 0"),
        ("tick_hz=1e9", "tick_hz must be between 1 and 100"),
        ("seed=-3", "seed must be a whole number >= 0"),
        ("seed=1.5", "seed must be a whole number >= 0"),
        ("seed=99999999999999999999999", "seed must be a whole number >= 0"),
        ("noise.wheel=nan", "finite number"),
        ("noise.wheel=-1", "greater than or equal to 0"),
        ("cruise=inf", "not a number"),
    ],
)
@pytest.mark.parametrize("command", ["run", "validate", "sweep"])
def test_set_is_checked_like_the_file_before_anything_runs(command, setting, message):
    mission = f"{ROOT}/missions/maze_part1_2.yaml" if setting.startswith("cruise") else SQUARE
    result = invoke(command, mission, "--set", setting, *(["--runs", "2"] if command == "sweep" else []))
    assert result.exit_code == 2 and message in result.output, result.output
    assert "Traceback" not in result.output and "SUCCESS" not in result.output


@pytest.mark.parametrize(
    "text, message",
    [
        ("time_limit: .nan", "nan is not a finite number"),
        ("time_limit: 1e9", "time_limit must be between"),
        ("tick_hz: .inf", "inf is not a finite number"),
        ("seed: 99999999999999999999999999999", "seed must be a whole number"),
        ("seed: -1", "seed must be a whole number"),
    ],
)
def test_settings_in_the_file_are_checked(tmp_path, text, message):
    path = tmp_path / "m.yaml"
    path.write_text(f"maze: arena\nstart: centre\n{text}\ntree: Stop\n")
    with pytest.raises(UserError, match=message) as err:
        load_mission(path)
    assert err.value.problems[0].line == 3


def test_a_valid_seed_from_set_is_the_same_as_the_option():
    by_set = invoke("run", SQUARE, "--set", "seed=5", "--set", "noise.wheel=0.05", "--report", "-", "-q")
    by_option = invoke("run", SQUARE, "--seed", "5", "--set", "noise.wheel=0.05", "--report", "-", "-q")
    assert by_set.exit_code == by_option.exit_code == 0
    assert by_set.stdout.split('"wall_time"')[0] == by_option.stdout.split('"wall_time"')[0]


@pytest.mark.parametrize(
    "option",
    [
        ["--realtime", "0"],
        ["--realtime", "-1"],
        ["--realtime", "nan"],
        ["--realtime", "inf"],
        ["--speedup", "0"],
        ["--speedup", "nan"],
        ["--seed", "-1"],
        ["--seed", "1e3"],
    ],
)
def test_option_numbers_are_finite_and_in_range(option):
    result = invoke("run", SQUARE, "-q", *option)
    assert result.exit_code == 2 and f"Invalid value for '{option[0]}'" in result.output


@pytest.mark.parametrize(
    ("start", "said"),
    [
        ("0.5,0.3,1e300", "more than a full turn"),  # a bare number: radians, at most one turn
        ("0.6,0.6,-1e20", "more than a full turn"),
        ("[0.6, 0.6, 1e300]", "more than a full turn"),
        ("[0.6, 0.6, 1e5 deg]", "more than ten turns"),  # with its unit: up to ten turns
        ("0.6,0.6,1e300rad", "more than ten turns"),
    ],
)
def test_an_absurd_yaw_is_refused(tmp_path, start, said):
    path = tmp_path / "m.yaml"
    path.write_text(f"maze: arena\nstart: {start}\ntree: Stop\n")
    with pytest.raises(UserError, match=said):
        load_mission(path)


def test_a_yaw_is_normalised_and_a_yaw_in_range_kept_exactly(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("maze: arena\nstart: [0.6, 0.6, 3*pi/2]\ntree: Stop\n")
    assert load_mission(path).start.yaw == pytest.approx(-math.pi / 2, abs=1e-15)
    assert load_mission(path, start="0.6,0.6,pi/2").start.yaw == math.pi / 2


@pytest.mark.parametrize(
    "start, reason",
    [
        ("0.6,0.6,0", "overlaps"),  # on the big block in the middle
        ("0.3,0.6,0", "overlaps"),  # the hull over its edge, the centre outside it
        ("5,5,0", "outside the maze"),
    ],
)
def test_a_start_in_or_over_an_obstacle_is_refused(tmp_path, start, reason):
    maze = tmp_path / "block.yaml"
    maze.write_text(
        "name: block\nwalls:\n"
        "  - {from: [0, 0], to: [1.2, 0]}\n  - {from: [1.2, 0], to: [1.2, 1.2]}\n"
        "  - {from: [1.2, 1.2], to: [0, 1.2]}\n  - {from: [0, 1.2], to: [0, 0]}\n"
        "obstacles:\n  - {polygon: [[0.35, 0.35], [0.85, 0.35], [0.85, 0.85], [0.35, 0.85]]}\n"
    )
    result = invoke("run", SQUARE, "--maze", str(maze), "--start", start)
    assert result.exit_code == 2 and "impossible start pose" in result.output and reason in result.output


BIG = "9" * 400


@pytest.mark.parametrize(
    "line",
    [
        f"time_limit: {BIG}",  # a setting
        f"seed: -{BIG}",
        "parameters: {cruise: " + BIG + "}",  # a parameter
    ],
)
def test_a_400_digit_integer_in_a_file_is_refused_where_it_stands(tmp_path, line):
    path = tmp_path / "big.yaml"
    path.write_text(f"name: big\nmaze: two_parts_maze\nstart: part1\n{line}\ntree:\n  MoveUntilWall: {{speed: 0.1}}\n")
    result = invoke("run", str(path))
    assert result.exit_code == 2 and "Traceback" not in result.output, result.output
    assert f"{path}:4:" in result.output and "a number of 400 digits is too large" in result.output


def test_a_400_digit_speed_in_a_behaviour_is_refused_where_it_stands(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text(f"name: big\nmaze: two_parts_maze\nstart: part1\ntree:\n  MoveUntilWall: {{speed: {BIG}}}\n")
    result = invoke("validate", str(path))
    assert result.exit_code == 2 and "Traceback" not in result.output, result.output
    assert f"{path}:5:" in result.output and "a number of 400 digits is too large" in result.output
