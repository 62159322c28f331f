"""The real-robot backend's mapping logic against fake nodes: no robot, no network, no waiting."""

import math
import os
import signal
import subprocess
import sys
import types
from dataclasses import replace
from pathlib import Path

import _require
import pytest
from py_trees.common import Status

from thymio_bt.backends.real import PROX_INDEX, AsebaDevice, TdmDevice, ThymioRobot, import_tdmclient
from thymio_bt.backends.real.thymio import TdmAddress
from thymio_bt.behaviours import Context
from thymio_bt.behaviours.motion import MoveUntilWall
from thymio_bt.errors import UserError
from thymio_bt.robot.interface import SENSOR_NAMES, Entities, Pose, RequestState, Robot
from thymio_bt.robot.model import COURSE, ENKI, REAL
from thymio_bt.sensor_tables import metres_to_raw

ROOT = Path(__file__).resolve().parents[1]

AXLE_X = COURSE.axle_x
SENSORS = tuple((s.name, s.x, s.y, s.yaw) for s in COURSE.sensors)

START = Pose(0.1, 0.1, 0.0)


class FakeNode(AsebaDevice):
    """Records motor writes; serves scripted readings, one per read, repeating the last one."""

    def __init__(self, prox=None, wheels=None):
        self.writes: list[tuple[int, int]] = []
        self.prox = list(prox or [[0] * 7])
        self.wheels = list(wheels or [(0, 0)])
        self.closed = False

    def set_motors(self, left, right):
        self.writes.append((left, right))

    def read_prox(self):
        return self.prox.pop(0) if len(self.prox) > 1 else self.prox[0]

    def read_wheel_speeds(self):
        return self.wheels.pop(0) if len(self.wheels) > 1 else self.wheels[0]

    def close(self):
        self.closed = True


class FakeClock:
    """Wall-clock time that only moves when the backend sleeps (or a test says so)."""

    def __init__(self):
        self.now = 1000.0
        self.sleeps: list[float] = []

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.sleeps.append(seconds)
        self.now += seconds


class Operator:
    """Answers prompts; ``minutes`` of wall-clock time pass at each one."""

    def __init__(self, clock, answer="", minutes=0.5):
        self.clock, self.answer, self.minutes = clock, answer, minutes
        self.prompts: list[str] = []

    def __call__(self, prompt):
        self.prompts.append(prompt)
        self.clock.now += 60 * self.minutes
        if isinstance(self.answer, BaseException):
            raise self.answer
        return self.answer


def make(node=None, spawn=START, answer="", model=REAL, **fields):
    """A backend on a fake node and clock; ``fields`` are fields of its robot ``model`` changed."""
    node = node or FakeNode()
    clock = FakeClock()
    operator = Operator(clock, answer)
    said: list[str] = []
    robot = ThymioRobot(
        node,
        model=replace(model, **fields),
        spawn=spawn,
        clock=clock,
        sleep=clock.sleep,
        ask=operator,
        say=said.append,
    )
    return robot, node, clock, operator, said


# ------------------------------------------------------------------ motors
def test_it_is_a_robot_backend_with_what_the_runner_uses():
    robot, node, *_ = make()
    assert isinstance(robot, Robot) and isinstance(robot, Entities)
    assert robot.robot_name == "thymio"
    assert robot.collisions == [] and robot.min_clearance == math.inf
    assert robot.true_pose() == robot.pose() == START
    assert node.writes == [(0, 0)]  # the motors are stopped on start


def test_driving_straight_writes_equal_targets_500_units_per_20_cm_s():
    robot, node, *_ = make()
    robot.drive(0.1, 0.0)
    assert node.writes[-1] == (250, 250)
    robot.drive(-0.05, 0.0)
    assert node.writes[-1] == (-125, -125)
    assert robot.command().linear == -0.05


def test_turning_writes_the_wheel_speed_differential():
    robot, node, *_ = make()
    robot.drive(0.1, 1.0)  # wheels 0.1 -/+ 1.0 * 0.0935 / 2 m/s
    assert node.writes[-1] == (round(0.05325 / 0.0004), round(0.14675 / 0.0004)) == (133, 367)
    robot.drive(0.0, -1.0)
    assert node.writes[-1] == (117, -117)


def test_clamping_to_500_units_keeps_the_turn_radius():
    robot, node, *_ = make()
    robot.drive(0.3, 2.0)
    left, right = node.writes[-1]
    assert right == 500
    assert left / right == pytest.approx((0.3 - 0.0935) / (0.3 + 0.0935), abs=0.002)
    robot.drive(0.0, 50.0)
    assert node.writes[-1] == (-500, 500)
    robot.drive(1.0, 0.0)
    assert node.writes[-1] == (500, 500)


def test_the_speed_constant_is_a_parameter():
    robot, node, *_ = make(metres_per_unit=1 / 2930)  # the ROS driver's calibration
    robot.drive(0.1, 0.0)
    assert node.writes[-1] == (293, 293)
    robot.drive(0.5, 0.0)
    assert node.writes[-1] == (500, 500)


def test_the_enki_model_drives_with_enkis_speed_and_sensor_curve():
    robot, node, *_ = make(FakeNode(prox=[[0, 0, 3366, 0, 0, 0, 0]]), model=ENKI)
    robot.drive(0.1, 0.0)
    assert node.writes[-1] == (301, 301)  # 500 units = 16.6 cm/s
    assert robot.proximity()["front_center"] == pytest.approx(0.05)


def test_every_number_comes_from_the_robot_model_with_no_copy():
    """RealConfig copied four of the model's fields (units, limit, wheel base, sensor table) and
    re-derived its kinematics: now the model is the one place, and a model's change reaches the robot."""
    from thymio_bt.backends.real import thymio

    assert not hasattr(thymio, "RealConfig") and not hasattr(thymio, "PLAYGROUND")
    odd = {"metres_per_unit": 0.0003, "max_units": 400, "wheel_separation": 0.1, "calibration": ENKI.calibration}
    robot, node, *_ = make(FakeNode(prox=[[0, 0, 3366, 0, 0, 0, 0]], wheels=[(100, 300)]), **odd)
    assert not hasattr(robot, "config")
    robot.drive(0.03, 0.0)
    assert node.writes[-1] == (100, 100) == robot.model.motor_targets(0.03, 0.0)
    robot.drive(1.0, 0.5)  # limited at 400 units, the turn radius kept
    left, right = robot.model.wheel_speeds(1.0, 0.5)
    assert node.writes[-1] == (round(400 * left / right), 400) == robot.model.motor_targets(1.0, 0.5)
    assert robot.proximity()["front_center"] == pytest.approx(0.05)  # Enki's curve
    robot.advance(0.1)
    assert (robot.velocity().linear, robot.velocity().angular) == pytest.approx((0.06, 0.6))


def test_a_speed_scale_stretches_the_units_but_not_the_model():
    """The Playground's Thymio covers 0.985 of Enki's distance per unit: the backend scales its
    units, and behaviours still read Enki's model."""
    robot, node, *_ = make(FakeNode(wheels=[(500, 500)]), model=ENKI)
    scaled = ThymioRobot(FakeNode(wheels=[(500, 500)]), spawn=START, model=ENKI, speed_scale=0.985)
    scaled.drive(0.1, 0.0)
    assert scaled.device.writes[-1] == (round(0.1 / (0.166 / 500 * 0.985)), 306)
    robot.drive(0.2, 0.0)
    scaled.drive(0.2, 0.0)
    assert node.writes[-1] == scaled.device.writes[-1] == (500, 500)
    assert scaled.velocity().linear == pytest.approx(0.985 * robot.velocity().linear) == 0.985 * 0.166
    assert scaled.model is ENKI


# --------------------------------------------------------------- proximity
def test_prox_horizontal_indices_are_the_sensor_names_in_order():
    assert PROX_INDEX == {
        "front_left": 0,
        "front_center_left": 1,
        "front_center": 2,
        "front_center_right": 3,
        "front_right": 4,
        "rear_left": 5,
        "rear_right": 6,
    }
    assert tuple(PROX_INDEX) == SENSOR_NAMES == tuple(name for name, *_ in SENSORS)


def test_proximity_maps_raw_readings_to_metres_per_sensor_with_inf_for_0():
    robot, node, *_ = make(FakeNode(prox=[[0, 4308, 3515, 2570, 1195, 0, 100]]))
    scan = robot.proximity()
    assert tuple(scan) == SENSOR_NAMES
    assert scan["front_left"] == scan["rear_left"] == math.inf
    assert scan["front_center_left"] == pytest.approx(0.00333)
    assert scan["front_center"] == pytest.approx(0.03)
    assert scan["front_center_right"] == pytest.approx(0.05)
    assert scan["front_right"] == pytest.approx(0.09)
    assert 0.09 < scan["rear_right"] < 0.0934
    assert robot.proximity_raw()["front_center"] == 3515


def test_proximity_is_refreshed_at_each_advance():
    robot, node, *_ = make(FakeNode(prox=[[0] * 7, [0, 0, 2570, 0, 0, 0, 0]]))
    assert robot.proximity()["front_center"] == math.inf
    robot.advance(0.1)
    assert robot.proximity()["front_center"] == pytest.approx(0.05)


def test_a_node_with_the_wrong_number_of_sensors_is_an_error():
    with pytest.raises(ValueError, match="7"):
        make(FakeNode(prox=[[0] * 5]))


# ---------------------------------------------------------------- odometry
def test_odometry_integrates_a_quarter_turn_exactly():
    # 200 units of wheel-speed difference are pi/4 rad/s: 100 and 300 units turn a quarter in 2 s
    k = math.pi / 4 * 0.0935 / 200
    wheels = [(0, 0)] + [(100, 300)] * 20 + [(0, 0)]
    robot, node, clock, *_ = make(FakeNode(wheels=wheels), metres_per_unit=k)
    for _ in range(21):  # ramp up and down over half a tick each: 20 ticks' worth at full speed
        robot.advance(0.1)
    radius = 200 * k / (math.pi / 4)  # v / w = the wheel separation
    assert radius == pytest.approx(0.0935)
    axle = (START.x + AXLE_X + radius, START.y + radius)
    pose = robot.pose()
    assert pose.yaw == pytest.approx(math.pi / 2, abs=1e-9)
    assert pose.x == pytest.approx(axle[0], abs=1e-9)
    assert pose.y == pytest.approx(axle[1] - AXLE_X, abs=1e-9)
    assert robot.velocity().linear == 0.0


def test_odometry_drives_0_1_m_in_a_second_at_250_units():
    robot, node, *_ = make(FakeNode(wheels=[(250, 250)]), spawn=Pose(0.2, 0.3, math.pi / 2))
    for _ in range(10):
        robot.advance(0.1)
    pose = robot.pose()
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((0.2, 0.4, math.pi / 2), abs=1e-9)
    assert robot.velocity().linear == pytest.approx(0.1)
    assert robot.velocity().angular == 0.0


def test_spinning_in_place_keeps_the_axle_fixed():
    robot, node, *_ = make(FakeNode(wheels=[(-150, 150)]))
    for _ in range(7):
        robot.advance(0.1)
    pose = robot.pose()
    axle = (pose.x + AXLE_X * math.cos(pose.yaw), pose.y + AXLE_X * math.sin(pose.yaw))
    assert axle == pytest.approx((START.x + AXLE_X, START.y), abs=1e-12)
    assert pose.yaw == pytest.approx(0.7 * 2 * 150 * 0.0004 / 0.0935)


# ------------------------------------------------------------------- clock
def test_advance_waits_for_the_next_tick_and_never_catches_up_when_late():
    robot, node, clock, *_ = make()
    assert robot.time() == 0.0
    robot.advance(0.1)
    assert clock.sleeps == [pytest.approx(0.1)] and robot.time() == pytest.approx(0.1)
    clock.now += 0.03  # the tree took 30 ms to tick
    robot.advance(0.1)
    assert clock.sleeps[-1] == pytest.approx(0.07) and robot.time() == pytest.approx(0.2)
    clock.now += 0.5  # a slow tick: no wait, the next tick is timed from now
    robot.advance(0.1)
    assert len(clock.sleeps) == 2 and robot.time() == pytest.approx(0.7)
    robot.advance(0.1)
    assert clock.sleeps[-1] == pytest.approx(0.1) and robot.time() == pytest.approx(0.8)


# ---------------------------------------------------------------- entities
def test_delete_stops_the_motors_and_marks_the_robot_absent():
    robot, node, clock, operator, said = make()
    robot.drive(0.1, 0.0)
    request = robot.request_delete("thymio")
    assert request.state is RequestState.PENDING  # served at the next advance, as in the simulator
    robot.advance(0.1)
    assert request.state is RequestState.SUCCEEDED
    assert node.writes[-1] == (0, 0)
    assert not robot.exists()
    assert robot.pose() is None and robot.proximity() is None and robot.proximity_raw() is None
    assert "deleted" in said[-1]
    robot.drive(0.1, 0.0)  # ignored while absent
    assert node.writes[-1] == (0, 0)
    again = robot.request_delete("thymio")
    robot.advance(0.1)
    assert again.state is RequestState.FAILED and "no entity named 'thymio'" in again.reason


def test_delete_of_an_unknown_entity_is_refused():
    robot, *_ = make()
    request = robot.request_delete("box")
    robot.advance(0.0)
    assert request.state is RequestState.FAILED and "existing: thymio" in request.reason
    assert robot.exists()


def test_spawn_prompts_the_operator_then_resets_odometry_with_the_clock_paused():
    robot, node, clock, operator, said = make(FakeNode(wheels=[(250, 250)]))
    robot.advance(0.1)
    robot.request_delete("thymio")
    robot.advance(0.1)
    before = robot.time()
    target = Pose(0.5, 0.3, math.pi / 2)
    request = robot.request_spawn("thymio", target)
    robot.advance(0.0)
    assert request.state is RequestState.SUCCEEDED
    assert "x=0.500 m, y=0.300 m, facing 90 deg" in operator.prompts[-1]
    assert robot.pose() == pytest.approx(target)
    assert robot.command().linear == 0.0
    assert robot.time() == pytest.approx(before)  # 30 s at the prompt do not count
    robot.advance(0.1)  # and the odometry starts from the new pose
    assert robot.pose().y == pytest.approx(0.3 + 0.01, abs=1e-9)  # 0.1 m/s for 0.1 s


def test_the_runner_start_is_a_spawn_prompt():
    robot, node, clock, operator, _ = make(spawn=None)
    assert not robot.exists() and robot.pose() is None
    assert robot.spawn_problem("thymio", START) is None
    robot.request_spawn("thymio", START)
    robot.advance(0.0)
    assert len(operator.prompts) == 1 and robot.pose() == START


@pytest.mark.parametrize("answer, reason", [("q", "refused"), (EOFError(), "standard input is closed")])
def test_the_operator_may_refuse_or_be_absent(answer, reason):
    robot, node, clock, operator, _ = make(spawn=None, answer=answer)
    request = robot.request_spawn("thymio", START)
    robot.advance(0.0)
    assert request.state is RequestState.FAILED and reason in request.reason
    assert not robot.exists()


def test_spawn_is_refused_without_a_prompt_when_the_robot_exists_or_the_name_is_another():
    robot, node, clock, operator, _ = make()
    taken = robot.request_spawn("thymio", START)
    other = robot.request_spawn("box", START)
    robot.advance(0.0)
    assert taken.state is other.state is RequestState.FAILED
    assert "already exists" in taken.reason and "one entity" in other.reason
    assert operator.prompts == []
    assert robot.spawn_problem("thymio", Pose(math.nan, 0.0, 0.0)) is not None


def test_close_stops_the_motors_and_releases_the_node():
    robot, node, *_ = make()
    with robot:
        robot.drive(0.1, 0.0)
    assert node.writes[-1] == (0, 0) and node.closed
    writes = len(node.writes)
    robot.close()
    assert len(node.writes) == writes


# ------------------------------------------------------ a behaviour on it
class WallAhead(FakeNode):
    """Ideal motors in front of a wall at x = 0.5: readings from the robot's own pose, through the table."""

    def __init__(self):
        super().__init__()
        self.robot: ThymioRobot | None = None
        self.target = (0, 0)

    def set_motors(self, left, right):
        super().set_motors(left, right)
        self.target = (left, right)

    def read_wheel_speeds(self):
        return self.target

    def read_prox(self):
        pose = self.robot.pose() if self.robot and self.robot.exists() else START
        gap = 0.5 - (pose.x + SENSORS[2][1])
        return [0, 0, round(metres_to_raw(gap)), 0, 0, 0, 0]


def test_move_until_wall_written_for_the_simulator_stops_at_5_cm_on_raw_readings():
    node = WallAhead()
    robot, *_ = make(node)
    node.robot = robot
    behaviour = MoveUntilWall("approach", MoveUntilWall.Params(distance=0.05), Context(robot=robot, entities=robot))
    for _ in range(100):
        behaviour.tick_once()
        if behaviour.status is not Status.RUNNING:
            break
        robot.advance(0.1)
    assert behaviour.status is Status.SUCCESS
    assert robot.proximity()["front_center"] == pytest.approx(0.05, abs=0.001)
    assert node.writes[-1] == (0, 0)


# --------------------------------------------------------------- tdmclient
def test_without_tdmclient_the_adapter_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "tdmclient", None)
    with pytest.raises(UserError) as error:
        import_tdmclient()
    assert "pip install 'thymio-bt[thymio]'" in str(error.value)
    with pytest.raises(UserError, match="tdmclient"):
        ThymioRobot.connect()


def test_the_backend_imports_without_tdmclient():
    code = (
        "import sys; sys.modules['tdmclient'] = None; import thymio_bt.backends.real, thymio_bt.sensor_tables; "
        "print('ok')"
    )
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "ok"


class FakeTdm:
    """A stand-in tdmclient module for connect(): no network; ``aw`` returns its argument."""

    def __init__(self, node=None, refuse=False, busy=False):
        self.node, self.refuse, self.busy = node, refuse, busy
        self.disconnected = False
        self.waited_for: set[str] = set()
        tdm = self

        class NodeLockError(Exception):
            pass

        class ClientAsync:
            def __init__(self, tdm_addr=None, tdm_port=None, password=None):
                if tdm.refuse:
                    raise ConnectionRefusedError(111, "Connection refused")

            def wait_for_node(self, timeout=None, node_name=None):
                return tdm.node

            def lock(self, node_name=None):
                if tdm.busy:
                    raise NodeLockError("Node lock error (current status: busy)")
                return tdm.node

            def disconnect(self):
                tdm.disconnected = True

        self.module = types.SimpleNamespace(ClientAsync=ClientAsync, NodeLockError=NodeLockError, aw=lambda x: x)

    def wait_for_variables(self, names):
        self.waited_for = set(names)


def test_connect_locks_the_robot_and_waits_for_the_variables(monkeypatch):
    fake = FakeTdm()
    fake.node = fake
    monkeypatch.setitem(sys.modules, "tdmclient", fake.module)
    node = TdmDevice.connect()
    assert node.node is fake
    assert fake.waited_for == {
        "prox.horizontal",
        "motor.left.speed",
        "motor.right.speed",
        "motor.left.target",
        "motor.right.target",
    }


@pytest.mark.parametrize(
    "fake, message",
    [
        (FakeTdm(refuse=True), "cannot reach the Thymio Device Manager at 127.0.0.1:8596"),
        (FakeTdm(node=None), "no Thymio appeared within 10 s"),
        (FakeTdm(node=object(), busy=True), "cannot take control of the robot"),
    ],
)
def test_connect_failures_are_user_errors_with_hints(monkeypatch, fake, message):
    monkeypatch.setitem(sys.modules, "tdmclient", fake.module)
    with pytest.raises(UserError) as error:
        TdmDevice.connect()
    assert message in str(error.value) and "hint:" in str(error.value)


def test_connect_names_the_address_and_robot_it_was_given(monkeypatch):
    monkeypatch.setitem(sys.modules, "tdmclient", FakeTdm(refuse=True).module)
    with pytest.raises(UserError, match="at 10.0.0.2:9000"):
        TdmDevice.connect(TdmAddress("10.0.0.2", 9000))
    monkeypatch.setitem(sys.modules, "tdmclient", FakeTdm(node=None).module)
    with pytest.raises(UserError, match="no Thymio named 'bob' appeared within 2 s"):
        ThymioRobot.connect(TdmAddress(robot_name="bob", timeout=2.0))


class FakeClient:
    """What a tdmclient ClientAsyncCacheNode asks of its client; delivers scripted variable updates."""

    debug = 0

    def __init__(self):
        self.packets: list[bytes] = []
        self.updates: list[dict] = []
        self.node = None
        self.request_id = 0
        self.disconnected = False

    def next_request_id(self, request_id_notify=None):
        self.request_id += 1
        return self.request_id

    def send_packet(self, packet, ignore_disconnected_error=False):
        self.packets.append(packet)

    def process_waiting_messages(self):
        while self.updates:
            self.node.notify_variables_changed(self.node, self.updates.pop(0))
        return False

    def disconnect(self):
        self.disconnected = True


def sent_variables(tdmclient, packet):
    """Decode a packet as the TDM would (tdmclient's own server does it this way)."""
    fb = tdmclient.FlatBuffer()
    fb.parse(packet, tdmclient.ThymioFB.SCHEMA)
    if fb.root.union_type != tdmclient.ThymioFB.MESSAGE_TYPE_SET_VARIABLES:
        return None
    return {v.fields[0][0]: v.fields[1][0] for v in fb.root.union_data[0].fields[2][0]}


def test_tdm_node_on_tdmclients_cache_node():
    tdmclient = _require.module("tdmclient")
    client = FakeClient()
    cache = tdmclient.ClientAsyncCacheNode(client, {"node_id": [7] * 16, "node_id_str": "fake", "status": 2})
    client.node = cache
    cache.notify_variables_changed(
        cache,
        {
            "prox.horizontal": [0] * 7,
            "motor.left.speed": [0],
            "motor.right.speed": [0],
            "motor.left.target": [0],
            "motor.right.target": [0],
        },
    )
    node = TdmDevice(client, cache)
    robot = ThymioRobot(node, spawn=START, clock=FakeClock(), sleep=lambda s: None)
    assert sent_variables(tdmclient, client.packets[-1]) == {"motor.left.target": [0], "motor.right.target": [0]}
    robot.drive(0.1, 1.0)
    assert sent_variables(tdmclient, client.packets[-1]) == {"motor.left.target": [133], "motor.right.target": [367]}
    client.updates.append(
        {"prox.horizontal": [0, 0, 3515, 0, 0, 2570, 0], "motor.left.speed": [131], "motor.right.speed": [369]}
    )
    robot.advance(0.1)
    assert robot.proximity_raw()["front_center"] == 3515
    assert robot.proximity()["rear_left"] == pytest.approx(0.05)
    assert robot.velocity().linear == pytest.approx((131 + 369) / 2 * 0.0004)
    robot.close()
    assert sent_variables(tdmclient, client.packets[-2]) == {"motor.left.target": [0], "motor.right.target": [0]}
    assert sent_variables(tdmclient, client.packets[-1]) is None  # the unlock request
    assert client.disconnected


# ------------------------------------------------------------ with the runner
class IdealWheels(FakeNode):
    """A robot whose wheels turn exactly at their targets and whose sensors see nothing."""

    def read_wheel_speeds(self):
        return self.writes[-1] if self.writes else (0, 0)


def test_the_runner_drives_the_square_mission_on_the_real_backend_and_closes_it():
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    node = IdealWheels()
    robot, _, clock, operator, said = make(node, spawn=None)
    mission = load_mission(f"{ROOT}/missions/square.yaml")
    result = Run(mission, backend=robot).run()
    assert result.status == "SUCCESS"
    assert len(operator.prompts) == 1  # place the robot at the start
    start = mission.start
    assert math.hypot(result.final_pose.x - start.x, result.final_pose.y - start.y) < 0.005
    assert node.closed and node.writes[-1] == (0, 0)  # motors stopped, robot released
    assert result.collisions == 0 and result.min_clearance is None
    assert sum(clock.sleeps) == pytest.approx(result.sim_time, abs=0.2)  # it ran in real time


def test_a_crash_inside_the_run_still_stops_the_motors():
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    node = IdealWheels()
    robot, *_ = make(node, spawn=None)
    run = Run(load_mission(f"{ROOT}/missions/square.yaml"), backend=robot)

    def interrupt(r):
        if r.ticks == 20:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run.run(on_tick=interrupt)
    assert node.closed and node.writes[-1] == (0, 0)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_real_robot_and_ends_the_run_interrupted(sig):
    from thymio_bt.mission import load_mission
    from thymio_bt.run.interrupts import Interrupts
    from thymio_bt.run.runner import Run

    node = IdealWheels()
    robot, *_ = make(node, spawn=None)
    run = Run(load_mission(f"{ROOT}/missions/square.yaml"), backend=robot)

    def signal_at_tick_20(r):
        if r.ticks == 20:
            os.kill(os.getpid(), sig)

    with Interrupts() as interrupts:
        result = run.run(on_tick=signal_at_tick_20, interrupts=interrupts)
    assert result.status == "FAILURE" and result.code == "INTERRUPTED" and result.ticks == 20
    assert signal.Signals(sig).name in result.reason and interrupts.exit_code == 128 + sig
    assert node.closed and node.writes[-1] == (0, 0)  # motors stopped, robot released
    assert result.report()["sim_time"] == pytest.approx(1.9)


def test_cli_backend_tdm_without_a_device_manager_is_a_user_error(monkeypatch):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    def refuse(*args, **kwargs):
        raise UserError("cannot reach the Thymio Device Manager (hint: start Thymio Suite)")

    monkeypatch.setattr(ThymioRobot, "connect", classmethod(refuse))
    result = CliRunner().invoke(main, ["run", f"{ROOT}/missions/square.yaml", "--backend", "tdm"])
    assert result.exit_code == 2 and "Thymio Device Manager" in result.output and "Traceback" not in result.output


def test_the_tdm_backend_takes_the_robot_model_and_its_options(monkeypatch):
    from thymio_bt.backends import backend_kind

    seen = {}

    def connect(cls, address, **kwargs):
        seen.update(host=address.tdm_addr, port=address.tdm_port, model=kwargs["model"])
        return make(FakeNode())[0]

    monkeypatch.setattr(ThymioRobot, "connect", classmethod(connect))
    from thymio_bt.mission import load_mission

    mission = load_mission(f"{ROOT}/missions/square.yaml", {"robot": "enki"})
    backend_kind("tdm").create(mission, 0, {"host": "127.0.0.1", "port": "8596"}).close()
    assert seen["host"] == "127.0.0.1" and seen["port"] == 8596
    assert seen["model"] is ENKI
