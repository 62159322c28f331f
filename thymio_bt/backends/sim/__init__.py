"""The pymunk backend: a Thymio (any :class:`~thymio_bt.robot.model.RobotModel`), its sensors and
noise models, in a maze.

Importing this package loads no physics engine: ``Simulation``, ``SimConfig`` and ``Collision``
load :mod:`.world` (and pymunk, with :mod:`.fastpath` and :mod:`.clearance`) on first use, so
layers that need only the noise settings (the mission loader) stay light. The robot's geometry
lives in :mod:`thymio_bt.robot.model`, the noise settings in :mod:`thymio_bt.robot.noise`.
"""

from typing import Any

from thymio_bt.robot.noise import REALISTIC, NoiseConfig

__all__ = ["Collision", "NoiseConfig", "REALISTIC", "SimConfig", "Simulation"]


def __getattr__(name: str) -> Any:
    """The simulation's classes, from :mod:`.world` on first use (PEP 562)."""
    if name in ("Collision", "SimConfig", "Simulation"):
        from thymio_bt.backends.sim import world

        return getattr(world, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
