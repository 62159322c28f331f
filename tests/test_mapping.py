"""The micromouse behaviours: the cell map and flood fill, the grid pose, and mapping, planning and
moving on small contest-style worlds (18 cm cells, 12 mm walls)."""

import math
from itertools import pairwise
from pathlib import Path

import pytest

from thymio_bt.maze.cellmap import CellMap, GridFrame, centre_cells
from thymio_bt.maze.generate import contest_maze
from thymio_bt.maze.micromouse import maze_from_cells, parse_micromouse, to_text
from thymio_bt.mission import load_mission
from thymio_bt.robot.noise import REALISTIC
from thymio_bt.run.runner import run_mission
from thymio_bt.testing import run_tree

ROOT = Path(__file__).resolve().parents[1]

CELL = 0.18


def text_maze(text):
    return maze_from_cells(parse_micromouse(text.strip("\n") + "\n"), "test")


def test_marking_a_side_marks_the_neighbours_side_too_and_the_outline_is_a_wall():
    cells = CellMap(3, 2)
    cells.mark((0, 0), "E", True)
    assert cells.wall((1, 0), "W") is True
    assert cells.wall((0, 0), "N") is None  # not seen yet
    assert cells.wall((0, 0), "S") is True and cells.wall((2, 1), "E") is True


def test_flood_fill_counts_steps_around_known_walls_and_assumes_unknown_sides_open():
    cells = CellMap(3, 1)
    assert cells.distances({(2, 0)}) == {(2, 0): 0, (1, 0): 1, (0, 0): 2}
    cells.mark((1, 0), "E", True)
    assert (0, 0) not in cells.distances({(2, 0)})  # the only way is walled off: no path
    assert cells.distances({(2, 0)}, known_only=True) == {(2, 0): 0}


def test_the_next_side_goes_downhill_straight_on_when_as_good_and_a_straight_run_counts_cells():
    cells = CellMap(4, 4)
    for i in range(3):
        cells.mark((i, 0), "E", False)
    cells.mark((3, 0), "N", False)
    distance = cells.distances({(3, 1)}, known_only=True)
    assert cells.next_side((0, 0), "E", distance, known_only=True) == "E"
    assert cells.straight_run((0, 0), "E", distance) == 3  # to (3, 0), where the path turns north
    open_map = CellMap(2, 2)
    both = open_map.distances({(1, 1)})
    assert open_map.next_side((0, 0), "N", both) == "N" and open_map.next_side((0, 0), "E", both) == "E"


def test_the_contests_goal_is_the_centre_block():
    assert centre_cells(16, 16) == {(7, 7), (8, 7), (7, 8), (8, 8)}
    assert centre_cells(5, 4) == {(2, 1), (2, 2)}


def test_a_grid_frame_correction_maps_that_odometry_pose_exactly_and_stays_rigid():
    frame = GridFrame()
    frame.correct((1.0, 2.0, 0.1), (1.01, 1.98, 0.0))
    x, y, yaw = frame.to_maze(1.0, 2.0, 0.1)
    assert (x, y, yaw) == pytest.approx((1.01, 1.98, 0.0))
    # a step of 0.1 m along the odometry heading is a step of 0.1 m along the maze heading
    x2, y2, _ = frame.to_maze(1.0 + 0.1 * math.cos(0.1), 2.0 + 0.1 * math.sin(0.1), 0.1)
    assert (x2 - x, y2 - y) == pytest.approx((0.1, 0.0), abs=1e-12)


DEAD_END = """
o---o---o---o
| S         |
o---o---o---o
"""


def test_map_walls_marks_an_opening_ahead_and_the_cell_visited():
    result = run_tree({"MapWalls": {}}, text_maze(DEAD_END), seconds=5)
    end = [e for e in result.events if e["kind"] == "behaviour_end"][-1]
    assert result.status == "SUCCESS"
    assert (end["cell"], end["side"], end["wall"], end["visited"]) == ([0, 0], "E", False, 1)


def test_plan_move_then_move_cells_drives_to_the_goal_cell_centre():
    maze = text_maze(DEAD_END.replace("        |", "      G |"))
    tree = {
        "sequence": [
            {"MapWalls": {}},
            {"PlanMove": {"target": "goal", "known_only": False}},
            {"MoveDistance": {"distance": "bb:move_centre"}},
            {"TurnAngle": {"angle": "bb:move_turn"}},
            {"MoveCells": {"distance": "bb:move_distance"}},
        ]
    }
    result = run_tree(tree, maze, seconds=20)
    assert result.status == "SUCCESS" and result.collisions == 0
    axle_x = result.final_pose.x - 0.0243 * math.cos(result.final_pose.yaw)
    assert axle_x == pytest.approx(1.5 * CELL, abs=0.002)  # one cell on: (1, 0)'s centre


def test_plan_move_fails_with_no_path_when_the_map_closes_the_way():
    closed = """
o---o---o---o
| S     | G |
o---o---o---o
"""
    tree = {
        "sequence": [
            {"MapWalls": {}},
            {"MoveCells": {"distance": "18cm"}},
            {"MapWalls": {}},
            {"PlanMove": {"target": "goal"}},
        ]
    }
    result = run_tree(tree, text_maze(closed), seconds=5)
    assert result.status == "FAILURE" and result.code == "NO_PATH"


def test_plan_move_without_a_goal_region_is_a_clear_input_failure():
    result = run_tree({"PlanMove": {"target": "goal"}}, text_maze(DEAD_END), seconds=5)
    assert result.status == "FAILURE" and result.code == "INVALID_INPUT"
    assert "no goal region" in result.reason


def test_at_target_holds_only_in_the_target():
    start_here = run_tree({"AtTarget": {"target": "start"}}, text_maze(DEAD_END), seconds=1)
    not_centre = run_tree({"AtTarget": {"target": "centre"}}, text_maze(DEAD_END), seconds=1)
    assert start_here.status == "SUCCESS" and not_centre.status == "FAILURE"


def mission_in(tmp_path, cells, **settings):
    path = tmp_path / "maze.txt"
    path.write_text(to_text(cells))
    return run_mission(
        load_mission(f"{ROOT}/missions/micromouse.yaml", settings, maze=path), seed=settings and 3 or None
    )


@pytest.mark.parametrize("seed", [0, 1])
def test_the_mission_solves_generated_8x8_contest_mazes_and_reports_its_phases(tmp_path, seed):
    result = mission_in(tmp_path, contest_maze(seed, size=8))
    assert result.status == "SUCCESS" and result.collisions == 0 and result.goal.reached
    phases = {p.name: p.as_dict() for p in result.phases}
    assert list(phases) == ["search", "return", "fast run"]
    assert phases["fast run"]["duration"] <= phases["search"]["duration"]
    assert phases["search"]["cells"] >= 4
    assert result.goal.t == pytest.approx(phases["search"]["end"], abs=3.0)


def test_the_mission_with_realistic_noise_reaches_the_goal(tmp_path):
    noise = REALISTIC.settings()
    result = mission_in(tmp_path, contest_maze(4, size=8), **noise)
    assert result.status == "SUCCESS" and result.goal.reached


def test_move_cells_maps_the_side_walls_of_the_cells_it_drives_through():
    corridor = """
o---o---o---o---o
| S             |
o---o   o---o---o
|   |   |   |   |
o---o---o---o---o
"""
    result = run_tree({"MoveCells": {"distance": "54cm"}}, text_maze(corridor), seconds=20)
    assert result.status == "SUCCESS" and result.collisions == 0
    # the corridor is the row y in [0.18, 0.36]; its north side is the outline, known from the start
    walls = {tuple(w) for w in result.maze_map["walls"]}
    assert walls == {(0.36, 0.18, 0.54, 0.18), (0.54, 0.18, 0.72, 0.18)}  # south of cells (2, 1), (3, 1)
    assert result.maze_map["open_sides"] == 1  # south of (1, 1)


def test_the_side_bias_is_a_median_that_a_few_wild_readings_do_not_move():
    from thymio_bt.maze.cellmap import RunningMedian

    bias = RunningMedian(window=5)
    for value in (0.007, 0.0069, 0.03, 0.0071, -0.02, 0.007):
        bias.add(value)
    assert bias.median == pytest.approx(0.007) and bias.count == 6 and len(bias.values) == 5


@pytest.mark.parametrize("robot", ["course", "enki", "real"])
def test_the_mission_solves_a_16x16_contest_maze_with_noise_on_every_robot_model(tmp_path, robot):
    noise = REALISTIC.settings()
    result = mission_in(tmp_path, contest_maze(12), robot=robot, **noise)
    assert result.status == "SUCCESS" and result.collisions == 0 and result.goal.reached
    phases = {p.name: p.as_dict() for p in result.phases}
    assert phases["fast run"]["duration"] < phases["search"]["duration"]


def test_the_report_map_has_the_distances_to_the_goal_and_the_shortest_known_path():
    result = run_mission(load_mission(f"{ROOT}/missions/micromouse.yaml"))
    cells = result.maze_map
    assert cells["goal"] == [[0, 3]]  # the 4 x 4 example's G cell
    path = cells["path"]
    assert path[0] == [0, 0] and path[-1] == [0, 3]
    steps = {(i, j): d for i, j, d in cells["distances"]}
    assert [steps[tuple(p)] for p in path] == list(range(len(path) - 1, -1, -1))
    assert all(abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1 for a, b in pairwise(path))


@pytest.mark.parametrize(("seed", "size"), [(1, 12), (7, 16)])
def test_a_wall_ahead_is_believed_as_far_as_the_map_may_have_drifted(tmp_path, seed, size):
    """25 cm cells, Enki's robot: after a turn a few degrees off and a run through open cells the
    map was 4 cm off, the wall ahead that said so was refused (over 2.4 cm), and the robot drove
    into it. The fix is now believed up to the drift the distance driven allows."""
    import yaml

    cells = maze_from_cells(contest_maze(seed, size=size, loops=0.1), "wide", cell=0.25)
    path = tmp_path / "wide.yaml"
    path.write_text(yaml.safe_dump(cells.to_yaml_dict(), sort_keys=False))
    mission = load_mission(
        f"{ROOT}/missions/micromouse.yaml", {"cell": "0.25", "robot": "enki"}, maze=path, start="start"
    )
    result = run_mission(mission, seed=0)
    assert result.status == "SUCCESS" and result.collisions == 0 and result.goal.reached, result.reason
