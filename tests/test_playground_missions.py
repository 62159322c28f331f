"""The course missions on the Aseba Playground with only --robot enki, judged on its ground truth
(the issue's acceptance): part 1's front gap 5.0 ± 0.5 cm, the respawn at (0.5, 0.3, pi/2) ± 5 mm,
the end in the right pocket within 2 cm, the hull never touching a wall, the bonus's turns.

Real time: about 3 minutes together (CI installs the Playground: .ci/setup.d/20-aseba.sh).
"""

import math
from pathlib import Path

import _require
import pytest

from thymio_bt.expect import front_gap
from thymio_bt.mission import load_mission
from thymio_bt.robot import Pose
from thymio_bt.robot_model import ENKI
from thymio_bt.runner import Run

MISSIONS = Path(__file__).resolve().parent.parent / "missions"


@pytest.fixture(scope="module", autouse=True)
def playground_installed():
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    _require.module("jeepney")


def _run(name):
    mission = load_mission(MISSIONS / f"{name}.yaml", {"robot": "enki"})
    result = Run(mission, backend=_playground(mission)).run()
    return mission, result.report()


def _playground(mission):
    from thymio_bt.backends import backend_kind

    return backend_kind("playground").create(mission, mission.seed, {})


def _pose_at(report, t, after=False):
    samples = report["trajectory"]
    sample = next(s for s in samples if s[0] >= t - 1e-9) if after else [s for s in samples if s[0] <= t + 1e-9][-1]
    return Pose(*sample[1:])


def _judge(mission, report):
    """The tree succeeded (a miss of the mission's own, tighter, goal radius aside), the robot ended
    within 2 cm of the course's end point, and never touched a wall."""
    assert report["code"] in (None, "EXPECTATION"), report["reason"]
    if report["code"] == "EXPECTATION":
        assert all(f.startswith("goal:") for f in report["expectations"]["failed"]), report["reason"]
    end = report["final_pose"]
    assert math.dist((end["x"], end["y"]), mission.expect.goal.centre) <= 0.02
    assert report["collisions"] == 0 and report["min_clearance"] > 0


def test_maze_part1_2_on_the_playground():
    mission, report = _run("maze_part1_2")
    _judge(mission, report)
    kinds = {e["kind"]: e for e in report["events"] if e["kind"] in ("delete_entity", "spawn_entity")}
    stop = _pose_at(report, kinds["delete_entity"]["t"])
    assert front_gap(mission.maze, ENKI, stop) == pytest.approx(0.05, abs=0.005)
    respawn = _pose_at(report, kinds["spawn_entity"]["t"], after=True)
    assert math.dist((respawn.x, respawn.y), (0.5, 0.3)) <= 0.005
    assert respawn.yaw == pytest.approx(math.pi / 2, abs=0.01)


def test_maze_bonus_on_the_playground():
    mission, report = _run("maze_bonus")
    _judge(mission, report)
    turns = "".join(e["decision"][0].upper() for e in report["events"] if e["kind"] == "behaviour_end"
                    and e["name"] == "ChooseTurn" and e.get("decision") in ("left", "right"))
    assert turns == "RRRLRLLLLLR"
