"""expect: a run succeeds only when its tree succeeds and the mission's criteria hold on the ground
truth (goal region, no collision, time bound, front gaps by geometry); the failed ones are named."""

import math
from pathlib import Path

import pytest

from thymio_bt.errors import UserError
from thymio_bt.maze import load_maze
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import COURSE
from thymio_bt.run.runner import Run
from thymio_bt.run.sweep import sweep
from thymio_bt.run.verdict import front_gap

ROOT = Path(__file__).resolve().parents[1]

MISSION = """\
maze: two_parts_maze
start: part1
expect:
{expect}
tree:
  MoveUntilWall: {{distance: 5cm}}
"""


def run(tmp_path, expect: str):
    path = tmp_path / "m.yaml"
    path.write_text(MISSION.format(expect=expect))
    return Run(load_mission(path)).run()


def test_all_criteria_met_is_a_success_with_the_check_in_the_report(tmp_path):
    result = run(
        tmp_path,
        "  goal: {centre: [0.4893, 0.1], radius: 2mm}\n  no_collision: true\n  max_time: 10s\n"
        "  gaps: [{after: MoveUntilWall, distance: 5cm, tolerance: 1mm}]",
    )
    assert result.status == "SUCCESS" and result.report()["expectations"] == {"met": True, "failed": []}


@pytest.mark.parametrize(
    "expect, message",
    [
        ("  goal: {centre: [0.3, 0.1], radius: 1cm}", "goal: ended 189.2 mm from (0.3, 0.1), more than 10 mm"),
        ("  max_time: 2s", "max_time: took 4.3 s, more than 2 s"),
        ("  gaps: [{after: MoveUntilWall, distance: 4cm}]", "the front gap was 5.01 cm, not 4 ± 0.3 cm"),
        ("  gaps: [{after: Nothing, distance: 4cm}]", "gaps: no node matching 'Nothing' ended with a robot"),
        ("  leaves_maze: true", "leaves_maze: ended inside the maze at (0.49, 0.10)"),
        ("  dead_end: {distance: 4cm}", "dead_end: stopped 5.0 cm from the wall, wanted 4.0 +- 0.5 cm"),
        ("  dead_end: {distance: 5cm, side: 3cm}", "dead_end: stopped where the left side is open: not a dead end"),
    ],
)
def test_a_tree_success_that_misses_an_expectation_is_a_failure_naming_it(tmp_path, expect, message):
    result = run(tmp_path, expect)
    assert (result.status, result.code, result.failed_path) == ("FAILURE", "EXPECTATION", "expect")
    assert message in result.reason and result.report()["expectations"]["met"] is False


def test_a_collision_fails_no_collision(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(
        "maze: two_parts_maze\nstart: part1\nexpect: {no_collision: true}\n"
        "tree:\n  force_success: {MoveDistance: {distance: 50cm, timeout: 10}}\n"
    )
    result = Run(load_mission(path)).run()
    assert (result.status, result.code) == ("FAILURE", "EXPECTATION") and "no_collision: 1 collision" in result.reason


def test_the_front_gap_is_measured_by_geometry():
    maze = load_maze(f"{ROOT}/mazes/two_parts_maze.yaml")
    assert front_gap(maze, COURSE, Pose(0.4893, 0.1, 0.0)) == pytest.approx(0.0500, abs=2e-4)
    behind = front_gap(maze, COURSE, Pose(0.4893, 0.1, math.pi))  # the west wall, far behind
    assert math.isfinite(behind) and behind > 0.3


@pytest.mark.parametrize("maze_file", [f"{ROOT}/mazes/two_parts_maze.yaml", f"{ROOT}/mazes/maze_6x6.yaml"])
def test_a_ray_meets_the_nearest_face_of_every_wall_it_crosses(maze_file):
    """ray_distance skips the walls behind the ray; it finds what trying every face finds, bit for bit,
    along the axes (whose cosine or sine is a zero of either sign) and at any angle."""
    import random

    from thymio_bt.robot.placement import _ray_segment, ray_distance

    maze = load_maze(maze_file)
    xmin, ymin, xmax, ymax = maze.bounds()
    rng = random.Random(3)
    yaws = [0.0, -0.0, math.pi / 2, -math.pi / 2, math.pi, -math.pi] + [rng.uniform(-4, 4) for _ in range(40)]
    for yaw in yaws:
        for _ in range(10):
            x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
            c, s = math.cos(yaw), math.sin(yaw)
            every = [
                _ray_segment(x, y, c, s, *a, *b)
                for wall in maze.walls
                for a, b in zip(wall.corners(), [*wall.corners()[1:], wall.corners()[0]], strict=True)
            ]
            assert ray_distance(maze, x, y, yaw) == min((d for d in every if d is not None), default=math.inf)


def test_expectations_are_validated_with_units_and_places(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(
        "maze: arena\nstart: centre\nexpect:\n  goal: {centre: [1, 2], radius: 3 s}\n  colision: true\ntree: Stop\n"
    )
    with pytest.raises(UserError) as err:
        load_mission(path)
    messages = [(p.line, p.message) for p in err.value.problems]
    assert messages[0][0] == 4 and "length" in messages[0][1]
    assert (5, "unknown key 'colision'") in messages


def test_in_another_maze_only_place_free_criteria_hold(tmp_path):
    mission = load_mission(f"{ROOT}/missions/maze_bonus.yaml", maze=f"{ROOT}/mazes/arena.yaml", start="0.6,0.6,0")
    assert mission.expect.goal is None and mission.expect.no_collision


def test_the_wall_followers_expect_to_leave_any_maze():
    """leaves_maze holds in any maze: a wall follower whose odometry says it is out while it is
    still inside (Enki's robot once on a 0.25 m grid) does not report SUCCESS there."""
    for side in ("left", "right"):
        mission = load_mission(
            f"{ROOT}/missions/maze_6x6_{side}.yaml", maze=f"{ROOT}/mazes/arena.yaml", start="0.6,0.6,0"
        )
        assert mission.expect.goal is None and mission.expect.leaves_maze and mission.expect.no_collision


def test_expectations_may_name_the_mission_s_parameters(tmp_path):
    """maze_bonus's dead end has its side walls within a cell: `side: $cell`, --set cell changes it."""
    mission = load_mission(
        f"{ROOT}/missions/maze_bonus.yaml", {"cell": "30cm"}, maze=f"{ROOT}/mazes/arena.yaml", start="0.6,0.6,0"
    )
    assert mission.expect.dead_end is not None and mission.expect.dead_end.side == pytest.approx(0.3)
    path = tmp_path / "m.yaml"
    path.write_text(
        MISSION.format(expect="  dead_end: {distance: 5cm, side: $fast}").replace(
            "tree:", "parameters: {fast: 1 m/s}\ntree:"
        )
    )
    with pytest.raises(UserError) as err:
        load_mission(path)
    assert (err.value.problems[0].line, err.value.problems[0].message) == (4, "expected a length (in m), got a speed")


def test_the_schema_knows_every_expectation():
    from thymio_bt.analysis.schema import mission_schema
    from thymio_bt.plan.expect import Expect

    assert set(mission_schema()["properties"]["expect"]["properties"]) == set(Expect.model_fields)


def test_a_sweep_counts_a_missed_expectation_as_a_failure(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(MISSION.format(expect="  gaps: [{after: MoveUntilWall, distance: 5cm, tolerance: 0.2mm}]"))
    result = sweep(path, runs=6, overrides={"noise.range_sd": "0.003"})
    failed = [r for r in result.results if r["status"] != "SUCCESS"]
    assert failed and all(r["code"] == "EXPECTATION" for r in failed) and result.successes == 6 - len(failed)


def test_the_course_missions_meet_their_expectations():
    for name in ("maze_part1_2", "maze_bonus", "course_full"):
        result = Run(load_mission(f"{ROOT}/missions/{name}.yaml")).run()
        assert result.status == "SUCCESS" and result.report()["expectations"]["met"], name


def test_a_dead_end_expected_where_no_wall_is_ahead_says_so(tmp_path):
    (tmp_path / "corner.yaml").write_text(
        "name: corner\nwalls:\n  - {from: [0, 0], to: [0.6, 0]}\n  - {from: [0, 0], to: [0, 0.6]}\n"
    )
    path = tmp_path / "m.yaml"
    path.write_text("maze: corner.yaml\nstart: [0.3, 0.3, 45deg]\nexpect:\n  dead_end: {distance: 5cm}\ntree: Stop\n")
    result = Run(load_mission(path)).run()
    assert (result.status, result.reason) == ("FAILURE", "dead_end: stopped facing no wall (wanted 5 cm from one)")
