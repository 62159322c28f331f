"""The run's hot path does no work that nobody reads (benchmarks/README.md, "Tick loop ..."): each
test counts a piece of work a run would do for nothing and fails if it comes back."""

from __future__ import annotations

from collections import Counter

import pytest

from thymio_bt.backends.sim.fastpath import RayReader
from thymio_bt.testing import run_tree, world


@pytest.fixture
def casts(monkeypatch: pytest.MonkeyPatch) -> Counter[str]:
    """How often each sensor's ray is cast in the simulation (noise-free readings are cast when read)."""
    counted: Counter[str] = Counter()
    read = RayReader.read

    def counting(self: RayReader, name: str, *at: float) -> float:
        counted[name] += 1
        return read(self, name, *at)

    monkeypatch.setattr(RayReader, "read", counting)
    return counted


def test_move_until_wall_casts_its_side_rays_only_to_centre(casts: Counter[str]) -> None:
    result = run_tree({"MoveUntilWall": {"distance": "5cm"}}, world("corridor"), seconds=20)
    assert result.status == "SUCCESS" and casts["front_center"] > 20
    # once each, for the behaviour_end event's readings: never to steer
    assert casts["front_left"] == casts["front_right"] == 1
    casts.clear()
    run_tree({"MoveUntilWall": {"distance": "5cm", "centre": True}}, world("corridor"), seconds=20)
    assert casts["front_left"] > 20 and casts["front_right"] > 20
