"""Enki's proximity sensors: each a cone of three rays, combined as Enki combines them.

A real Thymio's infrared sensor sees a cone, not a line; Enki (the Thymio makers' simulator, inside
Aseba Playground) models it with three rays at -15°, 0° and +15° (enki/interactions/IRSensor.cpp).
Each ray's distance ``d`` gives ``f(d)``, Enki's response (``m (c - x0²) / (d² - 2 x0 d + c)`` in
cm, ``m`` below ``x0``, 0 beyond the range); the centre ray counts ``f(d) - 2 f(d / cos 15°)``, so
that on a wall square to the sensor, where the side rays hit at ``d / cos 15°``, the sum is exactly
``f(d)``. At other angles it is not: a side wall seen at a slant reads weaker, and a wall's end is
lost by the cone before a single ray would lose it. The sum gets Gaussian noise (sd 2.87), is
clipped to [0, m] and read as an integer, as ``prox.horizontal``.

Example::

    >>> cone = ConeResponse()
    >>> side = 0.05 / math.cos(APERTURE)           # a wall square to the sensor, 5 cm away
    >>> round(cone.value(side, 0.05, side), 2)     # f(0.05): the centre ray alone
    3366.03
    >>> cone.reading(cone.value(side, 0.05, side), z=0.0), cone.reading(0.0, z=-1.0)   # clipped at 0
    (3366, 0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: the half-angle between a sensor's centre ray and its side rays
APERTURE = math.radians(15.0)


@dataclass(frozen=True, slots=True)
class ConeResponse:
    """Enki's Thymio2 sensor response (Thymio2.cpp: range 14 cm, m 4505, x0 0.03, c 73, noise 2.87)."""

    range: float = 0.14
    m: float = 4505.0
    x0: float = 0.03
    c: float = 73.0
    noise_sd: float = 2.87

    def f(self, distance: float | None) -> float:
        """One ray's contribution for a hit at ``distance`` metres (None: no hit)."""
        if distance is None:
            return 0.0
        x = distance * 100.0  # Enki works in cm
        if x < self.x0:
            return self.m
        if x > self.range * 100.0:
            return 0.0
        return self.m * (self.c - self.x0 * self.x0) / (x * x - 2.0 * self.x0 * x + self.c)

    def value(self, left: float | None, centre: float | None, right: float | None) -> float:
        """The noise-free reading of one sensor from its three rays' distances (None: no hit)."""
        middle = 0.0 if centre is None else self.f(centre) - 2.0 * self.f(centre / math.cos(APERTURE))
        return self.f(left) + middle + self.f(right)

    def reading(self, value: float, z: float) -> int:
        """The integer ``prox.horizontal`` for a noise-free ``value`` and a standard normal draw ``z``."""
        return int(max(0.0, min(self.m, value + self.noise_sd * z)))
