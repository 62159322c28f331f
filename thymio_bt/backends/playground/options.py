"""The ``playground`` backend's settings (``--backend-opt KEY=VALUE`` or a mission's ``backend:`` block)."""

from __future__ import annotations

from pydantic import Field

from thymio_bt.backends import BackendOptions, latency_option


class PlaygroundOptions(BackendOptions):
    """The ``playground`` backend's settings: start-up wait, latency, the speed calibration and Enki's sensor fix."""

    timeout: float = Field(10.0, gt=0, le=60, description="how long to wait for the Playground to start (s)")
    latency: float = latency_option(
        0.2,
        ", for the behaviours (measured: readings 40-120 ms behind the true pose, a new motor target acting "
        "~100 ms later)",
    )
    speed_scale: float | None = Field(
        None,
        gt=0.5,
        le=2,
        description="the Playground's Thymio's speed per motor "
        "unit over the robot model's; default: 0.985 (measured against its ground "
        "truth) for a built-in model, 1 for a profile measured by thymio-bt calibrate",
    )
    enki_fix: bool = Field(
        True,
        description="correct Enki 1.6.99's stale sensor rays (enki-community/enki#68) in the Playground "
        "(needs g++ and libenki-dev; false runs Enki as installed)",
    )
