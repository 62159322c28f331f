"""'Nothing in range' is one value per layer: math.inf in the live robot interface (readings are
compared with thresholds), None in everything a run produces (report, RunResult, events, logs)."""

import json
import math
from pathlib import Path

from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.logs import read_log
from thymio_bt.testing import run_tree, world

ROOT = Path(__file__).resolve().parents[1]


def no_reading_values(obj):
    """Every value found under a 'proximity'/'prox'/'final_proximity' key, recursively."""
    if isinstance(obj, dict):
        for key, value in obj.items():
            if key in ("proximity", "prox", "final_proximity") and isinstance(value, dict):
                yield from value.values()
            else:
                yield from no_reading_values(value)
    elif isinstance(obj, list):
        for item in obj:
            yield from no_reading_values(item)


def test_the_robot_interface_says_inf_and_never_none():
    from thymio_bt.backends.sim import Simulation
    from thymio_bt.robot.interface import Pose

    sim = Simulation(world("arena"), spawn=Pose(0.3, 0.3, 0.0))
    scan = sim.proximity()
    assert scan is not None and any(math.isinf(v) for v in scan.values())
    assert all(isinstance(v, float) for v in scan.values())


def test_results_say_none_and_never_inf(tmp_path):
    result = run_tree({"MoveDistance": {"distance": "10cm"}}, world("arena"), seconds=10)
    values = list(no_reading_values(result.report())) + list(result.final_proximity.values())
    assert None in values and not any(isinstance(v, float) and math.isinf(v) for v in values)
    log = tmp_path / "r.jsonl"
    assert CliRunner().invoke(main, ["run", f"{ROOT}/missions/square.yaml", "-q", "--log", str(log)]).exit_code == 0
    recording = read_log(log)
    from_log = list(no_reading_values(recording.samples)) + list(no_reading_values(recording.events))
    assert None in from_log and not any(isinstance(v, float) and math.isinf(v) for v in from_log)
    assert "Infinity" not in log.read_text() and json.loads(log.read_text().splitlines()[-1])
