"""ROS 2 both ways, over real DDS between separate processes: ``thymio-bt serve ros2`` and
``thymio-bt run ... --backend ros2`` from the environment ``scripts/ros2-env.sh`` makes (CI builds it
in ``.venv-ros2``: .ci/setup.d/30-ros2.sh; elsewhere set THYMIO_BT_ROS2_ENV=DIR), plus what needs
no ROS: the topic map, the conversions and the errors of a machine without ROS.

Discovery stays on loopback (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) and every test has its own
ROS_DOMAIN_ID, so no test hears another's leftovers, nor a test running beside it in another pytest-xdist
worker: each worker takes its domains from a band of its own (:func:`domain_band`). About 60 s in all.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import re
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import _require
import pytest

from thymio_bt.backends.ros2.messages import proximity_range, quaternion_of, stamp_ns, stamp_parts, yaw_of
from thymio_bt.backends.ros2.topics import COURSE_TOPICS, load_topics
from thymio_bt.backends.sim.world import Simulation
from thymio_bt.behaviours.maze import turns_decided
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parent.parent
MISSIONS = ROOT / "missions"
SPEEDUP = 4.0


def domain_band(worker: str, pid: int) -> int:
    """The first ROS_DOMAIN_ID of a pytest process: xdist worker ``gwN`` (``""``: no xdist, as worker 0)
    gets 25 domains of its own within ROS 2's 1-101 (a process takes about 12), starting a few
    further by its PID, so that a serve a killed run left behind is not heard either."""
    band = int(worker.removeprefix("gw") or 0) % 4
    return 1 + 25 * band + pid % 10


_domains = itertools.count(domain_band(os.environ.get("PYTEST_XDIST_WORKER", ""), os.getpid()))


# ------------------------------------------------------------------ without ROS
def test_workers_side_by_side_never_share_a_ros_domain():
    """Two xdist workers' domains (a process takes about 12) never meet, whatever their PIDs, and
    stay in ROS 2's 1-101 (test_interrupts takes 215 on)."""
    taken = [
        {domain_band(f"gw{worker}", pid) + k for k in range(13)} for worker, pid in [(0, 9), (1, 0), (2, 9), (3, 5)]
    ]
    assert all(not (a & b) for i, a in enumerate(taken) for b in taken[i + 1 :])
    assert min(map(min, taken)) >= 1 and max(map(max, taken)) <= 101
    assert domain_band("", 1234) == domain_band("gw0", 1234)


def test_conversions():
    for yaw in (-3.0, -1.2, 0.0, 0.4, math.pi / 2, 3.1):
        assert yaw_of(*quaternion_of(yaw)) == pytest.approx(yaw, abs=1e-12)
    assert stamp_parts(stamp_ns(12, 345)) == (12, 345)
    assert proximity_range(math.inf) == math.inf
    assert proximity_range(-math.inf) == 0.0
    assert proximity_range(math.nan) == math.inf
    assert proximity_range(0.2, range_max=0.0975) == math.inf
    assert proximity_range(0.05, range_max=0.0975) == 0.05


def test_the_course_topics():
    assert COURSE_TOPICS.cmd_vel == "/cmd_vel" and COURSE_TOPICS.odom == "/odom"
    assert COURSE_TOPICS.sensors["rear_left"] == "/thymio_rear_left_proximity_sensor"
    assert len(COURSE_TOPICS.sensors) == 7 and COURSE_TOPICS.sensor_type == "LaserScan"


def test_a_topic_map_file_replaces_keys(tmp_path):
    path = tmp_path / "driver.yaml"
    path.write_text("sensor_type: Range\nsensors: {front_center: /prox/center}\nspawn: ''\n")
    topics = load_topics(path)
    assert topics.sensor_type == "Range" and topics.sensors == {"front_center": "/prox/center"}
    assert topics.spawn == "" and topics.odom == "/odom"


def test_a_bad_topic_map_is_located(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("odom: /odom\nsensor_typo: Range\nsensors: {front_middle: /x}\n")
    result = _cli(
        sys.executable,
        "run",
        str(MISSIONS / "maze_part1_2.yaml"),
        "--backend",
        "ros2",
        "--backend-opt",
        f"topics={path}",
    )
    assert result.returncode == 2
    assert f"{path}:2:1: unknown key 'sensor_typo'" in result.stderr and "did you mean 'sensor_type'?" in result.stderr
    assert f"{path}:3:10:" in result.stderr and "no sensor named 'front_middle'" in result.stderr  # at the value
    assert "Traceback" not in result.stderr


def test_without_ros_the_commands_say_how_to_get_it():
    """ROS 2 hidden from this Python (whether or not it has it): a clear error, exit 2."""
    hide = "import sys\nfor m in ('rclpy', 'gazebo_msgs'): sys.modules[m] = None\n"
    for args in (["serve", "ros2"], ["run", str(MISSIONS / "maze_part1_2.yaml"), "--backend", "ros2"]):
        code = hide + f"from thymio_bt.cli import main\nsys.argv = ['thymio-bt', *{args!r}]\nmain()\n"
        result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT)
        assert result.returncode == 2, result.stderr
        assert "ROS 2 in thymio-bt needs" in result.stderr and "scripts/ros2-env.sh" in result.stderr
        assert "Traceback" not in result.stderr


def test_the_package_declares_python_3_10_and_keeps_to_it():
    """ROS 2 Humble runs Python 3.10: no 3.11-only syntax or library use (vermin reads the code)."""
    import tomllib

    assert tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"] == ">=3.10"
    vermin = (
        _require.program("vermin")
        if not (Path(sys.executable).parent / "vermin").exists()
        else str(Path(sys.executable).parent / "vermin")
    )
    result = subprocess.run(
        [
            vermin,
            "--no-tips",
            "--violations",
            "--eval-annotations",
            "--target=3.10-",
            "--backport",
            "typing_extensions",
            str(ROOT / "thymio_bt"),
            str(ROOT / "examples"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stdout + result.stderr


# ------------------------------------------------------------------ over ROS 2
@pytest.fixture(scope="module")
def ros2_env() -> Path:
    env = Path(os.environ.get("THYMIO_BT_ROS2_ENV", ROOT / ".venv-ros2"))
    if not (env / "bin" / "thymio-bt").exists():
        _require.missing(f"a ROS 2 environment in {env} (make it: scripts/ros2-env.sh {env})")
    return env


def _environment(domain: int | None = None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "RMW_"))}
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env["NO_COLOR"] = "1"
    if domain is not None:
        env["ROS_DOMAIN_ID"] = str(domain)
    return env


def _cli(
    python: str | Path, *args: str, domain: int | None = None, timeout: float = 300
) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(python), "-m", "thymio_bt", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=_environment(domain),
        cwd=ROOT,
    )


@contextmanager
def serving(env: Path, *args: str, speedup: float = SPEEDUP) -> Iterator[int]:
    """A ``thymio-bt serve ros2`` in its own domain, ready; stopped (SIGINT) at the end."""
    domain = next(_domains)
    proc = subprocess.Popen(
        [str(env / "bin" / "thymio-bt"), "serve", "ros2", "--speedup", str(speedup), *args],
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env=_environment(domain),
    )
    try:
        deadline = time.monotonic() + 120  # only against a hang: a loaded machine's ROS 2 starts slowly
        line = ""
        while "serving" not in line:
            assert proc.poll() is None, f"serve ended: {proc.stderr.read() if proc.stderr else ''}"
            assert time.monotonic() < deadline, "serve did not start within 120 s"
            if select.select([proc.stderr], [], [], 0.5)[0]:
                line = proc.stderr.readline()  # type: ignore[union-attr]
        yield domain
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            assert proc.wait(timeout=10) == 0, "serve did not stop cleanly on SIGINT"
        finally:
            if proc.poll() is None:
                proc.kill()


def _run(env: Path, mission: str, domain: int, tmp_path: Path, *args: str) -> tuple[int, dict]:
    report = tmp_path / f"{mission}.json"
    result = _cli(
        env / "bin" / "python",
        "run",
        str(MISSIONS / f"{mission}.yaml"),
        "--backend",
        "ros2",
        "--report",
        str(report),
        *args,
        domain=domain,
    )
    assert "Traceback" not in result.stderr, result.stderr
    return result.returncode, json.loads(report.read_text())


def _direct(mission: str) -> dict:
    return Run(load_mission(MISSIONS / f"{mission}.yaml")).run().report()


def _turns(report: dict) -> str:
    return turns_decided(report["events"])


def _pose_at(report: dict, t: float) -> Pose:
    """The trajectory's pose at the last tick before ``t``."""
    return Pose(*[s for s in report["trajectory"] if s[0] <= t][-1][1:])


def _pose_after(report: dict, t: float) -> Pose:
    return Pose(*next(s for s in report["trajectory"] if s[0] >= t - 1e-9)[1:])


def test_maze_part1_2_through_ros2_matches_the_direct_run(ros2_env, tmp_path):
    with serving(ros2_env) as domain:
        code, report = _run(ros2_env, "maze_part1_2", domain, tmp_path)
    assert code == 0 and report["status"] == "SUCCESS", report["reason"]
    events = {e["kind"]: e for e in report["events"] if e["kind"] in ("delete_entity", "spawn_entity")}
    mission = load_mission(MISSIONS / "maze_part1_2.yaml")
    stop = _pose_at(report, events["delete_entity"]["t"])
    gap = Simulation(mission.maze, spawn=stop).proximity()["front_center"]  # the true gap, from geometry
    assert gap == pytest.approx(0.050, abs=0.002)
    respawn = _pose_after(report, events["spawn_entity"]["t"])
    assert (respawn.x, respawn.y, respawn.yaw) == pytest.approx((0.5, 0.3, math.pi / 2), abs=1e-3)
    direct = _direct("maze_part1_2")["final_pose"]
    assert math.hypot(report["final_pose"]["x"] - direct["x"], report["final_pose"]["y"] - direct["y"]) < 0.01
    assert report["collisions"] == 0


def test_maze_bonus_through_ros2_turns_as_the_course_says(ros2_env, tmp_path):
    with serving(ros2_env) as domain:  # the robot starts at part 1's spawn: the run respawns it
        code, report = _run(ros2_env, "maze_bonus", domain, tmp_path)
    assert code == 0 and report["status"] == "SUCCESS", report["reason"]
    assert _turns(report) == "RRRLRLLLLLR"
    direct = _direct("maze_bonus")["final_pose"]
    assert math.hypot(report["final_pose"]["x"] - direct["x"], report["final_pose"]["y"] - direct["y"]) < 0.01


def test_the_course_students_node_runs_against_serve(ros2_env):
    with serving(ros2_env, speedup=1.0) as domain:  # real time, as the course's Gazebo: its timer is wall-clock
        result = subprocess.run(
            [str(ros2_env / "bin" / "python"), str(ROOT / "examples" / "ros2_course_part1.py")],
            capture_output=True,
            text=True,
            timeout=120,
            env=_environment(domain),
        )
    assert result.returncode == 0, result.stderr
    stopped = next(line for line in result.stdout.splitlines() if line.startswith("STOPPED"))
    fields = dict(item.split("=") for item in stopped.split()[1:])
    maze = load_mission(MISSIONS / "maze_part1_2.yaml").maze
    gap = Simulation(maze, spawn=Pose(float(fields["x"]), float(fields["y"]), 0.0)).proximity()["front_center"]
    assert gap == pytest.approx(0.05, abs=0.01)
    assert "SPAWNED True" in result.stdout


def test_nothing_to_drive_fails_quickly_with_a_reason(ros2_env, tmp_path):
    """Quickly: after its 5 s wait for a first message, before any tick (the report's own record),
    not at the mission's time limit."""
    code, report = _run(ros2_env, "maze_part1_2", next(_domains), tmp_path)
    assert code == 1 and report["status"] == "FAILURE" and report["code"] == "ROBOT_LOST"
    assert report["ticks"] == 0, report
    reason = report["reason"]  # what was waited for, how long, and how to start a server
    assert reason.startswith("nothing answered: no message on /clock or /odom and no /spawn_entity")
    waited = re.search(r" within (\d+\.\d) s \(ROS_DOMAIN_ID=", reason)  # the wall time it waited: 5.0 s or a bit more
    assert waited and float(waited[1]) >= 5.0 and "'thymio-bt serve ros2 --maze " in reason


def _probe_speed(env: Path, domain: int) -> float:
    """The robot's speed now, from /odom, read by a separate ROS node."""
    script = (
        "import rclpy, sys\nfrom nav_msgs.msg import Odometry\nrclpy.init()\nn = rclpy.create_node('probe')\n"
        "got = []\nn.create_subscription(Odometry, '/odom', lambda m: got.append(m), 10)\n"
        "while len(got) < 5: rclpy.spin_once(n, timeout_sec=1.0)\n"
        "t = got[-1].twist.twist\nprint(abs(t.linear.x) + abs(t.angular.z))\n"
    )
    return float(_ros_python(env, domain, script))


def _ros_python(env: Path, domain: int, script: str) -> str:
    """What ``script`` prints, run by the ROS 2 venv's Python on ``domain`` (a separate node)."""
    result = subprocess.run(
        [str(env / "bin" / "python"), "-c", script],
        capture_output=True,
        text=True,
        timeout=180,  # only against a hang: a new node's discovery and a held world's 10 s, under load
        env=_environment(domain),
    )
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_a_missing_service_fails_the_run_and_stops_the_motors(ros2_env, tmp_path):
    topics = tmp_path / "no_delete.yaml"
    topics.write_text("delete: /no_such_delete\n")
    with serving(ros2_env) as domain:
        code, report = _run(
            ros2_env,
            "maze_part1_2",
            domain,
            tmp_path,
            "--backend-opt",
            f"topics={topics}",
            "--backend-opt",
            "timeout=0.5",
        )  # before DeleteEntity's own 5 s (sim) limit
        assert code == 1 and report["status"] == "FAILURE" and report["code"] == "ENTITY_ERROR"
        assert "/no_such_delete is not available" in report["reason"]
        assert _probe_speed(ros2_env, domain) == 0.0


def test_a_silent_sensor_topic_ends_the_run_as_robot_lost(ros2_env, tmp_path):
    topics = tmp_path / "silent.yaml"
    topics.write_text(
        "sensors:\n  front_left: /nobody_publishes_this\n  front_center: /thymio_front_center_proximity_sensor\n"
    )
    with serving(ros2_env) as domain:
        code, report = _run(
            ros2_env,
            "maze_part1_2",
            domain,
            tmp_path,
            "--backend-opt",
            f"topics={topics}",
            "--backend-opt",
            "timeout=2",
        )
        assert code == 1 and report["code"] == "ROBOT_LOST"
        assert "/nobody_publishes_this" in report["reason"]


def test_a_run_stopped_while_driving_stops_the_robot(ros2_env, tmp_path):
    report = tmp_path / "report.json"
    with serving(ros2_env) as domain:
        run = subprocess.Popen(
            [
                str(ros2_env / "bin" / "thymio-bt"),
                "run",
                str(MISSIONS / "maze_part1_2.yaml"),
                "--backend",
                "ros2",
                "--report",
                str(report),
                "-q",
            ],
            env=_environment(domain),
        )
        try:
            deadline = time.monotonic() + 120  # only against a hang: each probe is a new ROS 2 process
            while _probe_speed(ros2_env, domain) == 0.0:
                assert time.monotonic() < deadline, "the robot never moved"
            run.send_signal(signal.SIGTERM)
            assert run.wait(timeout=60) == 143
        finally:
            if run.poll() is None:
                run.kill()
        assert _probe_speed(ros2_env, domain) == 0.0
    assert json.loads(report.read_text())["code"] == "INTERRUPTED"


def test_a_driver_publishing_range_in_wall_time(ros2_env, tmp_path):
    """A real robot's layout: no /clock, Range messages on its own names, no spawn service."""
    topics = tmp_path / "driver.yaml"
    topics.write_text(
        "sensor_type: Range\nspawn: ''\ndelete: ''\nsensors:\n"
        + "".join(
            f"  {name}: /proximity/{topic}\n"
            for name, topic in (
                ("front_left", "left"),
                ("front_center_left", "center_left"),
                ("front_center", "center"),
                ("front_center_right", "center_right"),
                ("front_right", "right"),
                ("rear_left", "rear_left"),
                ("rear_right", "rear_right"),
            )
        )
    )
    mission = tmp_path / "approach.yaml"
    mission.write_text(
        f"name: approach\nmaze: {ROOT / 'mazes' / 'two_parts_maze.yaml'}\nstart: part1\n"
        "time_limit: 20\ntree:\n  MoveUntilWall: {distance: 5cm}\n"
    )
    domain = next(_domains)
    driver = subprocess.Popen(
        [str(ros2_env / "bin" / "python"), str(ROOT / "tests" / "data" / "ros2_range_driver.py")],
        env=_environment(domain),
    )
    try:
        report = tmp_path / "report.json"
        result = _cli(
            ros2_env / "bin" / "python",
            "run",
            str(mission),
            "--backend",
            "ros2",
            "--backend-opt",
            f"topics={topics}",
            "--report",
            str(report),
            domain=domain,
        )
    finally:
        driver.terminate()
        driver.wait(timeout=10)
    assert result.returncode == 0, result.stderr
    data = json.loads(report.read_text())
    gap = 0.595 - data["final_pose"]["x"] - 0.0557
    assert gap == pytest.approx(0.05, abs=0.01)  # wall time: the readings are up to 0.1 s old
