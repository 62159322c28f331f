"""A PID controller as in the student report's Algorithm 1.

Trapezoidal integral, a finite-difference derivative, an output limit, and anti-windup: while the
output saturates the integrator does not take the step that drove it there.

Example::

    >>> heading = PID(kp=3.0, limit=math.pi)
    >>> round(heading(error=0.4, dt=0.1), 6)  # rad/s
    1.2
    >>> heading(error=2.0, dt=0.1) == math.pi  # limited
    True
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class PID:
    """u = kp·e + ki·∫e + kd·de/dt, limited to ±limit."""

    kp: float
    ki: float = 0.0
    kd: float = 0.0
    limit: float = math.inf
    integrator: float = 0.0
    previous: float | None = None

    def __call__(self, error: float, dt: float) -> float:
        """The output for ``error`` after ``dt`` seconds (> 0) since the last call."""
        if dt <= 0:
            raise ValueError("dt must be positive")
        previous = error if self.previous is None else self.previous
        step = dt * (error + previous) / 2.0
        self.integrator += step
        derivative = (error - previous) / dt
        u = self.kp * error + self.ki * self.integrator + self.kd * derivative
        if abs(u) > self.limit:
            if self.ki != 0.0:
                self.integrator -= step  # anti-windup: no integration while saturated
            u = math.copysign(self.limit, u)
        self.previous = error
        return u

    def reset(self) -> None:
        """Forget the integral and the last error (a new goal)."""
        self.integrator = 0.0
        self.previous = None
