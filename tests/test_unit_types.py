"""One unit-type mechanism (issue 45): ``Length``, ``Angle``, ``Point``, ``Duration``, ``Speed`` and
``Memory`` are declared once, in :mod:`thymio_bt.inputs.fields`, by the :class:`Unit` they are in.
A maze, a mission's ``expect:`` and an assignment use the very types node parameters use, and a
value reads the same and is refused the same wherever it is written."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from thymio_bt.behaviours.motion import MoveDistanceParams, TurnAngleParams
from thymio_bt.errors import UserError
from thymio_bt.grade import assignment
from thymio_bt.inputs import fields
from thymio_bt.inputs.validation import problems_from
from thymio_bt.maze import model as maze_model
from thymio_bt.maze.model import Spawn
from thymio_bt.mission.loader import load_mission
from thymio_bt.plan import expect


def test_each_unit_type_is_declared_once():
    assert (maze_model.Length, maze_model.Angle, maze_model.Point) == (fields.Length, fields.Angle, fields.Point)
    assert expect.Duration is fields.Duration and expect.Length is fields.Length
    assert (assignment.Duration, assignment.Speed, assignment.Memory) == (fields.Duration, fields.Speed, fields.Memory)
    thickness = maze_model.Wall.model_fields["thickness"]
    assert fields.unit_of(thickness) == "m"  # a maze's numbers carry their unit, as parameters' do


LENGTHS = ["20cm", "0.2 m", "200mm", "0.2", 0.2, "2 * 10cm", "0.1 + 10cm"]
ANGLES = ["90deg", "pi/2", "1.5707963267948966", math.pi / 2, "180deg / 2"]


@pytest.mark.parametrize("length", LENGTHS)
@pytest.mark.parametrize("angle", ANGLES)
def test_a_maze_and_a_node_parameter_read_the_same_text_alike(length, angle):
    spawn = Spawn.model_validate({"x": length, "y": 0, "yaw": angle})
    assert MoveDistanceParams(distance=length).distance == spawn.x == pytest.approx(0.2, abs=1e-12)
    assert TurnAngleParams(angle=angle).angle == spawn.yaw == pytest.approx(math.pi / 2, abs=1e-12)


@pytest.mark.parametrize(
    "length, said",
    [
        ("5s", "expected a length (in m), got a time"),
        (True, "expected a number, got true/false"),
        ([1], "expected a number, got a list"),
        ("5 parsec", "unknown unit 'parsec'"),
    ],
)
def test_a_maze_and_a_node_parameter_refuse_a_value_alike(length, said):
    def problem(model, data):
        with pytest.raises(ValidationError) as info:
            model.model_validate(data)
        (found,) = problems_from(info.value, data, "f.yaml", model)
        return found.message, found.hint

    in_maze = problem(Spawn, {"x": length, "y": 0})
    assert in_maze == problem(MoveDistanceParams, {"distance": length})
    assert said in in_maze[0] and in_maze[1]  # with a hint


def test_a_bare_angle_past_a_full_turn_is_refused_alike():
    with pytest.raises(ValidationError, match="90 rad is more than a full turn"):
        Spawn(x=0, y=0, yaw=90)
    with pytest.raises(ValidationError, match="90 rad is more than a full turn"):
        TurnAngleParams(angle=90)


def test_a_mission_value_with_its_unit_is_checked_once(tmp_path):
    """The loader converts ``400deg`` to radians before pydantic sees it (context IN_SI): the range
    is what refuses it, not the bare-angle rule, which would wrongly say it was written without a unit."""
    mission = tmp_path / "m.yaml"
    mission.write_text("maze: two_parts_maze\nstart: part1\ntree:\n  TurnAngle: {angle: 400deg}\n")
    with pytest.raises(UserError) as info:
        load_mission(mission)
    (problem,) = info.value.problems
    assert problem.message.startswith("Input should be less than or equal to 6.28") and problem.line == 4
