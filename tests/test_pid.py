"""The report's PID (Algorithm 1) on its own: step response, saturation, windup recovery."""

import math

import pytest

from thymio_bt.robot.pid import PID


def simulate(pid, setpoint=1.0, steps=300, dt=0.05, gain=1.0, tau=0.5, disturbance=0.0):
    """A first-order plant x' = (gain*u - x)/tau + disturbance, from x = 0."""
    x, out = 0.0, []
    for _ in range(steps):
        u = pid(setpoint - x, dt)
        x += dt * ((gain * u - x) / tau + disturbance)
        out.append((u, x))
    return out


def test_proportional_step_response_settles_with_the_expected_offset():
    trace = simulate(PID(kp=3.0))
    assert trace[-1][1] == pytest.approx(3 / 4, abs=1e-3)  # P only: x = kp/(1+kp)


def test_integral_removes_the_offset():
    trace = simulate(PID(kp=2.0, ki=2.0))
    assert trace[-1][1] == pytest.approx(1.0, abs=1e-3)


def test_output_is_limited():
    pid = PID(kp=10.0, limit=0.5)
    assert pid(1.0, 0.1) == 0.5 and pid(-1.0, 0.1) == -0.5


def test_trapezoidal_integral_and_derivative():
    pid = PID(kp=0.0, ki=1.0, kd=0.0)
    pid(1.0, 0.1)
    pid(3.0, 0.1)
    assert pid.integrator == pytest.approx(0.1 * 1.0 + 0.1 * (1.0 + 3.0) / 2)
    d = PID(kp=0.0, kd=1.0)
    d(1.0, 0.1)
    assert d(3.0, 0.1) == pytest.approx(20.0)


def test_anti_windup_recovers_faster_than_a_plain_integrator():
    def overshoot(anti_windup):
        pid = PID(kp=1.0, ki=4.0, limit=1.2 if anti_windup else math.inf)
        x, peak = 0.0, 0.0
        for _ in range(400):
            u = pid(1.0 - x, 0.05)
            u = max(-1.2, min(1.2, u))  # the actuator saturates either way
            x += 0.05 * (u - x) / 0.5
            peak = max(peak, x)
        return peak, pid.integrator

    peak_aw, integ_aw = overshoot(True)
    peak_plain, integ_plain = overshoot(False)
    assert peak_aw < peak_plain
    assert peak_aw < 1.1


def test_reset_clears_memory():
    pid = PID(kp=1.0, ki=1.0)
    pid(1.0, 0.1)
    pid.reset()
    assert pid.integrator == 0.0 and pid.previous is None
