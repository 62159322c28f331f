"""The ``sim`` backend's settings (``--backend-opt KEY=VALUE`` or a mission's ``backend:`` block).

Example::

    >>> SimOptions(physics_hz=200).physics_hz
    200.0
"""

from __future__ import annotations

from pydantic import Field

from thymio_bt.backends import BackendOptions


class SimOptions(BackendOptions):
    """The ``sim`` backend's settings: the physics sub-step rate."""

    physics_hz: float = Field(100.0, ge=50.0, le=2000.0, description="physics sub-steps per simulated second")
