"""The ``sim`` backend kind: a :class:`~thymio_bt.backends.sim.world.Simulation` of a mission's maze.

Example::

    >>> from thymio_bt.backends.sim.options import SimOptions
    >>> from thymio_bt.mission import load_mission
    >>> sim = create(load_mission("maze_part1_2"), seed=0, options=SimOptions())
    >>> sim.model.name, sim.config.sensor_model, sim.config.physics_hz
    ('course', 'metres', 100.0)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from thymio_bt.backends.sim.world import SimConfig, Simulation
from thymio_bt.robot.model import is_sim_sensor_model, robot_model

if TYPE_CHECKING:
    from thymio_bt.backends import MissionWorld
    from thymio_bt.backends.sim.options import SimOptions


def create(mission: MissionWorld, seed: int, options: SimOptions) -> Simulation:
    """The simulation of ``mission``'s maze with its robot model, noise and sensor model."""
    if not is_sim_sensor_model(mission.sensor_model):  # a checked mission's never is
        raise ValueError(f"no sensor model named {mission.sensor_model!r}")
    return Simulation(
        mission.maze,
        config=SimConfig(
            physics_hz=options.physics_hz,
            noise=mission.noise,
            seed=seed,
            sensor_model=mission.sensor_model,
            robot=robot_model(mission.robot),
        ),
    )
