"""One pydantic-error translator (issue 45): every reader of user input turns pydantic's errors into
located problems through :func:`thymio_bt.inputs.validation.problems_from`, so that a robot profile,
a topic map, a backend option, a Gazebo world's wall or spawn and a run log's line say what is wrong
as a mission does: in words, at the value's place, with a hint."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import thymio_bt
from thymio_bt.backends import BUILTIN
from thymio_bt.backends.ros2.topics import load_topics
from thymio_bt.errors import UserError
from thymio_bt.maze.gazebo import import_world
from thymio_bt.robot.model import robot_model

PACKAGE = Path(thymio_bt.__file__).parent
COURSE_WORLD = Path(__file__).parent / "data" / "course" / "maze_6x6.world"


def _reads_pydantic_errors(path: Path) -> list[int]:
    """Lines where ``path`` calls ``.errors()`` on a caught ``ValidationError``."""
    found = []
    for handler in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(handler, ast.ExceptHandler) and handler.name and "ValidationError" in ast.unparse(handler.type):
            for node in ast.walk(handler):
                if (
                    isinstance(node, ast.Call)
                    and isinstance(node.func, ast.Attribute)
                    and node.func.attr == "errors"
                    and isinstance(node.func.value, ast.Name)
                    and node.func.value.id == handler.name
                ):
                    found.append(node.lineno)
    return found


def test_only_the_translator_reads_pydantic_errors():
    readers = {
        path.relative_to(PACKAGE).as_posix(): lines
        for path in PACKAGE.rglob("*.py")
        if (lines := _reads_pydantic_errors(path))
    }
    assert readers == {}, "call thymio_bt.inputs.validation.problems_from instead"
    # the check sees what it looks for
    assert _reads_pydantic_errors(PACKAGE / "inputs" / "validation.py") == []
    sample = Path(__file__).parent / "_sample_reader.py"
    try:
        sample.write_text("try:\n    pass\nexcept ValidationError as exc:\n    print(exc.errors()[0])\n")
        assert _reads_pydantic_errors(sample) == [4]
    finally:
        sample.unlink()


def test_a_profile_value_is_located_at_the_value_with_its_range(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("base: enki\nname: x\nmetres_per_unit: -1\ncolour: red\n")
    with pytest.raises(UserError) as info:
        robot_model(str(path))
    assert [str(p) for p in info.value.problems] == [
        f"{path}:3:18: Input should be greater than 0 [at metres_per_unit] (hint: allowed: > 0 and < 0.01)",
        f"{path}:4:1: unknown key 'colour' [at colour] (hint: expected one of: base, calibration, description, "
        "measured, metres_per_unit, name, wheel_separation)",
    ]


def test_a_profile_without_its_name_says_what_the_name_is_for(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("base: enki\n")
    with pytest.raises(UserError) as info:
        robot_model(str(path))
    said = "missing required key 'name' [at name] (hint: the profile's name, for reports)"
    assert str(info.value) == f"{path}:1:1: {said}"


def test_a_topic_map_value_is_located_at_the_value_without_pydantic_words(tmp_path):
    path = tmp_path / "t.yaml"
    path.write_text("odom: /odom\nsensors: {front_middle: /x}\n")
    with pytest.raises(UserError) as info:
        load_topics(path)
    (problem,) = info.value.problems
    assert (problem.line, problem.column, problem.path) == (2, 10, "sensors")
    assert problem.message.startswith("no sensor named 'front_middle'") and "Value error" not in str(problem)
    assert problem.hint.startswith("sensors: ")  # what the key is for


def test_a_backend_option_out_of_range_gives_the_range():
    with pytest.raises(UserError) as info:
        BUILTIN["sim"].parse_options({"physics_hz": "10"})
    assert str(info.value) == (
        "--backend-opt: backend 'sim' option 'physics_hz': Input should be greater than or equal to 50 "
        "[at physics_hz] (hint: allowed: >= 50 and <= 2000)"
    )
    with pytest.raises(UserError, match=r"backend 'sim' has no option 'physics'.*did you mean 'physics_hz'"):
        BUILTIN["sim"].parse_options({"physics": "10"})


def test_every_bad_spawn_given_to_a_world_import_is_named():
    """Before: only the first error of the first bad spawn, and no hint."""
    with pytest.raises(UserError) as info:
        import_world(COURSE_WORLD, spawns={"a": (0.1, 0.1, "90"), "b": (0.1, 0.1, 0.0), "c": ("1 parsec", 0, 0)})
    problems = info.value.problems
    assert [p.file for p in problems] == ["<spawns>", "<spawns>"]
    assert problems[0].message == "bad spawn: 90 rad is more than a full turn (an angle without a unit is in radians)"
    assert problems[0].hint.startswith("did you mean 90deg?")
    assert problems[1].path.startswith("c.") and problems[1].message.startswith("bad spawn: ")


def test_a_gazebo_box_too_thick_for_a_wall_says_how_thick_a_wall_may_be(tmp_path):
    world = tmp_path / "w.world"
    world.write_text(
        "<sdf version='1.6'><world name='w'><model name='m'><link name='slab'><collision name='c'>"
        "<geometry><box>\n<size>3 2 0.1</size></box></geometry></collision></link></model></world></sdf>"
    )
    with pytest.raises(UserError) as info:
        import_world(world)
    (problem,) = info.value.problems
    assert problem.message == "box of 'slab' cannot be a wall: Input should be less than or equal to 1"
    assert (problem.file, problem.line, problem.hint) == (str(world), 2, "allowed: > 0 and <= 1 m")


def test_a_bad_blackboard_value_is_said_in_one_line_as_a_mission_value_would_be():
    """Before: pydantic's own report, four lines with a web address, in the run's failure reason."""
    from thymio_bt.testing import run_tree, world

    tree = {"sequence": [{"SetBlackboard": {"key": "x", "value": 100}}, {"TurnAngle": {"angle": "bb:x"}}]}
    result = run_tree(tree, world("corridor"), seconds=2)
    assert result.status == "FAILURE"
    assert result.reason == (
        "blackboard value for angle is invalid: Input should be less than or equal to 6.283185307179586 "
        "[at angle] (hint: allowed: >= -6.28319 and <= 6.28319 rad)"
    )
