"""The pymunk backend: the course's Thymio, its sensors and noise models, in a maze.

``thymio``, ``noise`` and ``fastpath`` are separate modules; only :mod:`.world` (and so
``Simulation``) imports pymunk, on first use, so layers that need the robot's geometry or the
noise settings (behaviours, the mission loader) do not load the physics engine.
"""

from typing import Any

from thymio_bt.robot.noise import REALISTIC, NoiseConfig

__all__ = ["Collision", "NoiseConfig", "REALISTIC", "SimConfig", "Simulation"]


def __getattr__(name: str) -> Any:
    if name in ("Collision", "SimConfig", "Simulation"):
        from thymio_bt.backends.sim import world

        return getattr(world, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
