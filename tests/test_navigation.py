"""The report's navigation: GoToPose, FollowWaypoints, and the avoidance modes on their own."""

import math
from itertools import pairwise
from pathlib import Path

import pytest

from thymio_bt.maze import Obstacle, load_maze
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.testing import run_tree, world

ROOT = Path(__file__).resolve().parents[1]

ARENA = load_maze(f"{ROOT}/mazes/report_arena.yaml")


def events(result, kind, name=None):
    return [e for e in result.events if e["kind"] == kind and (name is None or e.get("name") == name)]


def test_go_to_pose_reaches_the_goal_within_its_tolerance():
    result = run_tree({"GoToPose": {"goal": [0.3, 0.2], "tolerance": "5mm"}}, ARENA, seconds=60)
    assert result.status == "SUCCESS"
    assert math.dist((result.final_pose.x, result.final_pose.y), (0.3, 0.2)) <= 0.005


def test_follow_waypoints_visits_every_waypoint_in_order():
    points = [[0.0, -0.4], [0.0, 0.0], [-0.3, 0.2]]
    result = run_tree({"FollowWaypoints": {"waypoints": points}}, ARENA, seconds=120)
    reached = events(result, "waypoint_reached")
    assert result.status == "SUCCESS" and [e["index"] for e in reached] == [0, 1, 2]
    for event, point in zip(reached, points, strict=True):
        assert math.dist((event["pose"]["x"], event["pose"]["y"]), point) <= 0.01


@pytest.mark.parametrize(
    "node",
    ["GoToPose: {goal: [0.9, 0.8], tolerance: 0.2mm}", "FollowWaypoints: {waypoints: [[0.9, 0.8]], tolerance: 0.2mm}"],
)
def test_a_tolerance_tighter_than_the_controller_holds_fails_instead_of_spinning(tmp_path, node):
    path = tmp_path / "m.yaml"
    path.write_text(f"maze: arena\nstart: centre\ntree:\n  {node}\n")
    result = Run(load_mission(path)).run()
    assert (result.status, result.code) == ("FAILURE", "NO_PROGRESS")  # not a 300 s TIMEOUT
    assert result.sim_time < 30 and "tighter than the controller can hold (try tolerance: 5mm)" in result.reason
    path.write_text(f"maze: arena\nstart: centre\ntree:\n  {node.replace('0.2mm', '5mm')}\n")
    assert Run(load_mission(path)).run().status == "SUCCESS"  # the suggestion works


def test_speed_limits_are_respected():
    from thymio_bt.logs.recording import Recorder

    mission = load_mission(f"{ROOT}/missions/waypoints.yaml")
    recorder = Recorder()
    Run(mission).run(on_tick=recorder)
    assert max(abs(s["cmd"][0]) for s in recorder.samples) <= 0.05 + 1e-6
    assert max(abs(s["cmd"][1]) for s in recorder.samples) <= math.pi + 1e-6


def test_waypoint_mission_reaches_every_waypoint_in_the_reports_time():
    result = Run(load_mission(f"{ROOT}/missions/waypoints.yaml")).run()
    assert result.status == "SUCCESS" and result.collisions == 0
    assert len(events(result, "waypoint_reached")) == 5
    assert 60 < result.sim_time < 150  # ~4.2 m at <= 5 cm/s: the report's order of magnitude


def test_the_block_is_bypassed_on_the_left_without_collision():
    result = Run(load_mission(f"{ROOT}/missions/waypoints_obstacles.yaml")).run()
    assert result.status == "SUCCESS"
    assert result.collisions == 0 and result.min_clearance > 0.005
    assert len(events(result, "waypoint_reached")) == 5
    turning_left = [e for e in events(result, "behaviour_end", "TurnUntilClear") if e["status"] == "SUCCESS"]
    assert turning_left, "the avoidance never ran"
    # left-wall avoidance on the leg from (-0.5, 0) to (0.5, 0): the robot passes north of the block
    passing = [(x, y) for t, x, y, yaw in result.trajectory if abs(x) < 0.05 and -0.2 < y < 0.3]
    assert passing and min(y for _, y in passing) > 0.04


def test_turn_until_clear_adds_the_angle_it_turned_to_the_counter():
    result = run_tree({"TurnUntilClear": {"direction": "left"}}, world("corridor"), start=[0.72, 0.1, 0], seconds=20)
    end = events(result, "behaviour_end", "TurnUntilClear")[0]
    assert result.status == "SUCCESS"
    assert end["counter"] == pytest.approx(result.final_pose.yaw, abs=1e-3) and end["counter"] > 0.3


def test_turn_back_returns_the_counter_to_zero_or_fails_when_blocked():
    tree = {"sequence": [{"SetBlackboard": {"key": "avoid_turn", "value": 0.8}}, {"TurnBack": {}}]}
    free = run_tree(tree, ARENA, start=[0.0, 0.0, 0.8], seconds=20)
    assert free.status == "SUCCESS"
    assert free.final_pose.yaw == pytest.approx(0.0, abs=0.02)
    blocked = run_tree(tree, world("corridor"), start=[0.72, 0.1, 0.8], seconds=20)
    assert blocked.status == "FAILURE"
    assert blocked.code == "BLOCKED" and blocked.failed_path.endswith("TurnBack")
    assert "obstacle ahead" in events(blocked, "behaviour_end", "TurnBack")[0]["reason"]


def test_obstacle_ahead_uses_the_reports_thresholds():
    near = run_tree({"ObstacleAhead": {}}, world("corridor"), start=[0.72, 0.1, 0], seconds=1)  # 2.3 cm
    far = run_tree({"ObstacleAhead": {}}, world("corridor"), start=[0.70, 0.1, 0], seconds=1)  # 4.3 cm
    assert (near.status, far.status) == ("SUCCESS", "FAILURE")


def test_corner_case_left_is_the_long_way_round(tmp_path):
    """The report's Fig. 10: a wall that reaches far to the left of the path and only a little to the
    right. Left-wall avoidance always goes left, so the robot follows the long side: it still
    reaches the goal, on a path several times the straight line (the global optimum turns right)."""
    maze = ARENA.model_copy(update={"obstacles": [Obstacle(center=(0.0, 0.1), size=(0.04, 0.5))]})
    maze_file = tmp_path / "corner.yaml"
    import yaml

    maze_file.write_text(yaml.safe_dump(maze.to_yaml_dict()))
    mission = load_mission(f"{ROOT}/missions/waypoints_obstacles.yaml", maze=maze_file, start="-0.5,0,0", overrides={})
    mission.tree.children[0].children[1].params = (
        mission.tree.children[0].children[1].params.model_copy(update={"waypoints": [(0.5, 0.0)]})
    )
    result = Run(mission).run()
    assert result.status == "SUCCESS" and result.collisions == 0
    path = sum(math.dist(a[1:3], b[1:3]) for a, b in pairwise(result.trajectory))
    assert path > 1.5  # the straight line is 1.0 m; round the short end ~1.2 m
    assert max(y for _, x, y, _ in result.trajectory) > 0.4  # went round the far (left) end
