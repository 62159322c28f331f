"""Opt-in noise models, all seeded so that the same seed gives the same run bit for bit.

Defaults are off (the course's Gazebo model is noise-free). :data:`REALISTIC` holds the values a
sweep switches on: plausible for a real Thymio II (../shared/research/sim_anchors.md).
"""

from __future__ import annotations

import math
import random

from pydantic import BaseModel, ConfigDict, Field


class NoiseConfig(BaseModel):
    """Noise switches: all zero means the ideal, noise-free Gazebo robot."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    range_sd: float = Field(
        0.0, ge=0, le=0.05, allow_inf_nan=False, description="Gaussian sd added to each finite proximity range, m"
    )
    wheel: float = Field(
        0.0,
        ge=0,
        le=0.5,
        allow_inf_nan=False,
        description="uniform ± fraction on each wheel's speed, resampled every tick (Enki uses 0.027)",
    )
    odometry: float = Field(
        0.0,
        ge=0,
        le=0.5,
        allow_inf_nan=False,
        description="uniform ± fraction of wheel-encoder error; > 0 makes odometry drift instead of reporting the true pose",
    )

    @property
    def enabled(self) -> bool:
        return bool(self.range_sd or self.wheel or self.odometry)


#: What ``thymio-bt sweep`` switches on: Enki's ±2.7 % wheel noise, 1 mm range noise, 1 % encoder error.
REALISTIC = NoiseConfig(range_sd=0.001, wheel=0.027, odometry=0.01)


class NoiseSource:
    """The seeded random draws the simulator needs."""

    def __init__(self, config: NoiseConfig, seed: int) -> None:
        self.config = config
        self._rng = random.Random(seed)
        self._gauss = self._rng.gauss
        self._range_sd = config.range_sd  # read per ray: kept out of the model

    def wheel_factors(self) -> tuple[float, float]:
        a = self.config.wheel
        if not a:
            return 1.0, 1.0
        return 1.0 + self._rng.uniform(-a, a), 1.0 + self._rng.uniform(-a, a)

    def encoder_factors(self) -> tuple[float, float]:
        a = self.config.odometry
        return 1.0 + self._rng.uniform(-a, a), 1.0 + self._rng.uniform(-a, a)

    def range(self, value: float, lo: float, hi: float) -> float:
        sd = self._range_sd
        if not sd or math.isinf(value):
            return value
        noisy = value + self._gauss(0.0, sd)
        if noisy > hi:
            return math.inf
        return max(noisy, lo)
