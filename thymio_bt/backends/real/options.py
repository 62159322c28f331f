"""The settings of a Thymio's backends: ``tdm`` (the Thymio Device Manager) and ``aseba`` (its own protocol).

Reading them imports neither tdmclient nor thymiodirect: ``thymio-bt backends`` lists them without
the extras."""

from __future__ import annotations

from pydantic import Field

from thymio_bt.backends import BackendOptions, latency_option, placed_option


class TdmOptions(BackendOptions):
    """The ``tdm`` backend's settings: where the Thymio Device Manager is."""

    host: str | None = Field(None, description="Thymio Device Manager host (default: found on this machine)")
    port: int | None = Field(None, ge=1, le=65535, description="Thymio Device Manager TCP port")
    password: str | None = Field(None, description="Thymio Device Manager password, if it has one")
    placed: bool = placed_option()


class AsebaOptions(BackendOptions):
    """The ``aseba`` backend's settings: the device, how long to wait, and the robot's latency."""

    device: str = Field(
        "", description="tcp:HOST:PORT, a serial port such as /dev/ttyACM0, or empty for the only Thymio plugged in"
    )
    timeout: float = Field(5.0, gt=0, le=60, description="how long to wait for the robot to answer (s)")
    latency: float = latency_option(
        0.2, " (behaviours stop early by it); 0.2 was measured on the Playground, measure your robot's"
    )
    placed: bool = placed_option()
