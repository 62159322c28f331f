"""The simulated Thymio against the course's numbers (robot.md, mazes.md)."""

import itertools
import math
from pathlib import Path
from types import MappingProxyType

import pytest

from thymio_bt.backends.sim import NoiseConfig, SimConfig, Simulation, fastpath
from thymio_bt.maze import Maze, Wall, load_maze
from thymio_bt.robot.interface import SENSOR_NAMES, Pose
from thymio_bt.robot.model import COURSE as thymio_model
from thymio_bt.testing import world

ROOT = Path(__file__).resolve().parents[1]

COURSE = load_maze(f"{ROOT}/mazes/two_parts_maze.yaml")


def test_front_ray_reads_the_course_stop_distance():
    sim = Simulation(COURSE, spawn=Pose(0.4893, 0.1, 0.0))
    assert sim.proximity()["front_center"] == pytest.approx(0.0500, abs=0.0002)
    sim = Simulation(COURSE, spawn=Pose(0.4793, 0.1, 0.0))  # 1 cm further back
    assert sim.proximity()["front_center"] == pytest.approx(0.0600, abs=0.0002)
    sim = Simulation(COURSE, spawn=Pose(0.4893 - 0.048, 0.1, 0.0))  # gap 0.098 > range 0.0975
    assert sim.proximity()["front_center"] == math.inf


def test_scan_has_the_seven_named_sensors_and_inf_when_nothing_is_in_range():
    sim = Simulation(world("arena"), spawn=Pose(0.6, 0.6, 0.0))
    assert tuple(sim.proximity()) == SENSOR_NAMES
    assert all(v == math.inf for v in sim.proximity().values())


def test_centred_in_a_corridor_the_38_degree_rays_read_0_074():
    sim = Simulation(COURSE, spawn=Pose(0.2243, 0.1, 0.0))  # axle at x = 0.2, centred in y
    scan = sim.proximity()
    assert scan["front_left"] == pytest.approx(0.0742, abs=0.0005)
    assert scan["front_right"] == pytest.approx(scan["front_left"], abs=1e-9)


def test_rear_rays_read_equal_when_square_to_a_wall_behind():
    sim = Simulation(COURSE, spawn=Pose(0.5, 0.1, math.pi))  # rear faces Wall_4 at x = 0.6
    scan = sim.proximity()
    assert math.isfinite(scan["rear_left"])
    # Gazebo's wall yaw is 1.5708, not pi/2: the wall is tilted by 3.7e-6 rad, i.e. 0.2 um here
    assert scan["rear_left"] == pytest.approx(scan["rear_right"], abs=1e-6)
    assert scan["rear_left"] == pytest.approx(0.595 - 0.5 - 0.0543, abs=0.0002)
    tilted = Simulation(COURSE, spawn=Pose(0.5, 0.1, math.pi + 0.05)).proximity()
    assert abs(tilted["rear_left"] - tilted["rear_right"]) > 0.002


def test_one_second_at_0_1_m_per_s_moves_0_1_m():
    sim = Simulation(COURSE, spawn=Pose(0.1, 0.1, 0.0))
    sim.drive(0.1, 0.0)
    sim.advance(1.0)
    assert sim.pose().x - 0.1 == pytest.approx(0.100, abs=0.001)
    assert sim.pose().y == pytest.approx(0.1, abs=1e-6)
    assert sim.time() == pytest.approx(1.0)


def test_spinning_keeps_the_axle_fixed_and_base_link_on_a_0_0243_circle():
    sim = Simulation(COURSE, spawn=Pose(0.3, 0.1, 0.0))
    axle = (0.3 + thymio_model.axle_x, 0.1)
    sim.drive(0.0, math.pi / 2)
    for _ in range(10):
        sim.advance(0.1)
        p = sim.pose()
        assert math.hypot(p.x - axle[0], p.y - axle[1]) == pytest.approx(0.0243, abs=1e-6)
    assert sim.pose().yaw == pytest.approx(math.pi / 2, abs=1e-6)


def test_command_is_held_and_limited_to_the_wheel_speed_keeping_the_radius():
    assert thymio_model.limited_wheel_speeds(0.3, 0.0) == pytest.approx((0.2, 0.2))
    assert thymio_model.limited_wheel_speeds(0.05, 0.1) == thymio_model.wheel_speeds(0.05, 0.1)  # within the limit
    left, right = thymio_model.limited_wheel_speeds(0.2, 2.0)
    assert max(abs(left), abs(right)) == pytest.approx(0.2)
    v, w = thymio_model.body_velocity(left, right)
    assert v / w == pytest.approx(0.2 / 2.0)  # same turn radius
    sim = Simulation(world("arena"), spawn=Pose(0.3, 0.6, 0.0))
    sim.drive(1.0, 0.0)
    sim.advance(1.0)
    assert sim.pose().x - 0.3 == pytest.approx(0.2, abs=0.001)


@pytest.mark.parametrize("speed", [0.05, 0.2, 5.0])
def test_driving_into_a_wall_stops_without_tunnelling_and_counts_one_collision(speed):
    sim = Simulation(COURSE, spawn=Pose(0.1, 0.1, 0.0))
    sim.drive(speed, 0.0)
    sim.advance(12.0)
    nose = sim.pose().x + 0.0557
    assert nose == pytest.approx(0.595, abs=0.001)  # the face of Wall_4
    assert len(sim.collisions) == 1
    assert sim.collisions[0].x == pytest.approx(0.595, abs=0.001)
    assert sim.min_clearance == 0.0


def test_a_collision_episode_is_counted_once_per_contact():
    sim = Simulation(COURSE, spawn=Pose(0.45, 0.1, 0.0))
    for _ in range(3):
        sim.drive(0.1, 0.0)
        sim.advance(2.0)
        sim.drive(-0.1, 0.0)
        sim.advance(1.0)
    assert len(sim.collisions) == 3


def test_clearance_is_the_hull_to_wall_gap():
    sim = Simulation(COURSE, spawn=Pose(0.2243, 0.1, 0.0))
    assert sim.min_clearance == pytest.approx(0.095 - 0.0559, abs=1e-6)  # sides, centred
    sim.drive(0.1, 0.0)
    sim.advance(3.0)  # nose from 0.280 to 0.580: 15 mm from Wall_4
    assert sim.min_clearance == pytest.approx(0.015, abs=1e-4)


@pytest.mark.parametrize(
    "pose, why",
    [
        (Pose(0.6, 0.1, 0.0), "overlaps a wall"),
        (Pose(0.05, 0.1, 0.0), "overlaps a wall"),
        (Pose(2.5, 0.1, 0.0), "outside the maze"),
        (Pose(0.1, 0.1, math.nan), "finite"),
    ],
)
def test_impossible_spawns_are_refused_and_change_nothing(pose, why):
    sim = Simulation(COURSE)
    request = sim.request_spawn("thymio", pose)
    sim.advance(0.1)
    assert request.state.value == "failed" and why in request.reason
    assert not sim.exists() and sim.pose() is None and sim.proximity() is None


def test_delete_and_spawn_complete_over_ticks_and_names_are_checked():
    sim = Simulation(COURSE, spawn=Pose(0.1, 0.1, 0.0))
    taken = sim.request_spawn("thymio", Pose(0.5, 0.3, math.pi / 2))
    unknown = sim.request_delete("robot2")
    delete = sim.request_delete("thymio")
    assert not delete.done and sim.exists()
    sim.advance(0.1)
    assert "already exists" in taken.reason and "no entity named 'robot2'" in unknown.reason
    assert delete.state.value == "succeeded" and not sim.exists()
    sim.drive(0.1, 0.0)  # dropped while no robot exists
    assert sim.command().linear == 0.0
    spawn = sim.request_spawn("thymio", Pose(0.5, 0.3, math.pi / 2))
    sim.advance(0.1)
    assert spawn.state.value == "succeeded"
    assert sim.pose() == Pose(0.5, 0.3, math.pi / 2)


def test_a_pose_checked_twice_is_measured_once_and_told_apart_bit_for_bit(monkeypatch):
    from thymio_bt.backends.sim import world as world_module
    from thymio_bt.robot.placement import placement_problem

    measured = []

    def counting(shapes, model, pose):
        measured.append(pose)
        return placement_problem(shapes, model, pose)

    monkeypatch.setattr(world_module, "placement_problem", counting)
    sim = Simulation(COURSE)
    start = Pose(0.1, 0.1, 0.0)
    assert sim.spawn_problem("thymio", start) is None and sim.spawn_problem("thymio", start) is None
    assert measured == [start]  # the runner's check, then the spawn request's: measured once
    # a wall's overlap says the yaw: 0.0 and -0.0 are two poses, each with its own answer
    for pose in (Pose(0.6, 0.1, 0.0), Pose(0.6, 0.1, -0.0), Pose(0.6, 0.1, 0.0)):
        assert sim.spawn_problem("thymio", pose) == placement_problem(COURSE, thymio_model, pose)
    assert "yaw -0.000" in sim.spawn_problem("thymio", Pose(0.6, 0.1, -0.0))
    assert len(measured) == 5  # the last pose is remembered: each change of pose is measured


def _trajectory(seed, noise):
    sim = Simulation(COURSE, spawn=Pose(0.1, 0.1, 0.0), config=SimConfig(noise=noise, seed=seed))
    out = []
    for i in range(50):
        sim.drive(0.1, 0.3 if i % 10 < 5 else -0.3)
        sim.advance(0.1)
        out.append((sim.true_pose(), tuple(sim.proximity().values())))
    return out


def test_same_seed_same_trajectory_bit_for_bit_and_noise_is_opt_in():
    noise = NoiseConfig(range_sd=0.001, wheel=0.03, odometry=0.02)
    assert _trajectory(3, noise) == _trajectory(3, noise)
    assert _trajectory(3, noise) != _trajectory(4, noise)
    assert _trajectory(3, NoiseConfig()) == _trajectory(4, NoiseConfig())


def test_drifting_odometry_differs_from_the_true_pose_only_when_enabled():
    sim = Simulation(
        world("arena"), spawn=Pose(0.6, 0.6, 0.0), config=SimConfig(noise=NoiseConfig(odometry=0.05), seed=1)
    )
    for _ in range(30):
        sim.drive(0.1, 0.2)
        sim.advance(0.1)
    odo, true = sim.pose(), sim.true_pose()
    assert 1e-5 < math.hypot(odo.x - true.x, odo.y - true.y) < 0.05


def test_wheels_slipping_against_a_wall_make_odometry_drift():
    sim = Simulation(COURSE, spawn=Pose(0.5, 0.1, 0.0), config=SimConfig(noise=NoiseConfig(odometry=1e-6), seed=1))
    sim.drive(0.1, 0.0)
    sim.advance(1.0)  # blocked by Wall_4 after 3.9 cm; the wheels keep turning
    assert sim.true_pose().x == pytest.approx(0.5393, abs=0.001)
    assert sim.pose().x == pytest.approx(0.6, abs=0.001)


def test_walls_are_boxes_that_extend_half_their_thickness_past_each_end():
    wall = Wall(start=(0, 0), end=(0.6, 0), thickness=0.01)
    xs = sorted(c[0] for c in wall.corners())
    assert xs[0] == pytest.approx(-0.005) and xs[-1] == pytest.approx(0.605)
    maze = Maze(walls=[wall])
    assert maze.bounds() == pytest.approx((-0.005, -0.005, 0.605, 0.005))


def test_fast_clearance_equals_the_exact_polygon_distance_at_random_poses():
    import random

    rng = random.Random(7)
    maze = load_maze(f"{ROOT}/mazes/maze_6x6.yaml")
    checked = 0
    while checked < 300:
        pose = Pose(rng.uniform(-0.8, 0.4), rng.uniform(-1.0, 0.2), rng.uniform(-math.pi, math.pi))
        probe = Simulation(maze)
        if probe.spawn_problem("thymio", pose):
            continue
        sim = Simulation(maze, spawn=pose)  # the spawn computes the clearance once
        tracker, entity = sim._clearance, sim._entities["thymio"]
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        exact = tracker.exact(list(tracker.walls), entity.shape, pose.x, pose.y, c, s)
        if exact < 0.05:  # within the tracked horizon
            assert sim.min_clearance == pytest.approx(exact, abs=1e-9)
            checked += 1


def test_a_gap_a_hair_below_the_record_is_recorded():
    """The tracker's one-query shortcut (nothing nearer than the record, to 1 pm) must not hide a gap
    a few nanometres below it: the record follows the exact distance down in 20 nm steps."""
    walls = [Wall(start=(0, 0), end=(0.6, 0)), Wall(start=(0, 0.2), end=(0.6, 0.2))]
    sim = Simulation(Maze(walls=walls), spawn=Pose(0.3, 0.1, 0.0))
    entity, tracker = sim._entities["thymio"], sim._clearance
    records = [sim.min_clearance]
    for step in range(1, 6):
        entity.body.position = (0.3, 0.1 + step * 2e-8)
        sim._refresh_sensors(entity)
        exact = tracker.exact(list(tracker.walls), entity.shape, 0.3, 0.1 + step * 2e-8, 1.0, 0.0)
        assert sim.min_clearance == pytest.approx(exact, abs=1e-12)
        records.append(sim.min_clearance)
    assert all(later < earlier for earlier, later in itertools.pairwise(records))


def test_rays_cast_when_read_give_the_readings_of_rays_cast_at_once(monkeypatch):
    """Noise-free metres are cast only when proximity() asks: every mission's trajectory, events
    and readings are those of casting at every refresh, and a robot spawned after a refresh is not
    seen until the next one, as before."""
    import glob

    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    def runs():
        out = []
        for path in sorted(glob.glob(f"{ROOT}/missions/*.yaml")):
            result = Run(load_mission(path)).run()
            out.append((result.trajectory, result.events, result.final_proximity, result.min_clearance))
        return out

    def in_front(sim):
        sim.advance(0.1)  # a refresh, not read
        sim.request_spawn("other", Pose(0.25, 0.1, math.pi))  # 6 cm ahead of the front sensors
        sim.advance(0.0)  # served: no physics step
        seen_after_spawn = dict(sim.proximity())
        sim.advance(0.1)
        return seen_after_spawn, dict(sim.proximity())

    lazy = runs(), in_front(Simulation(world("corridor"), spawn=Pose(0.1, 0.1, 0.0)))
    assert lazy[1][1]["front_center"] < lazy[1][0]["front_center"]  # seen from the next refresh on
    monkeypatch.setattr(Simulation, "_refresh_sensors", _eager(Simulation._refresh_sensors))
    assert (runs(), in_front(Simulation(world("corridor"), spawn=Pose(0.1, 0.1, 0.0)))) == lazy


def _eager(refresh):
    """``Simulation._refresh_sensors`` that casts all the rays at every refresh in one fan, as the
    simulation did before it cast each when first read."""

    def eager(sim, entity):
        refresh(sim, entity)
        if sim._scan is None:
            sim._scan = MappingProxyType(sim._cast(entity, *sim._sensed))

    return eager


def test_the_fast_path_gives_the_same_run_as_pymunks_public_api(monkeypatch):
    """fastpath calls pymunk's C step and ray query directly; the public API must agree bit for bit,
    through collisions, a delete and a respawn (the course mission), with noise on (rays cast at
    each refresh) and off (each ray cast when read)."""
    from thymio_bt.backends.sim import world as world_module
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    def first_hit(space, x, y, cos, sin, ray, shape_filter):
        sx, sy, ex, ey = ray
        return space.segment_query_first(
            (x + sx * cos - sy * sin, y + sx * sin + sy * cos),
            (x + ex * cos - ey * sin, y + ex * sin + ey * cos),
            0.0,
            shape_filter,
        )

    class PublicRays:
        def __init__(self, space):
            self.space = space

        def fan(self, rays, x, y, cos, sin, shape_filter):
            hits = [first_hit(self.space, x, y, cos, sin, ray, shape_filter) for ray in rays]
            return [None if hit is None else hit.alpha for hit in hits]

    class PublicReader:
        def __init__(self, space, rays, reach, floor, shape_filter):
            self.space, self.rays, self.names, self.reach, self.floor = space, rays, tuple(rays), reach, floor
            self.filter = shape_filter

        def read(self, name, x, y, cos, sin):
            hit = first_hit(self.space, x, y, cos, sin, self.rays[name], self.filter)
            return math.inf if hit is None else max(hit.alpha * self.reach, self.floor)

    noisy = load_mission(
        f"{ROOT}/missions/maze_part1_2.yaml", overrides={"noise.wheel": "0.027", "noise.range_sd": "0.001"}
    )
    quiet = load_mission(f"{ROOT}/missions/maze_part1_2.yaml")

    def runs():
        results = [Run(noisy, seed=seed).run() for seed in (0, 7)] + [Run(quiet).run()]
        return [(result.trajectory, result.events, result.collisions) for result in results]

    fast = runs()
    monkeypatch.setattr(world_module, "stepper", lambda space: (lambda _, dt: space.step(dt), None))
    monkeypatch.setattr(world_module, "RayCaster", PublicRays)
    monkeypatch.setattr(world_module, "RayReader", PublicReader)
    monkeypatch.setattr(fastpath, "_memory", lambda body: None)  # bodies through Chipmunk's calls
    assert runs() == fast


def test_bodies_are_read_and_written_in_chipmunks_memory_on_this_pymunk():
    """The layout check passes here (else the simulation silently takes the slower C calls), and the
    memory view reads what pymunk reads and writes what it writes."""
    import pymunk

    assert fastpath._layout_known()
    body = pymunk.Body(0.27, 0.001)
    body.center_of_gravity = (0.03, 0.0)
    body.position, body.angle = (0.4, -0.2), 2.5
    control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    x, y, angle = fastpath.body_reader(body)()
    assert (x, y, angle) == (*body.position, body.angle)
    fastpath.body_driver(body, control)(0.1, 0.3, True)
    assert body.velocity == 0.1 * body.rotation_vector and body.angular_velocity == 0.3
    assert tuple(control.velocity) == (0.1 * math.cos(angle), 0.1 * math.sin(angle))
    assert control.angular_velocity == 0.3
    fastpath.control_aimer(body, control)(0.2)
    fastpath.spinner(control)(-0.4)
    assert tuple(control.velocity) == (0.2 * math.cos(angle), 0.2 * math.sin(angle))
    assert control.angular_velocity == -0.4


def test_a_wall_crash_is_the_same_on_the_fast_path_and_the_public_api(monkeypatch):
    from thymio_bt.backends.sim import world as world_module

    def crash():
        sim = Simulation(world("corridor"), spawn=Pose(0.1, 0.1, 0.0))
        sim.drive(0.2, 0.3)
        trace = []
        for _ in range(40):
            sim.advance(0.1)
            trace.append((sim.true_pose(), dict(sim.proximity())))
        return trace, sim.collisions

    fast = crash()
    assert fast[1], "the robot must hit a wall in this world"
    monkeypatch.setattr(world_module, "stepper", lambda space: (lambda _, dt: space.step(dt), None))
    monkeypatch.setattr(fastpath, "_memory", lambda body: None)
    assert crash() == fast


def test_the_raw_sensor_model_reports_a_real_thymios_readings_and_their_metres():
    config = SimConfig(sensor_model="raw", seed=4)
    sim = Simulation(COURSE, spawn=Pose(0.4893, 0.1, 0.0), config=config)  # 5 cm from the wall
    raw = sim.proximity_raw()
    assert set(raw) == set(SENSOR_NAMES) and all(isinstance(v, int) for v in raw.values())
    assert 2450 < raw["front_center"] < 2700  # Webots' table: 2570 at 5 cm, 1 % noise
    assert sim.proximity()["front_center"] == pytest.approx(0.05, abs=0.001)
    far = Simulation(COURSE, spawn=Pose(0.4893 - 0.0445, 0.1, 0.0), config=config)  # 9.45 cm: ray hits
    assert far.proximity_raw()["front_center"] == 0 and far.proximity()["front_center"] == math.inf
    assert Simulation(COURSE, spawn=Pose(0.4893, 0.1, 0.0)).proximity_raw() is None  # metres by default


def test_raw_readings_are_seeded():
    def readings(seed):
        sim = Simulation(COURSE, spawn=Pose(0.4893, 0.1, 0.0), config=SimConfig(sensor_model="raw", seed=seed))
        out = []
        for _ in range(5):
            sim.advance(0.1)
            out.append(sim.proximity_raw()["front_center"])
        return out

    assert readings(1) == readings(1) != readings(2)


@pytest.mark.parametrize("sensor_model", ["metres", "raw", "cone"])
def test_raw_readings_says_whether_proximity_raw_gives_integers(sensor_model):
    """``raw_readings`` is what a calibration checks before sampling: a metres simulation said True
    (a class-wide claim) and calibrate failed two steps later asking whether the robot faced the wall."""
    sim = Simulation(world("arena"), spawn=Pose(0.6, 0.6, 0.0), config=SimConfig(sensor_model=sensor_model))
    sim.advance(0.1)
    assert sim.raw_readings == (sim.proximity_raw() is not None) == (sensor_model != "metres")
