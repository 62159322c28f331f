"""The simulation's proximity sensors beyond the noise-free metres (:mod:`.readings`): Enki's
three-ray cones (:class:`ConeSensors`, :mod:`.cone`'s response) and a real Thymio's noisy
integer readings through the robot's calibration (:func:`raw_model`)."""

from __future__ import annotations

import math

import pymunk

from thymio_bt.backends.sim.cone import APERTURE, ConeResponse
from thymio_bt.backends.sim.fastpath import RayCaster
from thymio_bt.robot.model import RobotModel
from thymio_bt.sensor_tables import RawProximityModel


def raw_model(seed: int, model: RobotModel) -> RawProximityModel:
    """Noisy integer readings through ``model``'s calibration (a profile's measured table included)."""
    import numpy as np  # only raw mode needs it: keeps ~50 ms off every start-up

    return RawProximityModel(np.random.default_rng((seed, 1)), model.calibration)


class ConeSensors:
    """The seven sensors as Enki's cones (:mod:`thymio_bt.backends.sim.cone`): 21 rays, noisy integer readings."""

    def __init__(self, model: RobotModel, seed: int) -> None:
        import numpy as np

        self.response = ConeResponse()
        reach = self.response.range
        self.names = [s.name for s in model.sensors]
        #: each sensor's three rays in turn, (start, end) in the body frame
        self.rays = [
            (s.x, s.y, s.x + reach * math.cos(s.yaw + a), s.y + reach * math.sin(s.yaw + a))
            for s in model.sensors
            for a in (APERTURE, 0.0, -APERTURE)
        ]
        self.rng = np.random.default_rng((seed, 2))

    def measure(
        self, rays: RayCaster, shape_filter: pymunk.ShapeFilter, bx: float, by: float, cos: float, sin: float
    ) -> dict[str, int]:
        """The readings of a robot at (bx, by), heading with this cosine and sine, whose own shape
        ``shape_filter`` skips."""
        alphas = rays.fan(self.rays, bx, by, cos, sin, shape_filter)
        reach, response = self.response.range, self.response
        draws = self.rng.standard_normal(len(self.names))
        readings = {}
        for i, (name, z) in enumerate(zip(self.names, draws, strict=True)):
            hits = [None if alpha is None else alpha * reach for alpha in alphas[3 * i : 3 * i + 3]]
            readings[name] = response.reading(response.value(*hits), float(z))
        return readings
