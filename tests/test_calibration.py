"""The proximity calibration (Webots' Thymio II table) and the raw sensor model."""

import doctest
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from thymio_bt import sensor_tables as calibration
from thymio_bt.robot.interface import SENSOR_NAMES
from thymio_bt.sensor_tables import (
    ENKI_THYMIO2,
    WEBOTS_THYMIO2,
    CalibrationTable,
    RawProximityModel,
    metres_to_raw,
    raw_scan_to_metres,
    raw_to_metres,
)

TABLE = WEBOTS_THYMIO2
#: The table as usually quoted: Webots' rows at 1..9 cm.
QUOTED = {0.01: 4279, 0.02: 4139, 0.03: 3515, 0.04: 2965, 0.05: 2570, 0.06: 2248, 0.07: 1941, 0.08: 1597, 0.09: 1195}

in_table = st.floats(min_value=TABLE.min_distance, max_value=TABLE.max_distance, exclude_max=True)
readings = st.floats(min_value=0.0, max_value=TABLE.max_reading, exclude_min=True)


def test_the_module_examples_hold():
    assert doctest.testmod(calibration).failed == 0


@pytest.mark.parametrize("distance, reading", sorted(QUOTED.items()))
def test_the_1_cm_rows_are_the_quoted_table(distance, reading):
    assert metres_to_raw(distance) == reading
    assert raw_to_metres(reading) == pytest.approx(distance, abs=1e-12)


def test_3_cm_reads_about_3400_as_the_course_report_measured():
    assert metres_to_raw(0.03) == pytest.approx(3400, rel=0.04)
    assert raw_to_metres(3400) == pytest.approx(0.032, abs=0.0005)


def test_nothing_in_range_reads_0_and_0_means_nothing():
    for far in (TABLE.max_distance, 0.0975, 0.5, math.inf):
        assert metres_to_raw(far) == 0.0
    assert raw_to_metres(0) == math.inf
    assert raw_to_metres(-3) == math.inf


def test_the_close_end_saturates_and_converts_back_to_the_first_row():
    for close in (-0.01, 0.0, 0.0005, TABLE.min_distance):
        assert metres_to_raw(close) == 4308
    for strong in (4308, 4500, 10_000):
        assert raw_to_metres(strong) == TABLE.min_distance


def test_beyond_9_cm_webots_ramps_linearly_to_0_at_9_333_cm():
    assert metres_to_raw(0.09 + (0.09333 - 0.09) / 2) == pytest.approx(1195 / 2)
    assert 0.09 < raw_to_metres(1) < 0.09333


@given(st.floats(min_value=-0.01, max_value=0.2), st.floats(min_value=-0.01, max_value=0.2))
def test_metres_to_raw_is_monotone(a, b):
    near, far = sorted((a, b))
    assert metres_to_raw(near) >= metres_to_raw(far)


@given(in_table)
def test_metres_round_trip_exactly(distance):
    assert raw_to_metres(metres_to_raw(distance)) == pytest.approx(distance, rel=1e-12, abs=1e-15)


@given(readings)
def test_readings_round_trip_exactly(reading):
    assert metres_to_raw(raw_to_metres(reading)) == pytest.approx(reading, rel=1e-12, abs=1e-9)


@given(st.floats(min_value=TABLE.min_distance, max_value=0.0933))
def test_integer_readings_lose_at_most_0_17_mm(distance):
    # the flattest segment is 4308 -> 4298 over 3.33 mm: half a unit is 0.167 mm
    assert raw_to_metres(round(metres_to_raw(distance))) == pytest.approx(distance, abs=0.000167)


def test_a_table_must_be_invertible():
    with pytest.raises(ValueError, match="decrease strictly"):
        CalibrationTable((0.0, 0.01, 0.02), (4235.0, 4308.0, 0.0))  # Webots' own 0 m row
    with pytest.raises(ValueError, match="last reading must be 0"):
        CalibrationTable((0.01, 0.02), (3000.0, 1000.0))
    with pytest.raises(ValueError, match="two"):
        CalibrationTable((0.01,), (0.0,))


def test_a_raw_scan_converts_by_sensor_name():
    raw = dict(zip(SENSOR_NAMES, (0, 4308, 3515, 2570, 1195, 0, 2965), strict=True))
    scan = raw_scan_to_metres(raw)
    assert tuple(scan) == SENSOR_NAMES
    assert scan["front_left"] == scan["rear_left"] == math.inf
    assert scan["front_center"] == pytest.approx(0.03)
    assert scan["rear_right"] == pytest.approx(0.04)


def test_without_noise_the_model_reads_the_rounded_table():
    model = RawProximityModel(np.random.default_rng(0), relative_sd=0.0)
    assert model.measure(0.05) == 2570
    assert model.measure(0.025) == 3857
    assert model.measure(math.inf) == 0
    assert model.measure(0.0933) == 11  # 9.33 cm: the last millimetres of the ramp


def test_the_model_is_deterministic_for_a_seed():
    scan = dict(zip(SENSOR_NAMES, (0.02, 0.05, math.inf, 0.07, 0.09, 0.01, math.inf), strict=True))

    def readings(seed):
        model = RawProximityModel(np.random.default_rng(seed))
        return [model.measure_scan(scan) for _ in range(20)]

    assert readings(3) == readings(3)
    assert readings(3) != readings(4)


def test_what_one_sensor_sees_does_not_shift_the_others_noise():
    a = RawProximityModel(np.random.default_rng(7)).measure_scan({"x": 0.05, "y": math.inf, "z": 0.05})
    b = RawProximityModel(np.random.default_rng(7)).measure_scan({"x": 0.05, "y": 0.02, "z": 0.05})
    assert a["y"] == 0 and b["y"] > 0
    assert (a["x"], a["z"]) == (b["x"], b["z"])


def test_the_default_noise_is_webots_1_percent_and_enkis_is_absolute():
    webots = RawProximityModel(np.random.default_rng(1))
    values = np.array([webots.measure(0.05) for _ in range(4000)])
    assert values.mean() == pytest.approx(2570, abs=2)
    assert values.std() == pytest.approx(25.7, rel=0.06)
    assert all(isinstance(v, int) for v in (webots.measure(0.05), webots.measure(math.inf)))
    enki = RawProximityModel(np.random.default_rng(1), relative_sd=0.0, absolute_sd=2.87)
    assert np.std([enki.measure(0.02) for _ in range(4000)]) == pytest.approx(2.87, rel=0.06)


def test_noisy_readings_are_clipped_at_0_and_nothing_seen_stays_exactly_0():
    model = RawProximityModel(np.random.default_rng(2), relative_sd=0.0, absolute_sd=500.0)
    near_the_edge = [model.measure(0.0932) for _ in range(200)]
    assert min(near_the_edge) == 0 and max(near_the_edge) > 0
    assert all(model.measure(0.2) == 0 for _ in range(50))


def test_through_raw_gives_metres_back_within_the_noise():
    model = RawProximityModel(np.random.default_rng(5))
    scan = dict(zip(SENSOR_NAMES, (0.074, 0.05, 0.03, 0.05, 0.074, math.inf, 0.0955), strict=True))
    back = model.through_raw(scan)
    assert tuple(back) == SENSOR_NAMES
    assert back["rear_left"] == math.inf
    assert back["rear_right"] == math.inf  # 9.55 cm: in the course's range, beyond the table's
    for name in ("front_left", "front_center_left", "front_center"):
        assert back[name] == pytest.approx(scan[name], abs=0.003)


def test_the_enki_table_is_its_closed_form_and_sees_to_14_cm():
    m, x0, c = 4505, 0.03, 73  # IRSensor parameters, distances in cm
    for cm in range(14):
        assert metres_to_raw(cm / 100, ENKI_THYMIO2) == round(m * (c - x0**2) / (cm**2 - 2 * x0 * cm + c))
    assert metres_to_raw(0.1399, ENKI_THYMIO2) == pytest.approx(1226, abs=2)
    assert metres_to_raw(0.14, ENKI_THYMIO2) == 0
    # the same reading means a longer distance on Enki's hotter curve
    assert raw_to_metres(3366, ENKI_THYMIO2) == pytest.approx(0.05)
    assert raw_to_metres(3366) == pytest.approx(0.033, abs=0.001)


@pytest.mark.parametrize(
    "distances, readings, floor, said",
    [
        ((0.01, math.nan, 0.05), (4000.0, 2000.0, 0.0), 0.0, "distance 2 is nan"),  # passed every ordering check
        ((0.01, 0.03, math.inf), (4000.0, 2000.0, 0.0), 0.0, "distance 3 is inf"),
        ((0.01, 0.03, 0.05), (math.inf, 2000.0, 0.0), 0.0, "reading 1 is inf"),
        ((0.01, 0.03, 0.05), (4000.0, 2000.0, 0.0), math.inf, "floor is inf"),  # every reading noise
        ((-math.inf, 0.03, 0.05), (4000.0, 2000.0, 0.0), 0.0, "distance 1 is -inf"),
    ],
)
def test_a_table_holds_finite_numbers(distances, readings, floor, said):
    with pytest.raises(ValueError, match=f"^{said}: a calibration table holds finite numbers$"):
        CalibrationTable(distances, readings, floor=floor)
