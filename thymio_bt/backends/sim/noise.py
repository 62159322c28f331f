"""The simulator's noise draws, all seeded so that the same seed gives the same run bit for bit.

The settings (:class:`NoiseConfig`, :data:`REALISTIC`) live in :mod:`thymio_bt.robot.noise`;
they are importable from here too.

Example::

    >>> NoiseSource(NoiseConfig(), seed=1).wheel_factors()        # noise off: exact
    (1.0, 1.0)
    >>> noisy = NoiseSource(REALISTIC, seed=1)
    >>> noisy.wheel_factors() == NoiseSource(REALISTIC, seed=1).wheel_factors()   # a seed, a stream
    True
    >>> noisy.range(float("inf"), 0.0005, 0.0975)                 # nothing seen stays nothing seen
    inf
"""

from __future__ import annotations

import math
import random

from thymio_bt.robot.noise import REALISTIC, NoiseConfig

__all__ = ["REALISTIC", "NoiseConfig", "NoiseSource"]


class NoiseSource:
    """The seeded random draws the simulator needs."""

    def __init__(self, config: NoiseConfig, seed: int) -> None:
        self.config = config
        self._rng = random.Random(seed)
        self._gauss = self._rng.gauss
        self._range_sd = config.range_sd  # read per ray: kept out of the model

    def wheel_factors(self) -> tuple[float, float]:
        """Each wheel's speed factor for a new command: 1 ± ``wheel`` (uniform), or exactly 1 when off."""
        a = self.config.wheel
        if not a:
            return 1.0, 1.0
        return 1.0 + self._rng.uniform(-a, a), 1.0 + self._rng.uniform(-a, a)

    def encoder_factors(self) -> tuple[float, float]:
        """Each wheel encoder's factor for one dead-reckoning step: 1 ± ``odometry`` (uniform)."""
        a = self.config.odometry
        return 1.0 + self._rng.uniform(-a, a), 1.0 + self._rng.uniform(-a, a)

    def range(self, value: float, lo: float, hi: float) -> float:
        """A range reading with Gaussian noise (sd ``range_sd``): inf stays inf, above ``hi`` reads inf, below
        ``lo`` reads ``lo``."""
        sd = self._range_sd
        if not sd or math.isinf(value):
            return value
        noisy = value + self._gauss(0.0, sd)
        if noisy > hi:
            return math.inf
        return max(noisy, lo)
