"""An angle written without a unit is in radians everywhere, and one past a full turn is refused
with the degrees it surely meant: a node's angle, every pose's yaw (a mission's start, --start,
SpawnEntity, a maze's spawn, an assignment's start and respawn), a parameter used as one, --set."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner
from pydantic import BaseModel, ValidationError

from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.grade.assignment import load_assignment
from thymio_bt.inputs.fields import Pose2D
from thymio_bt.inputs.units import UnitError, parse_pose
from thymio_bt.mission import load_mission

ROOT = Path(__file__).resolve().parents[1]
MEANT = "did you mean 90deg? a bare number is in rad"


def _mission(tmp_path: Path, spawn_yaw: str, start: str = "part1") -> Path:
    path = tmp_path / "m.yaml"
    path.write_text(
        f"maze: two_parts_maze\nstart: {start}\nparameters: {{turn: 10deg}}\n"
        f"tree:\n  SpawnEntity: {{entity: thymio, pose: [0.5, 0.3, {spawn_yaw}]}}\n"
    )
    return path


@pytest.mark.parametrize("command", ["validate", "lint", "run"])
def test_every_command_refuses_a_spawn_yaw_meant_in_degrees(tmp_path: Path, command: str) -> None:
    path = _mission(tmp_path, "90")
    result = CliRunner().invoke(main, [command, str(path)])
    assert result.exit_code == 2, result.output
    assert f"{path}:5:50: 90 rad is more than a full turn" in result.stderr and MEANT in result.stderr
    assert "Traceback" not in result.output


@pytest.mark.parametrize("yaw", ["pi/2", "1.5707963267948966", "90deg", "-pi", "6.2"])
def test_radians_as_the_shipped_missions_write_them_are_kept(tmp_path: Path, yaw: str) -> None:
    assert load_mission(_mission(tmp_path, yaw)) is not None


def test_the_start_option_and_a_set_parameter_get_the_same_rule(tmp_path: Path) -> None:
    path = _mission(tmp_path, "pi/2")
    result = CliRunner().invoke(main, ["run", str(path), "--start", "0.2,0.1,90"])
    assert result.exit_code == 2 and MEANT in result.stderr, result.output
    result = CliRunner().invoke(main, ["validate", str(path), "--set", "turn=90"])
    assert result.exit_code == 2 and MEANT in result.stderr, result.output
    assert CliRunner().invoke(main, ["validate", str(path), "--set", "turn=1.2"]).exit_code == 0


def test_only_a_whole_number_is_guessed_as_degrees(tmp_path: Path) -> None:
    with pytest.raises(UserError) as info:
        load_mission(_mission(tmp_path, "4*pi"))
    (problem,) = info.value.problems
    assert "12.5664 rad is more than a full turn" in problem.message and "did you mean" not in problem.hint


def test_a_pose_written_as_text_in_python_gets_the_same_rule() -> None:
    with pytest.raises(UnitError, match="YAW of '0.5, 0.3, 90': 90 rad is more than a full turn") as info:
        parse_pose("0.5, 0.3, 90")
    assert MEANT in info.value.hint

    class Params(BaseModel):
        pose: Pose2D

    with pytest.raises(ValidationError, match="more than a full turn"):
        Params(pose="0.5, 0.3, 90")  # type: ignore[arg-type]
    assert Params(pose="0.5, 0.3, pi/2").pose[2] == pytest.approx(1.5707963)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("variant", "criterion"),
    [
        ("start: [0.22, 0.1, 90]", "respawn: {pose: [0.5, 0.3, pi/2]}"),
        ("start: part1", "respawn: {pose: [0.5, 0.3, 90]}"),
    ],
)
def test_an_assignment_start_and_respawn_get_the_same_rule(tmp_path: Path, variant: str, criterion: str) -> None:
    path = tmp_path / "a.yaml"
    path.write_text(
        f"name: a\nvariants:\n  - {{name: v, maze: two_parts_maze, {variant}}}\n"
        f"criteria:\n  - {{name: c, points: 1, {criterion}}}\n"
    )
    with pytest.raises(UserError) as info:
        load_assignment(path)
    (problem,) = info.value.problems  # not also "Input should be a valid string" (the str of str | Spawn)
    assert "90 rad is more than a full turn" in problem.message
    assert MEANT in problem.hint and problem.line in (3, 5)


def test_the_shipped_assignments_still_load() -> None:
    for path in sorted((ROOT / "assignments").glob("*.yaml")):
        assert load_assignment(path).name == path.stem


def test_the_start_of_serve_ros2_gets_the_same_rule_and_hint() -> None:
    from thymio_bt.cli.serving import start_pose
    from thymio_bt.maze import load_maze, resolve_maze

    with pytest.raises(UserError, match="90 rad is more than a full turn") as info:
        start_pose(load_maze(resolve_maze("arena")), "0.2,0.1,90")
    assert MEANT in str(info.value)
