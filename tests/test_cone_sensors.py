"""Enki's cone sensors (three rays, Enki's combination and response) and the Enki robot profile:
the readings Enki gives, its command delay and its motor noise, chosen by --robot enki."""

import math
from pathlib import Path

import pytest

from thymio_bt.backends.sim import SimConfig, Simulation
from thymio_bt.backends.sim.cone import APERTURE, ConeResponse
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import ENKI
from thymio_bt.run.runner import Run
from thymio_bt.sensor_tables import ENKI_THYMIO2
from thymio_bt.testing import world

ROOT = Path(__file__).resolve().parents[1]

CONE = ConeResponse()
WALL = world("""
+--+--+--+
|>       |
+--+--+--+
""")


@pytest.mark.parametrize("d_cm, enki", [(3, 4019), (5, 3366), (9, 2142), (10, 1907), (14, 1293)])
def test_a_square_wall_reads_enkis_curve(d_cm, enki):
    d = d_cm / 100
    side = d / math.cos(APERTURE)
    # the side rays beyond the range see nothing: the sum is then the centre ray's share only
    sides = side if side <= CONE.range else None
    value = CONE.value(sides, d, sides)
    assert value == pytest.approx(enki, abs=1.0) if sides is not None else value < enki


def test_a_slanted_wall_reads_weaker_than_a_square_one():
    d = 0.11
    square = CONE.value(d / math.cos(APERTURE), d, d / math.cos(APERTURE))
    slanted = CONE.value(None, d, d * 0.9)  # 30 degrees: one side ray misses, the other hits sooner
    assert slanted < 0.5 * square


def test_noise_and_clipping_make_integer_readings():
    assert CONE.reading(0.0, -3.0) == 0 and CONE.reading(0.0, 2.0) == 5
    assert CONE.reading(5000.0, 0.0) == 4505 and isinstance(CONE.reading(1234.5, 0.1), int)


def sim_facing_wall(distance: float, model=ENKI, seed: int = 0) -> Simulation:
    """A robot whose front centre sensor is ``distance`` from the east wall of a 0.6 m corridor."""
    sensor = model.sensor("front_center")
    x = 0.6 - 0.005 - distance - sensor.x
    return Simulation(WALL, spawn=Pose(x, 0.1, 0.0), config=SimConfig(robot=model, sensor_model="cone", seed=seed))


@pytest.mark.parametrize("d", [0.03, 0.05, 0.09])
def test_the_simulated_cone_reads_enkis_value_and_the_enki_calibration_gives_the_distance_back(d):
    sim = sim_facing_wall(d)
    sim.advance(0.1)
    raw = sim.proximity_raw()["front_center"]
    assert abs(raw - ENKI_THYMIO2.to_raw(d)) < 15  # Enki's noise sd is 2.87
    assert sim.proximity()["front_center"] == pytest.approx(d, abs=0.0015)
    assert sim.proximity_raw()["rear_left"] < 20 and math.isinf(sim.proximity()["rear_left"])


def slanted_wall(d: float, incidence_deg: float) -> float:
    """The noise-free reading of a flat wall whose normal is ``incidence_deg`` off the centre ray,
    ``d`` metres away along that ray."""
    p = d * math.cos(math.radians(incidence_deg))  # the wall's perpendicular distance
    rays = []
    for phi in (-15.0, 0.0, 15.0):
        a = math.radians(incidence_deg + phi)
        rays.append(p / math.cos(a) if abs(a) < math.pi / 2 else None)
    return CONE.value(*rays)


def test_slanted_walls_read_as_enki_measured():
    """Enki's numbers (research note): at 30° 1680 at 11 cm, 375 at 11.5 cm, ~1300 at 15 cm; at 60°
    flat at 850-930 from 7.5 to 13.5 cm."""
    assert [round(slanted_wall(d, 30)) for d in (0.11, 0.115, 0.15)] == pytest.approx([1680, 375, 1300], abs=5)
    assert all(840 <= slanted_wall(d / 100, 60) <= 930 for d in (7.5, 9, 11, 13.5))


def test_the_cone_and_a_single_ray_see_the_end_of_a_side_wall_at_different_places():
    """Past a wall's end on the right, the ±40° sensor's cone and its single ray disagree by
    centimetres: what a behaviour deciding 'the side is open' from one reading cannot survive."""
    open_corner = world("""
    +--+--+--+--+
    |>          |
    +--+  +--+--+
    """)
    lost = {}
    for model_name in ("metres", "cone"):
        sim = Simulation(open_corner, spawn=Pose(0.1, 0.1, 0.0), config=SimConfig(robot=ENKI, sensor_model=model_name))
        sim.drive(0.05, 0.0)
        while not math.isinf(sim.proximity()["front_right"]) or sim.time() < 0.5:
            sim.advance(0.01)
            assert sim.time() < 10
        lost[model_name] = sim.true_pose().x
    assert abs(lost["cone"] - lost["metres"]) > 0.01  # 1.5 cm here


def test_enkis_profile_is_its_cones_its_command_delay_and_its_motor_noise():
    mission = load_mission(f"{ROOT}/missions/square.yaml", {"robot": "enki"})
    assert mission.sensor_model == "cone" and mission.noise.wheel == 0.027
    quiet = load_mission(
        f"{ROOT}/missions/square.yaml", {"robot": "enki", "noise.wheel": "0", "sensor_model": "metres"}
    )
    assert quiet.sensor_model == "metres" and quiet.noise.wheel == 0.0
    assert load_mission(f"{ROOT}/missions/square.yaml").sensor_model == "metres"  # the course's rays


def test_a_command_is_applied_one_physics_step_late_on_enki():
    sim = Simulation(world("arena"), spawn=Pose(0.3, 0.3, 0.0), config=SimConfig(robot=ENKI))
    sim.drive(0.1, 0.0)
    sim.advance(1.0)
    assert sim.true_pose().x - 0.3 == pytest.approx(0.099, abs=2e-4)  # 10 ms late: 9.9 cm, not 10
    course = Simulation(world("arena"), spawn=Pose(0.3, 0.3, 0.0))
    course.drive(0.1, 0.0)
    course.advance(1.0)
    assert course.true_pose().x - 0.3 == pytest.approx(0.1, abs=2e-4)


def test_enki_runs_are_deterministic():
    mission = load_mission(f"{ROOT}/missions/maze_bonus.yaml", {"robot": "enki"})
    a, b = Run(mission, 3).run(), Run(mission, 3).run()
    assert a.trajectory == b.trajectory and a.status == "SUCCESS"
