"""Every mission in missions/ end to end, with the course's acceptance numbers, via the run report."""

import math
from pathlib import Path

import pytest
import yaml

from thymio_bt.maze import load_maze
from thymio_bt.maze.generate import mirrored, path_maze, random_path, turns_along
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import COURSE
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]

AXLE_X = COURSE.axle_x

MISSIONS = sorted((ROOT / "missions").glob("*.yaml"))


def run(name, **kwargs):
    return Run(load_mission(f"{ROOT}/missions/{name}.yaml", **kwargs)).run()


def ends(result, name):
    return [e for e in result.events if e["kind"] == "behaviour_end" and e["name"] == name and e["status"] == "SUCCESS"]


def turn_letters(result):
    return "".join("L" if e["angle"] > 0 else "R" for e in ends(result, "TurnAngle"))


def axle(pose):
    return pose.x + AXLE_X * math.cos(pose.yaw), pose.y + AXLE_X * math.sin(pose.yaw)


@pytest.mark.parametrize("path", MISSIONS, ids=[p.stem for p in MISSIONS])
def test_every_mission_succeeds_without_collision(path):
    result = Run(load_mission(path)).run()
    assert result.status == "SUCCESS", f"{result.failed_path}: {result.reason}"
    assert result.collisions == 0
    # a Thymio turning in place in an 18 cm micromouse cell clears its walls by 4 mm at best
    least = 0.003 if path.stem == "micromouse" else 0.005
    assert result.min_clearance is None or result.min_clearance > least


def test_part1_stops_5cm_from_the_wall_then_respawns_only_after_the_delete():
    result = run("maze_part1_2")
    part1 = [e for e in result.events if e["kind"] == "behaviour_end" and e["path"].endswith("part 1")][0]
    assert part1["proximity"]["front_center"] == pytest.approx(0.050, abs=0.001)
    kinds = [e["kind"] for e in result.events]
    delete, spawn = kinds.index("delete_entity"), kinds.index("spawn_entity")
    assert delete < spawn
    assert result.events[delete]["t"] < result.events[spawn]["t"]
    assert result.events[spawn]["pose"] == pytest.approx({"x": 0.5, "y": 0.3, "yaw": round(math.pi / 2, 6)})


def test_part2_ends_in_the_pocket_with_the_axle_centred_after_every_turn():
    result = run("maze_part1_2")
    assert result.final_pose.x == pytest.approx(0.300, abs=0.005)
    assert result.final_pose.y == pytest.approx(0.489, abs=0.005)
    assert result.final_pose.yaw == pytest.approx(math.pi / 2, abs=math.radians(0.5))
    assert result.final_proximity["front_center"] == pytest.approx(0.05, abs=0.001)
    turns = ends(result, "TurnAngle")
    assert turn_letters(result) == "LLLL"
    expected = [(0.5, 0.7), (0.1, 0.7), (0.1, 0.3), (0.3, 0.3)]  # mazes.md turn points
    for event, point in zip(turns, expected, strict=True):
        assert axle(Pose(**event["pose"])) == pytest.approx(point, abs=0.005)


def test_bonus_turns_rrrlrllllr_and_stops_in_the_last_pocket():
    result = run("maze_bonus")
    assert turn_letters(result) == "RRRLRLLLLLR"
    assert result.final_pose.x == pytest.approx(1.7, abs=0.005)
    assert result.final_pose.y == pytest.approx(0.3107, abs=0.005)
    decisions = [e["decision"] for e in ends(result, "ChooseTurn")]
    assert decisions[-1] == "dead_end" and len(decisions) == 12


@pytest.mark.parametrize("side", ["left", "right"])
def test_6x6_is_left_through_the_top_gap(side):
    result = run(f"maze_6x6_{side}")
    assert result.final_pose.y > 0.205
    assert -0.4 < result.final_pose.x < -0.2


def test_same_seed_gives_identical_reports():
    first = run("maze_part1_2", overrides={"noise.wheel": "0.02", "noise.range_sd": "0.0005"})
    second = run("maze_part1_2", overrides={"noise.wheel": "0.02", "noise.range_sd": "0.0005"})
    a, b = first.report(), second.report()
    for volatile in ("wall_time", "real_time_factor"):
        a.pop(volatile), b.pop(volatile)
    assert a == b


def test_bonus_in_the_mirrored_maze_makes_the_mirrored_turns(tmp_path):
    maze = mirrored(load_maze(f"{ROOT}/mazes/two_parts_maze.yaml"), axis_x=1.0)
    (tmp_path / "mirror.yaml").write_text(yaml.safe_dump(maze.to_yaml_dict()))
    spawn = maze.spawns["bonus"]
    result = run("maze_bonus", maze=tmp_path / "mirror.yaml", start=f"{spawn.x},{spawn.y},{spawn.yaw}")
    assert result.status == "SUCCESS" and result.collisions == 0
    assert turn_letters(result) == "LLLRLRRRRRL"


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_bonus_follows_other_corridors_of_the_same_kind(tmp_path, seed):
    path = random_path(14, seed=seed)
    maze = path_maze(path)
    (tmp_path / "path.yaml").write_text(yaml.safe_dump(maze.to_yaml_dict()))
    s = maze.spawns["start"]
    result = run("maze_bonus", maze=tmp_path / "path.yaml", start=f"{s.x},{s.y},{s.yaw}")
    assert result.status == "SUCCESS" and result.collisions == 0
    assert turn_letters(result) == turns_along(path)
    last = path[-1]
    assert math.dist(axle(result.final_pose), ((last[0] + 0.5) * 0.2, (last[1] + 0.5) * 0.2)) < 0.06


@pytest.mark.parametrize("robot", ["course", "enki", "real"])
def test_bonus_takes_another_grid_from_its_cell_parameter(tmp_path, robot):
    """On a 0.3 m grid the side walls are beyond the course robot's side rays: it stops where cell
    says, turns to look, and its axle ends near the middle of each corridor it turns into."""
    path = random_path(10, seed=4)
    maze = path_maze(path, cell=0.3)
    (tmp_path / "wide.yaml").write_text(yaml.safe_dump(maze.to_yaml_dict()))
    s = maze.spawns["start"]
    start = f"{s.x},{s.y},{s.yaw}"
    result = run("maze_bonus", overrides={"cell": "30cm", "robot": robot}, maze=tmp_path / "wide.yaml", start=start)
    assert result.status == "SUCCESS" and result.collisions == 0
    assert turn_letters(result) == turns_along(path)
    last = path[-1]
    assert math.dist(axle(result.final_pose), ((last[0] + 0.5) * 0.3, (last[1] + 0.5) * 0.3)) < 0.08


@pytest.mark.parametrize("seed", range(20, 30))
def test_bonus_with_noise_reaches_the_last_pocket(seed):
    """Lateral drift from odometry errors once made seed 25 turn left into a wall and stop there,
    'successfully'; MoveUntilWall's centring keeps the robot where ChooseTurn can see both sides."""
    noise = {"noise.range_sd": "0.001", "noise.wheel": "0.027", "noise.odometry": "0.01"}
    result = Run(load_mission(f"{ROOT}/missions/maze_bonus.yaml", noise), seed=seed).run()
    assert result.status == "SUCCESS" and turn_letters(result) == "RRRLRLLLLLR"
    assert result.final_pose.x == pytest.approx(1.7, abs=0.01)
    assert result.final_pose.y == pytest.approx(0.311, abs=0.01)


def test_the_final_tree_shows_each_node_as_the_run_ended():
    """Drawn when first read, yet as the run ended: a run cut by its time limit shows the node it
    cut RUNNING (stopping it afterwards made it INVALID), a finished run each node's last status."""
    cut = Run(load_mission(f"{ROOT}/missions/maze_part1_2.yaml", overrides={"time_limit": "2"}))
    assert cut.final_tree == ""
    assert cut.run().status == "TIMEOUT" and cut.root.status.name == "INVALID"
    assert "--> part 1 [*] -- no wall in range" in cut.final_tree.splitlines()[1]
    done = Run(load_mission(f"{ROOT}/missions/maze_part1_2.yaml"))
    assert done.run().status == "SUCCESS"
    assert "--> part 1 [✓] -- stopped at 0.0501 m" in done.final_tree.splitlines()[1]
