"""The pymunk backend: the course's Thymio, its sensors and noise models, in a maze."""

from .noise import REALISTIC, NoiseConfig
from .world import Collision, SimConfig, Simulation

__all__ = ["Collision", "NoiseConfig", "REALISTIC", "SimConfig", "Simulation"]
