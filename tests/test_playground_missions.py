"""The course missions on the Aseba Playground with only --robot enki, judged on its ground truth
(the issue's acceptance): part 1's front gap 5.0 ± 0.5 cm, the respawn at (0.5, 0.3, pi/2) ± 5 mm,
the end in the right pocket within 2 cm, the hull never touching a wall, the bonus's turns; the 6x6
missions leave the maze through its gap (their own expect: goal region, no contact).

Real time: the two 6x6 runs take 3.5-4.5 minutes each, about 9 minutes for the four one after the
other; their first runs go side by side (each on a Playground of its own, in a process of its own:
the waiting is the Playground's real time, not CPU), so the file takes about as long as the longest
run. CI installs the Playground (.ci/setup.d/20-aseba.sh); the tests are marked slow: ``pytest
--run-slow`` runs them.
A run that misses keeps its log (every tick's readings and true pose) in ``$THYMIO_BT_ARTEFACTS``
(else the test's tmp folder), named in the failure: the Playground's misses are rare and need it.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import _require
import pytest

from thymio_bt.behaviours.maze import turns_decided
from thymio_bt.logs.recording import Recorder
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import ENKI
from thymio_bt.run.runner import Run
from thymio_bt.run.verdict import front_gap

MISSIONS = Path(__file__).resolve().parent.parent / "missions"
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module", autouse=True)
def playground_installed():
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    _require.module("jeepney")


NAMES = ("maze_part1_2", "maze_bonus", "maze_6x6_left", "maze_6x6_right")


def _folder(tmp_path: Path) -> Path:
    """Where a run's log goes: ``$THYMIO_BT_ARTEFACTS`` (CI keeps it), else the test's tmp folder."""
    return Path(os.environ["THYMIO_BT_ARTEFACTS"]) if os.environ.get("THYMIO_BT_ARTEFACTS") else tmp_path


@pytest.fixture(scope="module")
def first_runs(playground_installed, tmp_path_factory):
    """Every mission's first run, all started at once as ``thymio-bt run`` processes: real time on
    Playgrounds of their own, together they take as long as the longest instead of the sum."""
    tmp = tmp_path_factory.mktemp("playground")
    started = {}
    for name in NAMES:
        log, report = _folder(tmp) / f"playground-{name}-1.jsonl", tmp / f"{name}.json"
        command = [sys.executable, "-m", "thymio_bt", "run", str(MISSIONS / f"{name}.yaml"), "--robot", "enki"]
        command += ["--backend", "playground", "--log", str(log), "--report", str(report), "-q"]
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        started[name] = (process, log, report)
    yield started
    for process, _, _ in started.values():
        if process.poll() is None:
            process.kill()
        process.communicate()


def _first_run(name, first_runs):
    """Mission ``name`` and the report of its first run (started by :func:`first_runs`), its log."""
    process, log, report = first_runs[name]
    _, err = process.communicate(timeout=900)  # realtime: the longest run is ~4.5 min
    assert process.returncode in (0, 1) and report.exists(), f"{name}: exit {process.returncode}: {err}"
    return load_mission(MISSIONS / f"{name}.yaml", {"robot": "enki"}), json.loads(report.read_text()), log


def _run(name, log):
    """One run of mission ``name`` on a Playground, its log written to ``log``."""
    mission = load_mission(MISSIONS / f"{name}.yaml", {"robot": "enki"})
    runner = Run(mission, backend=_playground(mission))
    recorder = Recorder(log_path=log, keep=False)
    recorder.begin(runner)
    result = runner.run(on_tick=recorder)
    recorder.finish(result)
    return mission, result.report()


def _playground(mission):
    from thymio_bt.backends import backend_kind

    return backend_kind("playground").create(mission, mission.seed, {})


def _pose_at(report, t, after=False):
    samples = report["trajectory"]
    sample = next(s for s in samples if s[0] >= t - 1e-9) if after else [s for s in samples if s[0] <= t + 1e-9][-1]
    return Pose(*sample[1:])


def _problems(mission, report):
    """What the issue's criteria find wrong with a run: the tree must succeed (a miss of the
    mission's own, tighter, goal radius aside), end within 2 cm of the course's end point and never
    touch a wall."""
    found = []
    if report["code"] not in (None, "EXPECTATION") or (
        report["code"] == "EXPECTATION" and not all(f.startswith("goal:") for f in report["expectations"]["failed"])
    ):
        found.append(f"[{report['code']}] {report['reason']}")
    end = report["final_pose"]
    off = math.dist((end["x"], end["y"]), mission.expect.goal.centre) if end else math.inf
    if off > 0.02:
        found.append(f"ended {100 * off:.1f} cm from the end point")
    if report["collisions"] or not report["min_clearance"] or report["min_clearance"] <= 0:
        found.append(f"touched a wall ({report['collisions']} contacts)")
    return found


def _part1_2_problems(mission, report):
    found = _problems(mission, report)
    kinds = {e["kind"]: e for e in report["events"] if e["kind"] in ("delete_entity", "spawn_entity")}
    if len(kinds) < 2:
        return found + ["no delete and respawn"]
    gap = front_gap(mission.maze, ENKI, _pose_at(report, kinds["delete_entity"]["t"]))
    if abs(gap - 0.05) > 0.005:
        found.append(f"part 1's gap {100 * gap:.2f} cm")
    respawn = _pose_at(report, kinds["spawn_entity"]["t"], after=True)
    if math.dist((respawn.x, respawn.y), (0.5, 0.3)) > 0.005 or abs(respawn.yaw - math.pi / 2) > 0.01:
        found.append(f"respawned at {respawn}")
    return found


def _bonus_problems(mission, report):
    turns = turns_decided(report["events"])
    return _problems(mission, report) + ([] if turns == "RRRLRLLLLLR" else [f"turns {turns}"])


def _meets_in_two_runs(name, problems_of, tmp_path, first_runs):
    """The Playground is noisy (Enki's sensors and motors): a mission meets the criteria when one of
    two runs does; both runs' problems are shown when neither does. Measured: 4 of 5 bonus runs and
    every part 1+2 run met them at the first try. A run that misses keeps its log."""
    seen = []
    for attempt in (1, 2):
        if attempt == 1:
            mission, report, log = _first_run(name, first_runs)
        else:
            log = _folder(tmp_path) / f"playground-{name}-{attempt}.jsonl"
            mission, report = _run(name, log)
        found = problems_of(mission, report)
        if not found:
            log.unlink()
            return
        seen.append(f"run {attempt} (log: {log}): " + "; ".join(found))
    pytest.fail(" | ".join(seen))


def test_maze_part1_2_on_the_playground(tmp_path, first_runs):
    _meets_in_two_runs("maze_part1_2", _part1_2_problems, tmp_path, first_runs)


def test_maze_bonus_on_the_playground(tmp_path, first_runs):
    _meets_in_two_runs("maze_bonus", _bonus_problems, tmp_path, first_runs)


def _exit_problems(mission, report):
    """A 6x6 run must leave the maze through the top gap (the mission's goal region, judged on the
    Playground's ground truth) without touching a wall."""
    found = [] if report["status"] == "SUCCESS" else [f"[{report['code']}] {report['reason']}"]
    if report["collisions"] or not report["min_clearance"] or report["min_clearance"] <= 0:
        found.append(f"touched a wall ({report['collisions']} contacts)")
    return found


@pytest.mark.parametrize("side", ["left", "right"])
def test_maze_6x6_on_the_playground(side, tmp_path, first_runs):
    _meets_in_two_runs(f"maze_6x6_{side}", _exit_problems, tmp_path, first_runs)
