"""``serve ros2`` and ``--backend ros2`` give the direct run's verdict or none: the server says which
world it serves (a mission on another maze is refused), a run with no server says that nothing
answered, and the pair holds under CPU load because the server is stepped in lock with the run's
ticks (thymio_bt/backends/ros2/lockstep.py). Over real DDS, from the ROS 2 environment, as
tests/test_ros2.py (whose helpers these are).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import _require
import pytest
from test_ros2 import MISSIONS, ROOT, _direct, _environment, _pose_at, _ros_python, _run, serving

from thymio_bt.backends.sim.world import Simulation
from thymio_bt.mission import load_mission


@pytest.fixture(scope="module")
def ros2_env() -> Path:
    env = Path(os.environ.get("THYMIO_BT_ROS2_ENV", ROOT / ".venv-ros2"))
    if not (env / "bin" / "thymio-bt").exists():
        _require.missing(f"a ROS 2 environment in {env} (make it: scripts/ros2-env.sh {env})")
    return env


def _echo_world(env: Path, domain: int) -> dict | None:
    """The server's /thymio_bt/world message, read by a separate node subscribing late (latched)."""
    script = (
        "import rclpy\nfrom std_msgs.msg import String\nfrom rclpy.qos import QoSProfile, QoSDurabilityPolicy\n"
        "rclpy.init()\nn = rclpy.create_node('probe')\ngot = []\n"
        "qos = QoSProfile(depth=1, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)\n"
        "n.create_subscription(String, '/thymio_bt/world', lambda m: got.append(m.data), qos)\n"
        "import time\nend = time.monotonic() + 60\n"  # only against a hang: DDS discovery under load
        "while not got and time.monotonic() < end: rclpy.spin_once(n, timeout_sec=1.0)\n"
        "print(got[0] if got else 'null')\n"
    )
    return json.loads(_ros_python(env, domain, script))


def test_a_mission_on_another_maze_is_refused(ros2_env, tmp_path):
    """Before: the run drove maze_6x6's mission into two_parts_maze's walls (a collision at 2.4 s)."""
    report = tmp_path / "report.json"
    with serving(ros2_env, "--maze", "two_parts_maze") as domain:
        world = _echo_world(ros2_env, domain)
        result = subprocess.run(
            [str(ros2_env / "bin" / "python"), "-m", "thymio_bt", "run", str(MISSIONS / "maze_6x6_right.yaml")]
            + ["--backend", "ros2", "--report", str(report)],
            capture_output=True,
            text=True,
            timeout=120,
            env=_environment(domain),
            cwd=ROOT,
        )
    assert world is not None, "nothing on /thymio_bt/world within 60 s"
    assert world["maze"] == "two_parts_maze" and world["start"] == [0.1, 0.1, 0.0] and world["lockstep"]
    assert result.returncode == 2, result.stderr
    assert "the server serves maze 'two_parts_maze' (robot at x=0.1 y=0.1 yaw=0), not the mission's 'maze_6x6'" in (
        result.stderr
    )
    assert "'thymio-bt serve ros2 --maze maze_6x6'" in result.stderr  # a shipped maze by its name
    assert "Traceback" not in result.stderr and not report.exists()


def _part1_gap(report: dict) -> float:
    """The true front gap where part 1 stopped (at the DeleteEntity), from the maze's geometry."""
    deleted = next(e["t"] for e in report["events"] if e["kind"] == "delete_entity")
    maze = load_mission(MISSIONS / "maze_part1_2.yaml").maze
    return Simulation(maze, spawn=_pose_at(report, deleted)).proximity()["front_center"]


@contextmanager
def cpu_hog(processes: int = 4, seconds: float = 300) -> Iterator[None]:
    """``processes`` busy loops (each ends by itself after ``seconds``), killed on leaving."""
    code = f"import time\nend = time.monotonic() + {seconds}\nwhile time.monotonic() < end: pass\n"
    hogs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(processes)]
    try:
        yield
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait(timeout=10)


@pytest.mark.slow
def test_the_course_mission_holds_beside_a_cpu_hog(ros2_env, tmp_path):
    """Four busy loops on the two cores: before lockstep the run's ticks woke up to 6.5 s of simulated
    time late and the pair ended FAILURE (collision, or the goal missed by 11 mm); now it is the
    direct run's."""
    direct = _direct("maze_part1_2")
    with cpu_hog(), serving(ros2_env) as domain:
        code, report = _run(ros2_env, "maze_part1_2", domain, tmp_path)
    assert code == 0 and report["status"] == "SUCCESS", report["reason"]
    assert _part1_gap(report) == pytest.approx(0.050, abs=0.002)  # as the direct run (0.0501)
    assert _part1_gap(report) == pytest.approx(_part1_gap(direct), abs=1e-5)
    final, expected = report["final_pose"], direct["final_pose"]
    assert math.hypot(final["x"] - expected["x"], final["y"] - expected["y"]) < 1e-4
    assert report["collisions"] == 0
