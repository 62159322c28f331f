"""Each behaviour on small generated worlds, with numbers (thymio_bt.testing helpers)."""

import math

import pytest

from thymio_bt.maze.generate import perfect_maze
from thymio_bt.robot.interface import SENSOR_NAMES, Pose
from thymio_bt.robot.model import COURSE
from thymio_bt.testing import run_tree, world

AXLE_X = COURSE.axle_x

MIRRORED_L = """
+--+--+--+
|       <|
+  +--+--+
|  |
+--+
"""


def ends(result, name):
    return [e for e in result.events if e["kind"] == "behaviour_end" and e["name"] == name]


def axle(pose):
    return pose.x + AXLE_X * math.cos(pose.yaw), pose.y + AXLE_X * math.sin(pose.yaw)


@pytest.mark.parametrize("distance", [0.05, 0.015, 0.08])
def test_move_until_wall_stops_within_a_millimetre(distance):
    result = run_tree({"MoveUntilWall": {"speed": "10cm/s", "distance": distance}}, world("corridor"), seconds=20)
    assert result.status == "SUCCESS"
    assert result.final_proximity["front_center"] == pytest.approx(distance, abs=0.001)
    assert result.collisions == 0


def test_stopping_at_1_5_cm_then_turning_centres_the_axle_in_the_next_corridor():
    tree = {"sequence": [{"MoveUntilWall": {"distance": "1.5cm"}}, {"TurnAngle": {"angle": "-90deg"}}]}
    result = run_tree(tree, world("L"), seconds=30)
    x, y = axle(result.final_pose)
    assert result.status == "SUCCESS"
    assert x == pytest.approx(0.5, abs=0.005)  # the centre line of the corridor going down
    assert result.final_pose.yaw == pytest.approx(-math.pi / 2, abs=math.radians(0.5))


def test_move_until_wall_fails_with_no_wall_when_nothing_comes_into_range():
    open_corridor = world("""
+--+--+--+--+--+--+--+--+--+--+
 >
+--+--+--+--+--+--+--+--+--+--+
""")
    result = run_tree({"MoveUntilWall": {"speed": "5cm/s", "timeout": 5}}, open_corridor, seconds=20)
    assert result.status == "FAILURE" and result.code == "NO_WALL"
    assert "no wall came within" in result.reason
    assert result.sim_time == pytest.approx(5.0, abs=0.11)


def test_deleting_the_robot_mid_move_fails_with_no_robot():
    tree = {
        "parallel": {
            "policy": "success_on_all",
            "children": [
                {"MoveUntilWall": {"speed": "2cm/s"}},
                {"sequence": [{"Wait": {"seconds": 1}}, {"DeleteEntity": {}}]},
            ],
        }
    }
    result = run_tree(tree, world("corridor"), seconds=20)
    assert result.status == "FAILURE" and result.code == "NO_ROBOT"
    assert result.failed_path.endswith("MoveUntilWall")
    assert result.final_pose is None


def test_hitting_a_wall_fails_with_collision():
    result = run_tree({"MoveDistance": {"distance": 1.0}}, world("corridor"), seconds=20)
    assert result.status == "FAILURE" and result.code == "COLLISION"
    assert result.collisions == 1
    assert [e["kind"] for e in result.events].count("collision") == 1


@pytest.mark.parametrize("distance", [0.3, -0.2, 0.0123])
def test_move_distance_within_two_millimetres(distance):
    start = [0.6, 0.6, 0.3]
    result = run_tree({"MoveDistance": {"distance": distance}}, world("arena"), start=start, seconds=20)
    moved = math.hypot(result.final_pose.x - 0.6, result.final_pose.y - 0.6)
    assert result.status == "SUCCESS"
    assert moved == pytest.approx(abs(distance), abs=0.002)
    assert ends(result, "MoveDistance")[0]["distance"] == pytest.approx(distance, abs=0.002)


@pytest.mark.parametrize("angle", ["90deg", "-90deg", "pi", "-45 deg", "2*pi", "10deg"])
def test_turn_angle_within_half_a_degree_about_the_axle(angle):
    from thymio_bt.inputs.units import parse_value

    target = parse_value(angle).value
    result = run_tree({"TurnAngle": {"angle": angle}}, world("arena"), start=[0.6, 0.6, 0.2], seconds=20)
    end = ends(result, "TurnAngle")[0]
    assert result.status == "SUCCESS"
    assert end["angle"] == pytest.approx(target, abs=math.radians(0.5))
    error = (result.final_pose.yaw - (0.2 + target) + math.pi) % (2 * math.pi) - math.pi
    assert abs(error) < math.radians(0.5)
    assert axle(result.final_pose) == pytest.approx(axle(Pose(0.6, 0.6, 0.2)), abs=1e-6)


def test_turn_with_snap_lands_on_the_grid_heading():
    result = run_tree(
        {"TurnAngle": {"angle": "90deg", "snap": "90deg"}}, world("arena"), start=[0.6, 0.6, 0.03], seconds=20
    )
    assert result.final_pose.yaw == pytest.approx(math.pi / 2, abs=1e-3)


def test_turn_by_rear_sensors_squares_the_robot_to_the_wall_behind():
    tree = {
        "sequence": [
            {"MoveUntilWall": {"distance": "3cm"}},
            {"TurnAngle": {"angle": "pi", "mode": "rear_sensors", "tolerance": "0.2deg"}},
        ]
    }
    result = run_tree(tree, world("corridor"), start=[0.4, 0.1, 0.04], seconds=30)
    assert result.status == "SUCCESS"
    scan = result.final_proximity
    assert scan["rear_left"] == pytest.approx(scan["rear_right"], abs=0.061 * math.tan(math.radians(0.2)) + 1e-6)
    assert abs(abs(result.final_pose.yaw) - math.pi) < math.radians(0.3)


def test_turn_by_rear_sensors_fails_without_a_wall_behind():
    result = run_tree(
        {"TurnAngle": {"angle": "90deg", "mode": "rear_sensors"}}, world("arena"), start=[0.6, 0.6, 0], seconds=20
    )
    assert result.status == "FAILURE" and result.code == "NO_WALL"
    assert "rear sensors" in result.reason


@pytest.mark.parametrize(
    "grid, start, decision",
    [
        ("L", "start", "right"),
        (MIRRORED_L, "start", "left"),
        ("pocket", "start", "dead_end"),
    ],
)
def test_choose_turn_decides_when_the_wall_first_comes_into_range(grid, start, decision):
    tree = {
        "parallel": {
            "policy": "success_on_all",
            "children": [{"MoveUntilWall": {"distance": "1.5cm"}}, {"ChooseTurn": {}}],
        }
    }
    result = run_tree(tree, world(grid), start=start, seconds=20)
    choose = ends(result, "ChooseTurn")[0]
    assert result.status == "SUCCESS"
    assert choose["decision"] == decision
    assert choose["proximity"]["front_center"] is not None  # decided with the wall in range
    assert choose["proximity"]["front_center"] > 0.085


#: stop 5 cm before the wall, decide beside the approach, look where not sure
LOOKING_LEG = {
    "sequence": [
        {"parallel": {"policy": "success_on_all", "children": [{"MoveUntilWall": {"distance": "5cm"}}, "ChooseTurn"]}},
        "LookAround",
    ]
}


@pytest.mark.parametrize(("grid", "decision"), [("L", "right"), ("T", "left"), ("pocket", "dead_end")])
def test_choose_turn_is_sure_where_its_side_rays_reach_the_side_walls(grid, decision):
    result = run_tree(LOOKING_LEG, world(grid), seconds=30)
    choose, look = ends(result, "ChooseTurn")[0], ends(result, "LookAround")[0]
    assert result.status == "SUCCESS"
    assert (choose["decision"], choose["certain"]) == (decision, True)
    assert "looked" not in look and look["pose"] == ends(result, "MoveUntilWall")[0]["pose"]  # it did not move


@pytest.mark.parametrize("robot", ["course", "enki", "real"])
@pytest.mark.parametrize(("grid", "decision"), [("L", "right"), ("T", "left"), ("pocket", "dead_end")])
def test_look_around_finds_the_open_side_where_the_side_rays_cannot_reach(grid, decision, robot):
    """On 0.3 m cells the course robot's side rays (10.9 cm reach) see neither side wall, 14.5 cm
    away: ChooseTurn guesses left, not sure, and LookAround turns to look (Enki's cones reach
    13.85 cm: the robot may be sure there)."""
    result = run_tree(LOOKING_LEG, world(grid, cell=0.3), seconds=60, robot=robot)
    choose, look = ends(result, "ChooseTurn")[0], ends(result, "LookAround")[0]
    assert result.status == "SUCCESS", result.reason
    assert look.get("decision", choose["decision"]) == decision
    if robot == "course":
        assert choose["certain"] is False
        assert look["looked"] == (["left"] if decision == "left" else ["left", "right"])
    assert abs(math.remainder(look["pose"]["yaw"] - choose["pose"]["yaw"], math.tau)) < 0.01  # facing ahead again


@pytest.mark.parametrize("offset", [-0.03, 0.03])
def test_look_around_stops_turning_short_of_a_side_wall_it_would_touch(offset):
    """3 cm off the centre line of a 0.22 m dead end, the axle is 7.5 cm from a side wall and the
    hull sweeps 8 cm about it: turning to face that wall would touch it. The turn stops when a front
    sensor reads under 1 cm, and that side counts as closed."""
    result = run_tree(LOOKING_LEG, world("pocket", cell=0.22), start=[0.11, 0.11 + offset, 0], seconds=40)
    look = ends(result, "LookAround")[0]
    assert result.status == "SUCCESS" and result.collisions == 0, result.reason
    assert (look["decision"], look["looked"]) == ("dead_end", ["left", "right"])
    assert abs(result.final_pose.yaw) < 0.01  # facing ahead again


def test_look_around_halted_mid_turn_stops_the_robot():
    approach, look = LOOKING_LEG["sequence"]
    tree = {
        "sequence": [approach, {"force_success": {"timeout": {"seconds": 0.5, "do": look}}}, {"Wait": {"seconds": 1}}]
    }
    result = run_tree(tree, world("L", cell=0.3), seconds=30)
    halted = ends(result, "LookAround")[0]
    assert result.status == "SUCCESS" and halted["status"] == "INVALID"
    assert halted["pose"]["yaw"] > 0.1  # it was turning to look left
    assert result.final_pose.yaw == pytest.approx(halted["pose"]["yaw"], abs=0.01)  # and turned no further


def test_look_around_without_a_decision_says_so():
    result = run_tree("LookAround", world("L"), seconds=5)
    assert result.status == "FAILURE" and result.code == "INVALID_INPUT"
    assert "run ChooseTurn first" in result.reason


def test_a_decision_taken_close_to_the_wall_is_not_sure_and_looked_at():
    """A leg that starts 5 cm from the wall ahead: the side rays meet that wall, not the sides, so
    they tell nothing (they used to make a T junction a dead end); LookAround finds the way."""
    result = run_tree({"repeat": {"times": 2, "do": LOOKING_LEG}}, world("T"), seconds=30)
    assert result.status == "SUCCESS"
    assert [(e["decision"], e["certain"]) for e in ends(result, "ChooseTurn")] == [("left", True), ("left", False)]
    assert [(e.get("decision"), e.get("looked")) for e in ends(result, "LookAround")] == [
        (None, None),
        ("left", ["left"]),
    ]


def test_turn_angle_reads_its_angle_from_the_blackboard():
    tree = {
        "sequence": [
            {"parallel": {"children": [{"MoveUntilWall": {"distance": "1.5cm"}}, {"ChooseTurn": {}}]}},
            {"TurnAngle": {"angle": "bb:turn_angle"}},
        ]
    }
    result = run_tree(tree, world("L"), seconds=30)
    assert result.status == "SUCCESS"
    assert ends(result, "TurnAngle")[0]["angle"] == pytest.approx(-math.pi / 2, abs=1e-3)


def test_a_missing_blackboard_value_fails_with_invalid_input():
    result = run_tree({"TurnAngle": {"angle": "bb:nothing_here"}}, world("arena"), start="start", seconds=5)
    assert result.status == "FAILURE" and result.code == "INVALID_INPUT"
    assert "nothing_here" in result.reason


def test_conditions():
    wall_ahead = run_tree({"WallAhead": {}}, world("pocket"), start=[0.3, 0.1, 0], seconds=1)
    no_wall = run_tree({"WallAhead": {}}, world("arena"), start="start", seconds=1)
    side_open = run_tree({"SideOpen": {"side": "right"}}, world("L"), start=[0.4, 0.3, 0], seconds=1)
    side_closed = run_tree({"SideOpen": {"side": "left"}}, world("L"), start=[0.4, 0.3, 0], seconds=1)
    assert (wall_ahead.status, no_wall.status) == ("SUCCESS", "FAILURE")
    assert (side_open.status, side_closed.status) == ("SUCCESS", "FAILURE")


def test_wait_and_timeout_use_simulated_time():
    waited = run_tree({"Wait": {"seconds": 2.5}}, world("arena"), seconds=10)
    assert waited.status == "SUCCESS" and waited.sim_time == pytest.approx(2.5, abs=0.11)
    slow = {"timeout": {"seconds": 2, "do": {"MoveDistance": {"distance": 0.3, "speed": "1cm/s"}}}}
    timed_out = run_tree(slow, world("arena"), seconds=10)
    assert timed_out.status == "FAILURE" and timed_out.code == "TIMEOUT"
    assert timed_out.sim_time == pytest.approx(2.0, abs=0.11)
    limit = run_tree({"Wait": {"seconds": 100}}, world("arena"), seconds=3)
    assert limit.status == "TIMEOUT" and limit.sim_time == pytest.approx(3.0, abs=0.11)


def test_spawn_fails_clearly_while_the_name_exists_and_after_delete_succeeds():
    taken = run_tree({"SpawnEntity": {"pose": [0.3, 0.3, 0]}}, world("arena"), seconds=5)
    assert taken.status == "FAILURE" and taken.code == "ENTITY_ERROR" and "already exists" in taken.reason
    moved = run_tree(
        {"sequence": [{"DeleteEntity": {}}, {"SpawnEntity": {"pose": "0.3, 0.3, pi/2"}}]}, world("arena"), seconds=5
    )
    kinds = [e["kind"] for e in moved.events if e["kind"] in ("delete_entity", "spawn_entity")]
    assert moved.status == "SUCCESS" and kinds == ["delete_entity", "spawn_entity"]
    assert moved.final_pose == Pose(0.3, 0.3, round(math.pi / 2, 6))


def test_stop_and_events_carry_pose_and_proximity():
    result = run_tree({"sequence": [{"MoveDistance": {"distance": 0.1}}, {"Stop": {}}]}, world("arena"), seconds=5)
    end = ends(result, "Stop")[0]
    assert end["status"] == "SUCCESS" and set(end["pose"]) == {"x", "y", "yaw"}
    assert set(end["proximity"]) == set(SENSOR_NAMES) and len(SENSOR_NAMES) == 7  # every sensor's reading
    starts = [e for e in result.events if e["kind"] == "behaviour_start"]
    assert [e["name"] for e in starts] == ["MoveDistance", "Stop"]


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_wall_follow_leaves_generated_perfect_mazes(side, seed):
    maze = perfect_maze(5, 4, seed=seed)
    result = run_tree({"WallFollow": {"side": side}}, maze, seconds=600)
    xmin, ymin, xmax, ymax = maze.bounds()
    assert result.status == "SUCCESS", result.reason
    assert result.collisions == 0
    assert result.final_pose.y > ymax  # out through the gap in the top wall
    follow = ends(result, "WallFollow")[0]
    assert "LL" in follow["turns"] or "RR" in follow["turns"] or len(follow["turns"]) > 3


@pytest.mark.parametrize("robot", ["enki", "real"])
@pytest.mark.parametrize("side, seed", [("left", 4), ("right", 5), ("left", 6)])
def test_wall_follow_leaves_generated_mazes_on_other_robots_with_noise(robot, side, seed):
    """Enki's cones (and its motor noise) or a real robot's noisy readings: the same behaviour, no
    collision, with every noise model on."""
    maze = perfect_maze(5, 5, seed=seed)
    result = run_tree(
        {"WallFollow": {"side": side}},
        maze,
        seconds=600,
        seed=seed,
        robot=robot,
        noise={"wheel": 0.027, "odometry": 0.01, "range_sd": 0.001},
    )
    assert result.status == "SUCCESS", result.reason
    assert result.collisions == 0 and result.final_pose.y > maze.bounds()[3]  # truly out, whatever the drift


@pytest.mark.parametrize("side, seed", [("right", 25), ("right", 8), ("left", 22)])
def test_wall_follow_ends_truly_out_of_a_large_maze_on_enki(side, seed):
    """After a long maze its distances are off by a centimetre or two: it goes on until it believes
    itself ``exit_margin`` out, so base_link really is out (it once stopped up to 15 mm inside)."""
    maze = perfect_maze(7, 7, seed, cell=0.2)
    result = run_tree({"WallFollow": {"side": side}}, maze, seconds=900, robot="enki")
    assert result.status == "SUCCESS" and result.collisions == 0, result.reason
    assert result.final_pose.y > maze.bounds()[3] + 0.005


def test_wall_follow_turns_around_in_dead_ends():
    dead_end_first = world("""
+--+--+--+
|        |
+--+--+  +
|        |
+--+--+--+
""")
    # start facing a dead end (west): it must turn around (two turns away from the wall side)
    result = run_tree(
        {"WallFollow": {"side": "left", "until": "goal", "goal": [0.5, 0.1]}},
        dead_end_first,
        start=[0.3, 0.3, "pi"],
        seconds=120,
    )
    assert result.status == "SUCCESS", result.reason
    assert ends(result, "WallFollow")[0]["turns"].startswith("RR")


def test_move_until_wall_with_centre_steers_to_the_corridor_middle():
    start = [0.1, 0.085, 0.05]  # 15 mm right of the centre line, heading 2.9 deg to the left
    off = run_tree({"MoveUntilWall": {"distance": "5cm"}}, world("corridor"), start=start, seconds=20)
    on = run_tree({"MoveUntilWall": {"distance": "5cm", "centre": True}}, world("corridor"), start=start, seconds=20)
    assert off.status == on.status == "SUCCESS"
    assert abs(off.final_pose.y - 0.1) > 0.01  # heading held: it drifts across the corridor
    assert abs(on.final_pose.y - 0.1) < 0.003  # centred within 3 mm over 0.5 m
    assert abs(on.final_pose.yaw) < 0.02
    assert on.final_proximity["front_center"] == pytest.approx(0.05, abs=0.001)


def late_run(tmp_path, latency, tree, preset="corridor"):
    """``tree`` in a preset world on a simulated robot that says it is ``latency`` s late."""
    import yaml

    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run
    from thymio_bt.testing import mission_text

    (tmp_path / "w.yaml").write_text(yaml.safe_dump(world(preset).to_yaml_dict()))
    (tmp_path / "m.yaml").write_text(mission_text(tree, "w.yaml", seconds=30))
    run = Run(load_mission(tmp_path / "m.yaml"))
    run.backend.latency = latency
    return run.run()


def test_a_late_robot_makes_move_until_wall_and_turn_angle_lead_by_its_latency(tmp_path):
    plain = late_run(tmp_path, 0.0, {"MoveUntilWall": {"distance": "5cm"}})
    late = late_run(tmp_path, 0.2, {"MoveUntilWall": {"distance": "5cm"}})
    # this robot is not late: leading by 0.2 s stops it early by what its slowing approach covers
    assert late.final_proximity["front_center"] > plain.final_proximity["front_center"] + 0.001
    # (leading by a latency the robot does not have oscillates once gain x latency reaches 1: 0.1 s here)
    turn = late_run(tmp_path, 0.1, {"TurnAngle": {"angle": "90deg"}}, "arena")
    turned = ends(turn, "TurnAngle")[-1]["angle"]
    assert turn.status == "SUCCESS" and math.pi / 2 - 0.05 < turned < math.pi / 2 - 0.0005


#: parameters that make each built-in behaviour do something small in the arena (start: base_link
#: at (0.7, 0.7) facing +x, a 6 x 6 open floor of 0.2 m cells); each ends with SUCCESS by itself
#: except SpawnEntity (the robot's name is taken), DeleteEntity once the robot is gone, ChooseTurn
#: (no wall ahead comes into range: it runs out of time) and LookAround (no decision to check)
GRID = {"cell": 0.2, "wall": 0.01}
RESTART_PARAMS = {
    "MoveUntilWall": {"distance": "5cm"},
    "MoveDistance": {"distance": "2cm"},
    "TurnAngle": {"angle": "20deg"},
    "Stop": {},
    "Wait": {"seconds": 0.2},
    "DeleteEntity": {},
    "SpawnEntity": {"pose": [0.3, 0.3, 0]},
    "ChooseTurn": {"timeout": 1},
    "LookAround": {},
    "WallAhead": {},
    "SideOpen": {"side": "left"},
    "IsDeadEnd": {},
    "WallFollow": {"side": "left", "until": "goal", "goal": [0.9, 0.7]},
    "GoToPose": {"goal": [0.9, 0.8]},
    "FollowWaypoints": {"waypoints": [[0.9, 0.7], [0.9, 0.9]]},
    "WaypointsDone": {},
    "ObstacleAhead": {},
    "TurnUntilClear": {},
    "TurnBack": {},
    "SetBlackboard": {"key": "k", "value": 1},
    "MapWalls": GRID,
    "PlanMove": {**GRID, "target": "centre"},
    "MoveCells": {**GRID, "distance": -0.2},  # backwards: three cells ahead is the wall
    "WallMapped": GRID,
    "AtTarget": {**GRID, "target": "centre"},
    "OutsideMaze": {},
    "InRegion": {"centre": [0.7, 0.7], "radius": "5cm"},
}
#: the behaviours still running 0.2 s after they start with the parameters above
STILL_RUNNING = {
    "ChooseTurn",
    "FollowWaypoints",
    "GoToPose",
    "MoveCells",
    "MoveDistance",
    "MoveUntilWall",
    "TurnAngle",
    "WallFollow",
}


def test_every_builtin_behaviour_has_restart_parameters():
    from thymio_bt.plan.builtin_nodes import BUILTIN_NODES

    robot = [
        name
        for name, where in BUILTIN_NODES.items()
        if where.startswith("thymio_bt.behaviours.") and ".flow." not in where
    ]
    assert sorted(RESTART_PARAMS) == sorted(robot)


def restart_tree(name, loop, ending):
    """``name`` three times in a row: ``repeat`` over ``force_success`` (every ending counts as a
    success) or ``retry`` over ``force_failure``; the behaviour ends by itself (``finished``), runs
    out of its own 0.3 s (``timed out``, FAILURE) or is halted by a 0.2 s ``timeout`` (``halted``)."""
    params = dict(RESTART_PARAMS[name])
    node = {name: params}
    if ending == "timed out":
        params["timeout"] = 0.3
    elif ending == "halted":
        node = {"timeout": {"seconds": 0.2, "do": {name: {**params, "timeout": 5}}}}
    force = "force_success" if loop == "repeat" else "force_failure"
    return {loop: {"times": 3, "do": {force: node}}}


@pytest.mark.parametrize("ending", ["finished", "timed out", "halted"])
@pytest.mark.parametrize("loop", ["repeat", "retry"])
@pytest.mark.parametrize("name", sorted(RESTART_PARAMS))
def test_every_builtin_behaviour_restarts_after_success_failure_and_halt(name, loop, ending):
    """A behaviour is started again by ``repeat`` after it succeeded and by ``retry`` after it failed,
    and by either after a ``timeout`` halted it: its ``start`` hook must set it up afresh each time
    (WallFollow once overwrote its ``start`` hook with a tuple, and its second start raised TypeError)."""
    result = run_tree(restart_tree(name, loop, ending), world("arena"), start=[0.7, 0.7, 0], seconds=20)
    codes = [e.get("code") for e in result.events if e["kind"] == "behaviour_end"]
    assert "EXCEPTION" not in codes and result.code != "EXCEPTION", result.reason
    assert result.status == ("SUCCESS" if loop == "repeat" else "FAILURE"), result.reason
    ticks = [stats["ticks"] for path, stats in result.node_stats.items() if path.endswith(f"/{name}")]
    assert ticks and ticks[0] >= 3  # started three times, ticked at least once each
    endings = [e["status"] for e in ends(result, name)]
    if not endings:
        return  # a condition (or SetBlackboard): no events, it answers at once
    if ending == "finished" and name not in ("ChooseTurn", "LookAround", "SpawnEntity", "DeleteEntity"):
        assert endings == ["SUCCESS"] * 3
    elif ending != "finished" and name in STILL_RUNNING:
        assert endings == ["FAILURE" if ending == "timed out" else "INVALID"] * 3
    else:
        assert len(endings) == 3


@pytest.mark.parametrize(
    ("condition", "said"),
    [
        ({"SideOpen": {"side": "left"}}, "front_left reads 0.07"),  # the corridor's side wall
        ({"WallAhead": {"distance": "5cm"}}, "front_center reads nothing in range"),
        ({"ObstacleAhead": {}}, "reads 0.07"),
        ({"WallMapped": {}}, "side E of cell (0, 0): no wall on the map"),
        ({"AtTarget": {"target": "goal"}}, "cell (0, 0): not in the goal"),
        ({"bt_script_condition": {"code": "1 > 2"}}, "'1 > 2' is false"),
    ],
)
def test_a_failed_condition_says_what_it_judged(condition, said):
    """issue 46 item 7: the failure's reason is the reading the condition judged, not "'SideOpen'
    returned FAILURE"; every condition says it (the same trap was in ObstacleAhead and WallMapped)."""
    result = run_tree(condition, world("corridor"), seconds=2)
    assert (result.status, result.code) == ("FAILURE", "FAILED")
    assert said in result.reason and "returned FAILURE" not in result.reason


def test_repeat_and_retry_feedback_reads_like_words():
    """issue 46 item 7: a repeat's feedback is "iteration 2 of 3", not "[status: 1 success from 3]"."""
    from py_trees.behaviours import Failure, Running, Success

    from thymio_bt.behaviours.flow.decorators import Repeat, RepeatParams, Retry, RetryParams

    def feedback(node, ticks: int) -> str:
        for _ in range(ticks):
            node.tick_once()
        return node.feedback_message

    forever = Repeat.build("loop", RepeatParams(times="forever"), [Success("leg")], None)
    three = Repeat.build("loop", RepeatParams(times=3), [Success("leg")], None)
    running = Repeat.build("loop", RepeatParams(times=3), [Running("leg")], None)
    failed = Repeat.build("loop", RepeatParams(times=3), [Failure("leg")], None)
    retry = Retry.build("retry", RetryParams(times=3), [Failure("leg")], None)
    assert [feedback(forever, 1), feedback(three, 2), feedback(three, 1), feedback(running, 1)] == [
        "iteration 2 (for ever)",
        "iteration 3 of 3",
        "done: 3 iterations",
        "iteration 1 of 3",
    ]
    assert [feedback(failed, 1), feedback(retry, 1), feedback(retry, 2)] == [
        "iteration 1 of 3 failed",
        "attempt 2 of 3 (1 failed)",
        "all 3 attempts failed",
    ]
