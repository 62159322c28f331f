"""A Thymio over the Aseba protocol, against the real Aseba Playground (CI installs it: .ci/setup.d).

The Playground runs in real time: these tests take about 40 s together.
"""

import math
import socket
import time
from pathlib import Path

import _require
import pytest

from thymio_bt.backends.playground.backend import SPEED_SCALE
from thymio_bt.backends.playground.enki import EnkiRobot
from thymio_bt.backends.playground.process import Playground, listening
from thymio_bt.backends.playground.world import playground_world
from thymio_bt.backends.real.aseba import AsebaNode, signed
from thymio_bt.errors import UserError
from thymio_bt.maze.micromouse import maze_from_cells, parse_micromouse
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]

CORRIDOR = maze_from_cells(
    parse_micromouse("""o---o---o---o---o---o
| S                 |
o---o---o---o---o---o
"""),
    "corridor",
)


def test_words_are_signed():
    assert [signed(w) for w in (0, 1, 0x7FFF, 0x8000, 0xFFFF)] == [0, 1, 32767, -32768, -1]


def test_the_world_file_has_the_mazes_walls_and_the_robot_at_its_axle():
    world = playground_world(CORRIDOR, Pose(0.09, 0.09, 0.0), port=40000)
    assert world.text.count("<wall ") == len(CORRIDOR.walls)
    assert 'port="40000"' in world.text and 'type="thymio2"' in world.text
    assert world.from_enki(*world.to_enki(0.09, 0.09)) == pytest.approx((0.09, 0.09))


def test_a_tilted_wall_cannot_go_into_a_playground_world():
    from thymio_bt.maze import Maze

    tilted = Maze.model_validate({"walls": [{"from": [0, 0], "to": [1, 0.1]}]})
    with pytest.raises(UserError, match="not parallel to an axis"):
        playground_world(tilted, Pose(0.5, 0.5, 0.0), port=40000)


@pytest.fixture(scope="module")
def playground():
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    _require.module("jeepney")
    world = playground_world(CORRIDOR, Pose(0.09, 0.09, 0.0), port=0)
    with Playground.start(world.text, preload=_require.enki_fix()) as pg:
        yield pg, world


@pytest.fixture(scope="module")
def node(playground):
    pg, _ = playground
    robot = AsebaNode.connect(f"tcp:127.0.0.1:{pg.port}", timeout=5.0)
    yield robot
    robot.close()


@pytest.fixture(scope="module")
def enki(playground):
    robot = EnkiRobot.find(playground[0].bus)
    yield robot
    robot.close()


def settle(seconds):
    time.sleep(seconds)  # the Playground runs in real time


def test_reads_give_seven_proximity_values_and_two_wheel_speeds(node):
    prox = node.read_prox()
    assert len(prox) == 7 and all(isinstance(v, int) and 0 <= v <= 4600 for v in prox)
    assert node.read_wheel_speeds() == (0, 0)


def test_the_robot_moves_as_commanded_within_five_percent(node, enki, playground):
    world = playground[1]
    enki.place(*world.to_enki(0.2, 0.09), 0.0)
    settle(0.2)
    x0, _, _ = enki.pose()
    wheels0 = node.read_wheel_travel()
    node.set_motors(200, 200)
    settle(2.0)  # 2 s, not 1: what polling misses at the start and the stop weighs half as much
    node.set_motors(0, 0)
    settle(0.3)
    travelled = (enki.pose()[0] - x0) / 100.0
    # the Playground's Thymio does 0.166 m/s at 500 units; about 60 ms of the drive pass before it starts
    assert travelled == pytest.approx(0.166 * 200 / 500 * 2.0, rel=0.12)
    assert node.read_wheel_speeds() == (0, 0)
    # the node integrates the speeds as they arrive: odometry's distance, within 5 % of the truth
    wheels1 = node.read_wheel_travel()
    odometry = (wheels1[0] - wheels0[0] + wheels1[1] - wheels0[1]) / 2 * 0.166 / 500 * SPEED_SCALE
    assert odometry == pytest.approx(travelled, rel=0.05)


def test_negative_targets_read_back_signed(node):
    node.set_motors(-150, 150)
    settle(0.3)
    left, right = node.read_wheel_speeds()
    node.set_motors(0, 0)
    settle(0.2)
    assert left == pytest.approx(-150, abs=15) and right == pytest.approx(150, abs=15)


def test_teleport_and_ground_truth_agree(enki, playground):
    world = playground[1]
    enki.place(*world.to_enki(0.45, 0.09), math.pi / 2)
    settle(0.1)
    x, y = world.from_enki(*enki.pose()[:2])
    assert (x, y) == pytest.approx((0.45, 0.09), abs=1e-6)
    enki.place(*world.to_enki(0.09, 0.09), 0.0)


def test_connecting_to_a_closed_port_fails_at_once_with_a_hint():
    """At once: the refusal is the message, not a wait for the timeout (which would say "timed out")."""
    _require.module("thymiodirect")
    with socket.socket() as closed:  # bound, never listening: refused, and nobody else can listen there
        closed.bind(("127.0.0.1", 0))
        device = f"tcp:127.0.0.1:{closed.getsockname()[1]}"
        with pytest.raises(UserError, match=f"cannot reach a Thymio at {device}: Connection refused") as info:
            AsebaNode.connect(device, timeout=60.0)  # a wait would say "timed out"
    assert "(hint: start the Aseba Playground" in str(info.value)


def corridor_mission(tmp_path, tree_yaml):
    (tmp_path / "corridor.txt").write_text("""o---o---o---o---o---o
| S                 |
o---o---o---o---o---o
""")
    (tmp_path / "m.yaml").write_text(
        f"name: corridor\nmaze: corridor.txt\nstart: start\nrobot: enki\n"
        f"backend: {{name: playground}}\ntime_limit: 30\ntree:\n{tree_yaml}"
    )
    return load_mission(tmp_path / "m.yaml")


def test_a_mission_runs_on_the_playground_with_ground_truth_and_stops_it(tmp_path):
    _require.program("asebaplayground")
    mission = corridor_mission(tmp_path, "  MoveUntilWall: {distance: 5cm, speed: 8cm/s, centre: true}\n")
    run = Run(mission)
    folder = run.backend.playground.folder
    result = run.run()
    assert result.status == "SUCCESS" and result.collisions == 0
    # the front gap by the true pose and the maze: base_link x + 0.0557 to the far wall's face at 0.894
    gap = 0.9 - 0.006 - (result.final_pose.x + 0.0557)
    assert gap == pytest.approx(0.05, abs=0.015)
    assert result.min_clearance is not None and result.min_clearance > 0.005
    assert not folder.exists() and not listening(run.backend.playground.port)


def test_a_playground_that_dies_mid_run_ends_it_as_robot_lost_within_a_second(tmp_path):
    _require.program("asebaplayground")
    mission = corridor_mission(tmp_path, "  Wait: {seconds: 20}\n")
    run = Run(mission)
    killed = {}

    def hook(r):
        if r.ticks == 10:
            r.backend.playground.processes[-1].kill()
            killed["t"] = r.backend.time()

    result = run.run(on_tick=hook)
    assert result.status == "FAILURE" and result.code == "ROBOT_LOST"
    assert result.sim_time - killed["t"] < 1.2


def test_maze_export_writes_a_playground_world_with_the_robot_at_a_spawn(tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    out = tmp_path / "maze.playground"
    result = CliRunner().invoke(
        main,
        [
            "maze",
            "export",
            f"{ROOT}/mazes/two_parts_maze.yaml",
            "--playground",
            "--spawn",
            "part2",
            "--port",
            "40123",
            "-o",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    text = out.read_text()
    assert text.count("<wall ") == 21 and 'port="40123"' in text and 'angle="1.570796"' in text
    missing = CliRunner().invoke(
        main, ["maze", "export", f"{ROOT}/mazes/two_parts_maze.yaml", "--playground", "--spawn", "nope"]
    )
    assert missing.exit_code == 2 and "nope" in missing.output
