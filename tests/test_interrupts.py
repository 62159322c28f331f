"""Ctrl-C and SIGTERM on `run` and `sweep`: the robot stopped, the report and the log complete with
status INTERRUPTED, sweep workers gone with the results so far, exit 130/143; one
signal is enough even when a plugin is stuck inside a tick (the grace period of run/interrupts.py)."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from _waiting import ticks_logged, wait_until

ROOT = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "thymio_bt"]


def start(args, tmp_path, grace=None):
    """The command, in ``tmp_path``; ``grace``: its THYMIO_BT_INTERRUPT_GRACE (default: none set)."""
    env = {k: v for k, v in os.environ.items() if k != "THYMIO_BT_INTERRUPT_GRACE"}
    if grace is not None:
        env["THYMIO_BT_INTERRUPT_GRACE"] = grace
    return subprocess.Popen(
        [*CLI, *args], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )


def wait_for(path: Path, timeout: float = 60.0) -> None:
    """Until ``path`` has content: the process is past its start-up and inside its loop."""
    wait_until(lambda: path.exists() and path.stat().st_size > 0, f"{path} to appear", timeout)


def threads(pid: int) -> int:
    """How many threads process ``pid`` has (0 once it ended)."""
    try:
        return len(os.listdir(f"/proc/{pid}/task"))
    except OSError:
        return 0


def heard(send, pid: int) -> None:
    """``send()`` the first signal to ``pid`` and return once its handler ran: the handler starts the
    grace period's watchdog, a thread of its own (or the process ended)."""
    before = threads(pid)
    send()
    wait_until(lambda: threads(pid) != before, "the first signal's watchdog thread")


def stood_down(pid: int, count: int) -> None:
    """Until ``pid`` is back to ``count`` threads: a watchdog told in time ends at once, one not told
    would first break in (the test then fails there)."""
    wait_until(lambda: threads(pid) <= count, f"{pid} back to {count} threads")


def children(pid: int) -> list[int]:
    found = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()
    return [int(p) for p in found]


def cpu_seconds(pid: int) -> float:
    """The CPU time (user and system) process ``pid`` has used."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(") ", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().split(") ")[1].startswith("Z"))


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_run_ends_interrupted_with_report_and_log_end(tmp_path, sig, code):
    mission = str(ROOT / "missions/maze_6x6_left.yaml")
    proc = start(["run", mission, "--realtime", "4", "--report", "r.json", "--log", "r.jsonl"], tmp_path)
    wait_until(lambda: ticks_logged(tmp_path / "r.jsonl") >= 5, "5 ticks logged")
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == code, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["status"] == "FAILURE" and report["code"] == "INTERRUPTED"  # the contract's three statuses
    assert signal.Signals(sig).name in report["reason"] and 0 < report["sim_time"] < 30
    last = json.loads((tmp_path / "r.jsonl").read_text().splitlines()[-1])
    assert last["kind"] == "end" and (last["status"], last["code"]) == ("FAILURE", "INTERRUPTED")
    assert last["sim_time"] == report["sim_time"]
    assert "Traceback" not in err and "INTERRUPTED" in out


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_sweep_stops_keeps_the_results_so_far_and_leaves_no_worker(tmp_path, sig, code):
    mission = str(ROOT / "missions/maze_6x6_left.yaml")
    proc = start(["sweep", mission, "--runs", "2000", "--workers", "2", "--out", "s.json"], tmp_path)
    wait_until(lambda: len(children(proc.pid)) >= 2, "two workers")
    workers = children(proc.pid)
    # a run takes ~0.1 s of CPU, a chunk 4 runs: a worker that used 1.5 s has sent results, and one
    # that used 3 s has given the parent the time of several chunks to take them in, however loaded
    # the machine (a fixed wait saw none at a load of 11 on 2 cores)
    wait_until(lambda: sum(cpu_seconds(pid) for pid in workers) >= 3.0, "the workers at work", timeout=120)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)  # only against a hang: all 2000 runs take ~65 s of 2 workers
    assert proc.returncode == code, err
    assert not [pid for pid in workers if alive(pid)]
    data = json.loads((tmp_path / "s.json").read_text())
    assert data["interrupted"] == signal.Signals(sig).name and data["runs_requested"] == 2000
    assert 0 < data["runs"] == len(data["results"]) < 2000 and data["successes"] == data["runs"]
    assert f"interrupted by {signal.Signals(sig).name}" in err and "Traceback" not in err


def test_a_failing_sweep_run_prints_the_command_that_reproduces_it(tmp_path):
    mission = str(ROOT / "missions/maze_part1_2.yaml")
    done = subprocess.run(
        [
            *CLI,
            "sweep",
            mission,
            "--runs",
            "2",
            "--seed-start",
            "5",
            "--workers",
            "1",
            "--set",
            "time_limit=12",
            "--out",
            "s.json",
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    failed = json.loads((tmp_path / "s.json").read_text())["results"][0]
    assert failed["status"] == "TIMEOUT" and f"reproduce: {failed['reproduce']}" in done.stdout
    args = failed["reproduce"].split()[2:]
    again = subprocess.run([*CLI, "run", *args, "--report", "r.json"], cwd=tmp_path, capture_output=True, text=True)
    assert again.returncode == 1
    report = json.loads((tmp_path / "r.json").read_text())
    assert (report["final_pose"], report["sim_time"]) == (failed["final_pose"], failed["sim_time"])


PLUGIN = """\
import os, signal
from py_trees.common import Status
from thymio_bt.behaviours import RobotBehaviour
class DieOnSeed3(RobotBehaviour):
    \"\"\"Kills its process in the run of seed 3 (a simulation's config holds the seed).\"\"\"
    def step(self):
        if self.robot.config.seed == 3:
            BODY
        return Status.SUCCESS
"""


@pytest.mark.parametrize(
    "body, message",
    [
        ("os._exit(3)", "a worker process died (exit code 3)"),
        ("os.kill(os.getpid(), signal.SIGKILL)", "killed by SIGKILL"),
    ],
)
def test_a_sweep_worker_that_dies_is_reported_not_a_traceback(tmp_path, body, message):
    (tmp_path / "dying.py").write_text(PLUGIN.replace("BODY", body))
    (tmp_path / "m.yaml").write_text("maze: arena\nstart: centre\nplugins: [dying.py]\ntree: DieOnSeed3\n")
    done = subprocess.run(
        [*CLI, "sweep", "m.yaml", "--runs", "40", "--workers", "2", "--out", "s.json"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 1 and message in done.stderr and "Traceback" not in done.stderr
    data = json.loads((tmp_path / "s.json").read_text())
    assert data["interrupted"].startswith("a worker process died") and data["runs"] < 40
    assert all(r["status"] == "SUCCESS" for r in data["results"])


STUCK = """\
from pathlib import Path
from py_trees.common import Status
from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour
class StuckParams(BehaviourParams):
    \"\"\"No parameters.\"\"\"
class Stuck(RobotBehaviour):
    \"\"\"Drives for three ticks, then loops for ever inside its fourth (says so in 'stuck.txt').\"\"\"
    yaml_name = "Stuck"
    Params = StuckParams
    moves = True
    def start(self):
        self.ticks = 0
    def step(self):
        self.robot.drive(0.1, 0.0)
        self.ticks += 1
        if self.ticks > 3:
            Path("stuck.txt").write_text("stuck")
            while True:
                pass
        return Status.RUNNING
"""


def _stuck_mission(folder: Path) -> Path:
    (folder / "stuck.py").write_text(STUCK)
    mission = folder / "stuck.yaml"
    mission.write_text("name: stuck\nmaze: arena\nstart: centre\nplugins: [stuck.py]\ntree: {sequence: [Stuck]}\n")
    return mission


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_second_signal_ends_a_run_stuck_inside_a_tick(tmp_path, sig, code):
    _stuck_mission(tmp_path)
    proc = start(["run", "stuck.yaml", "--report", "r.json", "--log", "r.jsonl"], tmp_path, grace="60")
    wait_for(tmp_path / "stuck.txt")
    heard(lambda: proc.send_signal(sig), proc.pid)  # noted for the next tick, which never comes
    assert proc.poll() is None  # still stuck: the first signal only asks, and the grace period is long
    proc.send_signal(sig)  # the second breaks in at once, grace or not
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == code, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert (report["status"], report["code"], report["failed_path"]) == ("FAILURE", "INTERRUPTED", "sequence/Stuck")
    assert signal.Signals(sig).name in report["reason"] and "never ended its tick" in report["reason"]
    assert report["reason"].endswith("a second signal stopped it")
    assert report["ticks"] == 3 and report["sim_time"] == 0.3
    ends = [e for e in report["events"] if e["kind"] == "behaviour_end"]
    assert [e["name"] for e in ends] == ["Stuck"]  # halted like any running node: its motors stopped
    lines = [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()]
    assert lines[-1]["kind"] == "end" and lines[-1]["code"] == "INTERRUPTED"
    assert [r["tick"] for r in lines if "tick" in r] == [1, 2, 3]
    assert "Traceback" not in err and "INTERRUPTED" in out


def test_a_run_stuck_in_its_first_tick_still_leaves_a_whole_log(tmp_path):
    _stuck_mission(tmp_path)
    (tmp_path / "stuck.py").write_text(STUCK.replace("if self.ticks > 3:", "if self.ticks > 0:"))
    proc = start(["run", "stuck.yaml", "--report", "r.json", "--log", "r.jsonl"], tmp_path, grace="60")
    wait_for(tmp_path / "stuck.txt")
    heard(lambda: proc.send_signal(signal.SIGINT), proc.pid)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 130, err
    lines = [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()]
    assert [r["kind"] for r in lines] == ["header", "end"] and lines[-1]["code"] == "INTERRUPTED"
    assert json.loads((tmp_path / "r.json").read_text())["ticks"] == 0


def test_a_second_signal_stops_the_motors_of_a_run_stuck_inside_a_tick(tmp_path, monkeypatch):
    import threading

    from thymio_bt.mission import load_mission
    from thymio_bt.run.interrupts import Interrupts
    from thymio_bt.run.runner import Run

    run = Run(load_mission(_stuck_mission(tmp_path)))
    run.backend.close = lambda: None  # keep the world to look at it after the run
    monkeypatch.chdir(tmp_path)  # the plugin writes stuck.txt in the working folder

    def press_ctrl_c_twice():
        wait_for(tmp_path / "stuck.txt")
        heard(lambda: os.kill(os.getpid(), signal.SIGINT), os.getpid())
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=press_ctrl_c_twice, daemon=True).start()
    try:
        with Interrupts() as interrupts:
            result = run.run(interrupts=interrupts)
    except KeyboardInterrupt:
        pytest.fail("the second Ctrl-C escaped the run: no result, the robot left driving")
    assert (result.code, result.failed_path, interrupts.exit_code) == ("INTERRUPTED", "sequence/Stuck", 130)
    command = run.backend.command()
    assert (command.linear, command.angular) == (0.0, 0.0)


#: the ways a plugin gets stuck inside its tick: a loop of Python, a sleep in C, a lock that never comes
STUCK_BODIES = {
    "loop": "while True:\n                pass",
    "sleep": "import time\n            time.sleep(1000)",
    "lock": "import threading\n            lock = threading.Lock()\n            lock.acquire()\n"
    "            lock.acquire()",
}


def _stuck_in(folder: Path, how: str) -> Path:
    mission = _stuck_mission(folder)
    code = STUCK.replace("while True:\n                pass", STUCK_BODIES[how])
    assert code != STUCK or how == "loop"
    (folder / "stuck.py").write_text(code)
    return mission


@pytest.mark.parametrize("how", sorted(STUCK_BODIES))
@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_one_signal_ends_a_run_stuck_inside_a_tick_after_the_grace_period(tmp_path, how, sig, code):
    _stuck_in(tmp_path, how)
    proc = start(["run", "stuck.yaml", "--report", "r.json", "--log", "r.jsonl"], tmp_path)
    wait_for(tmp_path / "stuck.txt")
    proc.send_signal(sig)  # one signal, as a process manager sends before its SIGKILL
    out, err = proc.communicate(timeout=60)  # only against a hang: when it stopped is the report's to say
    assert proc.returncode == code, err
    report = json.loads((tmp_path / "r.json").read_text())
    assert (report["status"], report["code"], report["failed_path"]) == ("FAILURE", "INTERRUPTED", "sequence/Stuck")
    name = signal.Signals(sig).name
    assert report["reason"] == (
        f"interrupted by {name} at 0.3 s: 'sequence/Stuck' never ended its tick; stopped 2 s after the signal"
    )
    assert report["ticks"] == 3 and [e["name"] for e in report["events"] if e["kind"] == "behaviour_end"] == ["Stuck"]
    lines = [json.loads(line) for line in (tmp_path / "r.jsonl").read_text().splitlines()]
    assert lines[-1]["kind"] == "end" and (lines[-1]["code"], lines[-1]["failed_path"]) == (
        "INTERRUPTED",
        "sequence/Stuck",
    )
    assert "Traceback" not in err and "INTERRUPTED" in out


def test_the_grace_period_is_set_by_the_environment(tmp_path):
    _stuck_mission(tmp_path)
    proc = start(["run", "stuck.yaml", "--report", "r.json"], tmp_path, grace="0.25")
    wait_for(tmp_path / "stuck.txt")
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    assert json.loads((tmp_path / "r.json").read_text())["reason"].endswith("stopped 0.25 s after the signal")


def test_a_grace_period_that_is_not_seconds_is_a_user_error(tmp_path):
    done = subprocess.run(
        [*CLI, "run", "square"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={**os.environ, "THYMIO_BT_INTERRUPT_GRACE": "2s"},
    )
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "THYMIO_BT_INTERRUPT_GRACE=2s: expected seconds, a number >= 0" in done.stderr + done.stdout


def test_a_run_that_looks_at_the_signal_is_never_broken_into(tmp_path):
    """The grace period is for a tick that never ends: a run that ends at its next tick, and whatever
    the command does next inside the handled stretch (write its report), goes on undisturbed."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.interrupts import Interrupts
    from thymio_bt.run.runner import Run

    run = Run(load_mission("square"))

    def signal_at_tick_5(r):
        if r.ticks == 5:
            os.kill(os.getpid(), signal.SIGTERM)

    count = threads(os.getpid())
    try:
        with Interrupts(grace=0.1) as interrupts:
            result = run.run(on_tick=signal_at_tick_5, interrupts=interrupts)
            stood_down(os.getpid(), count)  # a watchdog not told would break in here first
    except KeyboardInterrupt:
        pytest.fail("a run that ended at its next tick was broken into after it")
    assert (result.code, result.ticks, result.reason) == ("INTERRUPTED", 5, "interrupted by SIGTERM at 0.4 s")


def test_a_signal_during_a_long_step_outside_a_run_ends_the_command(tmp_path):
    """Outside a run loop (nothing looks at the signal), the grace period ends the stretch with the
    first signal's code, as a second signal does."""
    from thymio_bt.run.interrupts import Interrupted, Interrupts

    with pytest.raises(Interrupted) as raised, Interrupts(grace=0.1):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(30)  # a blocking call in C: the watchdog's signal ends it early
    assert (raised.value.exit_code, raised.value.grace) == (130, 0.1)


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_one_signal_ends_a_sweep_whose_run_is_stuck_in_this_process(tmp_path, sig, code):
    _stuck_in(tmp_path, "sleep")
    proc = start(["sweep", "stuck.yaml", "--runs", "3", "--workers", "1", "--out", "s.json"], tmp_path)
    wait_for(tmp_path / "stuck.txt")
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)  # only against a hang: when it stopped is the result's to say
    assert proc.returncode == code, err
    data = json.loads((tmp_path / "s.json").read_text())
    assert data["interrupted"] == signal.Signals(sig).name and data["runs"] == 1
    [stuck] = data["results"]
    assert (stuck["seed"], stuck["code"], stuck["failed_path"]) == (0, "INTERRUPTED", "sequence/Stuck")
    assert stuck["reason"].endswith("'sequence/Stuck' never ended its tick; stopped 2 s after the signal")
    assert "Traceback" not in err


def test_one_signal_ends_a_sweep_whose_workers_are_stuck(tmp_path):
    _stuck_in(tmp_path, "lock")
    proc = start(["sweep", "stuck.yaml", "--runs", "4", "--workers", "2", "--out", "s.json"], tmp_path)
    wait_for(tmp_path / "stuck.txt")
    workers = children(proc.pid)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    assert workers and not [pid for pid in workers if alive(pid)]
    data = json.loads((tmp_path / "s.json").read_text())
    assert (data["interrupted"], data["runs"]) == ("SIGTERM", 0) and "Traceback" not in err


#: ``serve ros2`` whose 50th step never ends (its publishing blocks on a lock no one releases)
SERVE_STUCK = """\
import sys, threading
from pathlib import Path
from thymio_bt.backends.ros2.serve import GazeboStandIn
from thymio_bt.cli import main
MARKER = Path(sys.argv[1])
publish = GazeboStandIn._publish
def stuck_at_step_50(self, steps):
    if steps == 50:
        MARKER.write_text("stuck")
        lock = threading.Lock()
        lock.acquire()
        lock.acquire()
    publish(self, steps)
GazeboStandIn._publish = stuck_at_step_50
sys.argv = ["thymio-bt", "serve", "ros2", "--quiet"]
main()
"""


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_one_signal_ends_a_serve_whose_step_is_stuck(tmp_path, sig, code):
    import _require

    ros2 = Path(os.environ.get("THYMIO_BT_ROS2_ENV", ROOT / ".venv-ros2"))
    if not (ros2 / "bin" / "python").exists():
        _require.missing(f"a ROS 2 environment in {ros2} (make it: scripts/ros2-env.sh {ros2})")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "RMW_", "THYMIO_BT_INTERRUPT"))}
    env |= {
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "ROS_DOMAIN_ID": str(215 + os.getpid() % 17),
    }  # test_ros2 takes 1-101
    env["PYTHONPATH"] = str(ROOT)  # this checkout's thymio_bt, whichever the ROS 2 environment has
    marker = tmp_path / "stuck.txt"
    proc = subprocess.Popen(
        [str(ros2 / "bin" / "python"), "-c", SERVE_STUCK, str(marker)],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    wait_for(marker, timeout=60)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)  # only against a hang: when it stopped is its message's to say
    assert proc.returncode == code, err
    name = signal.Signals(sig).name
    assert f"stopped: a step of the simulation never ended; stopped 2 s after the signal ({name})" in err
    assert "Traceback" not in err


def test_a_signal_ends_a_slowly_paced_run_at_once_not_by_breaking_in():
    """``--realtime 0.01`` waits 10 s after each tick: a signal in that wait ends the run there, as at
    any tick, without the grace period's break-in (which would blame a tick that had ended)."""
    import threading

    from thymio_bt.mission import load_mission
    from thymio_bt.run.interrupts import Interrupts
    from thymio_bt.run.runner import Run

    run = Run(load_mission("square"))
    threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT)).start()  # in the first tick's wait
    with Interrupts(grace=0.2) as interrupts:
        result = run.run(realtime=0.01, interrupts=interrupts)
    assert (result.code, result.ticks, result.reason) == ("INTERRUPTED", 2, "interrupted by SIGINT at 0.1 s")


def test_a_sweep_broken_into_while_it_waits_for_a_result_keeps_the_results_so_far():
    """An executor that cannot wait briefly (Dask's as_completed): the grace period breaks into its
    wait, and the sweep ends with the runs it has, as when it stops between results."""
    from thymio_bt.run.interrupts import Interrupts
    from thymio_bt.run.sweep import run_job, sweep

    class Blocking:
        def imap_unordered(self, fn, jobs):
            jobs = list(jobs)
            yield run_job(jobs[0])
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(30)  # waits for the next result
            yield from map(fn, jobs[1:])

    with Interrupts(grace=0.1) as interrupts:
        result = sweep("square", runs=3, executor=Blocking(), interrupts=interrupts)
    assert (result.runs, result.requested, result.interrupted) == (1, 3, "SIGTERM")
    assert [r["seed"] for r in result.results] == [0]


def test_an_interrupts_not_entered_does_not_read_the_grace_setting(monkeypatch):
    """A run outside a command (a plugin's pytest, a sweep's worker) never handles a signal: a wrong
    setting is for the command to say, not a reason for every run to fail."""
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    monkeypatch.setenv("THYMIO_BT_INTERRUPT_GRACE", "soon")
    assert Run(load_mission("square")).run().status == "SUCCESS"


def test_a_second_signal_breaks_in_once_the_grace_period_adds_no_other():
    from thymio_bt.run.interrupts import Interrupted, Interrupts

    count = threads(os.getpid())
    with Interrupts(grace=0.3):
        os.kill(os.getpid(), signal.SIGINT)
        with pytest.raises(Interrupted) as raised:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(30)  # the second signal ends it
        assert raised.value.grace is None
        try:
            stood_down(os.getpid(), count)  # the first signal's watchdog ends without breaking in again
        except Interrupted:
            pytest.fail("the grace period broke in again after a second signal had")
