"""How noisy a robot is: the settings of the noise models (``noise:`` in a mission, ``--set noise.wheel=...``).

Defaults are off (the course's Gazebo model is noise-free). :data:`REALISTIC` holds the values a
sweep switches on: plausible for a real Thymio II (docs/sources.md, "Enki and the real robot").
The seeded draws themselves live with the simulator (:mod:`thymio_bt.backends.sim.noise`); these
settings live here so that checking a mission never loads a simulator module.

>>> REALISTIC.enabled, NoiseConfig().enabled
(True, False)
"""

from __future__ import annotations

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
        description=(
            "uniform ± fraction of wheel-encoder error; > 0 makes odometry drift instead of reporting the true pose"
        ),
    )

    def settings(self) -> dict[str, str]:
        """These values as a mission's ``--set`` overrides (what a sweep or a graded world passes on).

        >>> NoiseConfig().settings()
        {'noise.range_sd': '0', 'noise.wheel': '0', 'noise.odometry': '0'}
        >>> REALISTIC.settings()["noise.wheel"]
        '0.027'
        """
        return {f"noise.{name}": repr(value).removesuffix(".0") for name, value in self.model_dump().items()}

    @property
    def enabled(self) -> bool:
        """Whether any noise model is on."""
        return bool(self.range_sd or self.wheel or self.odometry)


#: What ``thymio-bt sweep`` switches on: Enki's ±2.7 % wheel noise, 1 mm range noise, 1 % encoder error.
REALISTIC = NoiseConfig(range_sd=0.001, wheel=0.027, odometry=0.01)
