"""The aseba backend's serial path, the one a Thymio on USB takes: a pseudo-terminal bridged to the
Aseba Playground's TCP port by socat (``socat PTY,link=...,raw,echo=0 TCP:127.0.0.1:PORT``), so the
serial code (open, framing, a lost robot, close) runs as with a real robot, in the CLI as a user
runs it. The operator who places the robot when it is respawned is played by the test: it reads the
prompt, teleports the Playground's robot there (D-Bus) and presses Enter.

Real time: about 25 s for the three (40 s when the course's start needs its second run). CI installs the
Playground and socat (.ci/setup.d/20-aseba.sh, 40-socat.sh).
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import _require
import pytest
from _waiting import ticks_logged, wait_until

from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import ENKI
from thymio_bt.run.verdict import front_gap

ROOT = Path(__file__).resolve().parent.parent
PROMPT = re.compile(r"place the Thymio .*? at x=(-?[\d.]+) m, y=(-?[\d.]+) m, facing (-?\d+) deg")


@pytest.fixture(autouse=True)
def _installed():
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.program("socat")
    _require.module("thymiodirect")
    _require.module("jeepney")
    _require.module("serial")


class Bridge:
    """A Playground on a mission's maze, the robot at its start, reached through a socat pty."""

    def __init__(self, mission_file: Path, folder: Path) -> None:
        from thymio_bt.backends.playground.enki import EnkiRobot
        from thymio_bt.backends.playground.process import Playground
        from thymio_bt.backends.playground.world import playground_world

        mission = load_mission(mission_file, {"robot": "enki"})
        self.world = playground_world(mission.maze, Pose(*ENKI.axle_of(mission.start)), port=0)
        self.playground = Playground.start(self.world.text, preload=_require.enki_fix())
        try:
            self.enki = EnkiRobot.find(self.playground.bus)
        except BaseException:
            self.playground.stop()
            raise
        self.tty = folder / "thymio-tty"
        self.socat = subprocess.Popen(
            ["socat", f"PTY,link={self.tty},raw,echo=0", f"TCP:127.0.0.1:{self.playground.port}"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        try:
            wait_until(lambda: self.tty.exists() or self.socat.poll() is not None, "socat's pty")
            assert self.tty.exists(), f"socat made no pty: {self.socat.stderr.read() if self.socat.stderr else ''}"
        except BaseException:
            self.close()
            raise

    def place(self, pose: Pose) -> None:
        """What an operator does at a prompt: put the robot at ``pose`` (base_link)."""
        x, y, yaw = ENKI.axle_of(pose)
        self.enki.place(*self.world.to_enki(x, y), yaw)

    def true_pose(self) -> Pose:
        x_cm, y_cm, angle = self.enki.pose()
        return ENKI.base_of(*self.world.from_enki(x_cm, y_cm), angle)

    def close(self) -> None:
        if self.socat.poll() is None:
            self.socat.kill()
        self.socat.wait(5)
        self.enki.close()
        self.playground.stop()


@pytest.fixture
def bridge(request, tmp_path):
    made: list[Bridge] = []

    def make(mission_file: Path) -> Bridge:
        made.append(Bridge(mission_file, tmp_path))
        return made[-1]

    yield make
    for b in made:
        b.close()


def _run(bridge: Bridge, mission: Path, folder: Path, stdin=subprocess.DEVNULL, *more: str) -> subprocess.Popen:
    command = [
        sys.executable,
        "-m",
        "thymio_bt",
        "run",
        str(mission),
        "--backend",
        "aseba",
        "--backend-opt",
        f"device={bridge.tty}",
        "--robot",
        "enki",
        "--report",
        str(folder / "report.json"),
        "--log",
        str(folder / "run.jsonl"),
        *more,
    ]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(command, stdin=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT, env=env)


class Operator(threading.Thread):
    """Reads the run's output; at each placement prompt, notes where the robot truly stands (a
    respawn's prompt comes where the last part left it), places it and presses Enter."""

    def __init__(self, process: subprocess.Popen, bridge: Bridge) -> None:
        super().__init__(daemon=True)
        self.process, self.bridge = process, bridge
        self.output = b""
        self.placed: list[Pose] = []
        self.found: list[Pose] = []

    def run(self) -> None:
        assert self.process.stdout is not None and self.process.stdin is not None
        seen = 0
        while chunk := self.process.stdout.read1(4096):
            self.output += chunk
            for match in list(PROMPT.finditer(self.output.decode(errors="replace")))[seen:]:
                seen += 1
                pose = Pose(float(match[1]), float(match[2]), math.radians(float(match[3])))
                self.found.append(self.bridge.true_pose())
                self.bridge.place(pose)
                self.placed.append(pose)
                time.sleep(0.3)  # realtime: the robot's readings from its new place (as an operator waits)
                self.process.stdin.write(b"\n")
                self.process.stdin.flush()


def _log_ends(path: Path) -> bool:
    lines = path.read_text().splitlines()
    return bool(lines) and json.loads(lines[-1])["kind"] == "end"


COURSE_START = """name: course start
maze: {maze}
start: part1
time_limit: 60
tree:
  sequence:
    name: course
    children:
      - MoveUntilWall: {{name: part 1, speed: 10cm/s, distance: 5cm}}
      - DeleteEntity: {{entity: thymio}}
      - SpawnEntity: {{entity: thymio, pose: part2}}
      - MoveUntilWall: {{name: part 2, speed: 10cm/s, distance: 5cm}}
"""


def _course_start_gaps(bridge, folder: Path) -> tuple[tuple[float, float], list]:
    """One run of :data:`COURSE_START` through a fresh bridge: the serial path's checks, then the
    true gaps after part 1 and after part 2's first leg, and the behaviours' ends (for a message)."""
    folder.mkdir()
    mission = folder / "course_start.yaml"
    mission.write_text(COURSE_START.format(maze=ROOT / "mazes" / "two_parts_maze.yaml"))
    maze = load_mission(mission).maze
    b = bridge(mission)
    process = _run(b, mission, folder, subprocess.PIPE, "--backend-opt", "placed=true")
    operator = Operator(process, b)
    operator.start()
    process.wait(timeout=120)
    operator.join(5)
    stderr = process.stderr.read().decode()
    assert "Traceback" not in stderr, stderr
    report = json.loads((folder / "report.json").read_text())
    assert report["status"] == "SUCCESS" and process.returncode == 0, report["reason"]
    assert operator.placed == [Pose(0.5, 0.3, math.pi / 2)]  # the respawn, asked of the operator
    assert _log_ends(folder / "run.jsonl")
    ends = [(e["path"], e.get("range"), e.get("pose")) for e in report["events"] if e["kind"] == "behaviour_end"]
    return (front_gap(maze, ENKI, operator.found[0]), front_gap(maze, ENKI, b.true_pose())), ends


def test_the_course_missions_start_over_a_serial_port(bridge, tmp_path):
    """The course mission's part 1, the respawn (placed by the operator) and part 2's first leg,
    through the pty. A real robot has no ground truth (its odometry judges the report), so the test
    judges on the Playground's: each stop 5 cm from its wall, in one of two runs. Under CPU load
    (load average 8) 2 runs in 9 stopped part 2's leg 13.5 cm short on a 0 m reading of the front
    sensor, Enki's glint (docs/real_robot.md); the serial path's own checks hold in every run. (The
    whole of maze_part1_2 this way, about 55 s, ended 7-9 cm short of the dead end in 2 of 3 tries
    here and once turned right; the Playground mission tests judge the whole course.)"""
    seen = []
    for attempt in (1, 2):
        gaps, ends = _course_start_gaps(bridge, tmp_path / f"run{attempt}")
        if gaps == pytest.approx((0.05, 0.05), abs=0.006):
            return
        seen.append(f"run {attempt}: gaps {gaps}, ends {ends}")
    pytest.fail(" | ".join(seen))


def test_a_robot_lost_mid_run_ends_it_failure_with_everything_written(bridge, tmp_path):
    """The bridge killed mid-run (a cable pulled): FAILURE ROBOT_LOST saying the robot was lost, the
    report and log complete, exit code 1, no traceback, nothing left running."""
    (tmp_path / "corridor.txt").write_text("o---o---o---o---o---o\n| S                 |\no---o---o---o---o---o\n")
    mission = tmp_path / "m.yaml"
    mission.write_text("name: wait\nmaze: corridor.txt\nstart: start\ntime_limit: 60\ntree:\n  Wait: {seconds: 30}\n")
    b = bridge(mission)
    process = _run(b, mission, tmp_path, subprocess.DEVNULL, "--backend-opt", "placed=true")
    wait_until(lambda: ticks_logged(tmp_path / "run.jsonl") >= 3 or process.poll() is not None, "3 ticks logged")
    assert process.poll() is None, process.stderr.read().decode()
    b.socat.kill()
    out, err = process.communicate(timeout=60)  # only against a hang
    stderr = err.decode()
    assert process.returncode == 1, stderr
    assert "Traceback" not in stderr and "Exception" not in stderr, stderr
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["status"] == "FAILURE" and report["code"] == "ROBOT_LOST", report
    assert report["sim_time"] < 30  # ended by the loss, not by its Wait's end
    assert re.search(r"stopped answering|connection .* failed|lost", report["reason"]), report["reason"]
    assert _log_ends(tmp_path / "run.jsonl")
    assert not b.tty.exists()  # socat is gone, and so is its pty


def test_with_nobody_to_place_the_robot_the_run_fails_at_once_saying_how(bridge, tmp_path):
    """Standard input closed and no placed=true: no hang, a message naming the option."""
    mission = ROOT / "missions" / "square.yaml"
    b = bridge(mission)
    process = _run(b, mission, tmp_path, subprocess.DEVNULL)
    out, err = process.communicate(timeout=30)
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["status"] == "FAILURE" and "placed=true" in report["reason"], report
    assert process.returncode == 1 and "Traceback" not in err.decode()
