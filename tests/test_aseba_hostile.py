"""The Aseba link against bad input: a device address that is not one, a peer that sends garbage, a
message cut short, an unknown or unannounced message (a fake Thymio on 127.0.0.1, _fake_aseba), and
a SIGTERM or Ctrl-C while the Aseba Playground starts. The command ends cleanly: a located message
(exit 2), the robot lost with the reason (exit 1), or the signal's code; never a traceback, and
nothing the Playground started left behind."""

import json
import os
import random
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import _require
import pytest
from _fake_aseba import (
    DESCRIPTION,
    DEVICE_INFO,
    VARIABLE_DESCRIPTION,
    VARIABLES,
    FakeThymio,
    frame,
    text,
    words,
)
from _waiting import wait_until

from thymio_bt.backends.playground.process import _GUARD, PlaygroundInterrupted, listening_ports
from thymio_bt.backends.real.aseba import tcp_address
from thymio_bt.errors import UserError

ROOT = Path(__file__).resolve().parents[1]


def thymio_bt(*args: str, **settings) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "thymio_bt", *args], capture_output=True, text=True, timeout=60, **settings
    )


# --- device addresses ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "device, problem",
    [
        ("tcp:127.0.0.1:70000", "the port is 70000, above 65535"),  # wrapped to 4464 before
        ("tcp:127.0.0.1:0", "the port is 0, below 1"),
        ("tcp:127.0.0.1:-1", "the port '-1' is not a number"),
        ("tcp:127.0.0.1:abc", "the port 'abc' is not a number"),
        ("tcp:127.0.0.1:\u0663\u0663\u0663", "is not a number"),  # Arabic-Indic digits, which int() reads
        ("tcp:127.0.0.1:3_333", "the port '3_333' is not a number"),  # int() reads that too
        ("tcp:127.0.0.1: 33333", "the port ' 33333' is not a number"),
        ("tcp:127.0.0.1:", "no port after the host"),
        ("tcp::33333", "no host before the port"),
        ("tcp:[]:33333", "no host before the port"),
        ("tcp:33333", "no HOST:PORT"),
        ("tcp:", "no HOST:PORT"),
    ],
)
def test_a_device_that_is_no_tcp_address_is_refused_with_a_hint(device, problem):
    with pytest.raises(UserError, match=re.escape(problem)) as info:
        tcp_address(device)
    assert "(hint: write tcp:HOST:PORT with a port from 1 to 65535" in str(info.value)


def test_good_tcp_addresses_read_as_host_and_port():
    assert tcp_address("tcp:localhost:1") == ("localhost", 1)
    assert tcp_address("tcp:127.0.0.1:65535") == ("127.0.0.1", 65535)
    assert tcp_address("tcp:[::1]:33333") == ("::1", 33333)


def test_a_port_above_65535_is_refused_by_the_cli_and_never_wraps():
    _require.module("thymiodirect")
    with socket.socket() as wrapped:  # 70000 wrapped is 4464: nothing must connect there
        try:
            wrapped.bind(("127.0.0.1", 70000 % 65536))
            wrapped.listen()
            wrapped.settimeout(0.0)
        except OSError:
            wrapped.close()
        done = thymio_bt("run", "square", "--backend", "aseba", "--backend-opt", "device=tcp:127.0.0.1:70000")
        assert done.returncode == 2, done.stderr
        assert "error: --backend-opt device=tcp:127.0.0.1:70000: the port is 70000, above 65535 (hint:" in done.stderr
        assert "Traceback" not in done.stderr
        if wrapped.fileno() != -1:
            with pytest.raises(BlockingIOError):
                wrapped.accept()


# --- a hostile peer during a run ------------------------------------------------------------------

#: a mission that waits 1.5 s: what ends it earlier is the link
WAIT = "name: wait\nmaze: two_parts_maze\nstart: part1\nrobot: real\ntime_limit: 10\ntree:\n  Wait: {seconds: 1.5}\n"
GARBAGE = random.Random(1).randbytes(64)
CUT = frame(VARIABLES, words(0, *range(11)))[:12]

LOST = {
    "garbage": (GARBAGE, "serve", "the peer does not speak Aseba, or the line carries garbage"),
    "a message cut short, then silence": (CUT, "silent", "a message was cut short: nothing more for 0.8 s"),
    "a message cut short, then the connection closed": (CUT, "close", "the peer closed the connection"),
    "variables of one byte": (
        frame(VARIABLES, b"\x01"),
        "serve",
        "node 1 sent a malformed message (0x9005, 1 byte:",
    ),
    "a device UUID of 3 bytes": (
        frame(DEVICE_INFO, b"\x01\x03abc"),
        "serve",
        "malformed message (0x900d, 5 bytes:",
    ),
    "a variable name not in UTF-8": (frame(VARIABLE_DESCRIPTION, words(1) + text(b"\xff\xfe")), "serve", "0x9001"),
    "variables past the memory": (frame(VARIABLES, words(60000, 1, 2, 3)), "serve", "up to word 60003 of its 11"),
}

IGNORED = {
    "an unknown message type": frame(0x9FFF, words(1, 2)),
    "variables from a node that never announced itself": frame(VARIABLES, words(0, 5, 5), source=9),
    "an event from a node that never announced itself": frame(0x0001, words(1), source=42),
    "a user event": frame(0x0001, words(7)),
    "a description nobody asked for": frame(DESCRIPTION, text("thymio-II") + words(5, 1000, 32, 1000, 5, 0, 1)),
    "a variable nobody asked for": frame(VARIABLE_DESCRIPTION, words(100) + text("extra")),
}


def run_against(tmp_path: Path, robot: FakeThymio) -> tuple[subprocess.CompletedProcess, dict]:
    _require.module("thymiodirect")
    (tmp_path / "wait.yaml").write_text(WAIT)
    report = tmp_path / "report.json"
    device = f"device={robot.device}"
    done = thymio_bt(
        "run", str(tmp_path / "wait.yaml"), "--backend", "aseba", "--backend-opt", device,
        "--backend-opt", "placed=true", "--report", str(report),
    )  # fmt: skip
    robot.close()
    assert "Traceback" not in done.stderr + done.stdout, done.stderr
    return done, json.loads(report.read_text()) if report.exists() else {}


@pytest.mark.parametrize("case", LOST)
def test_a_peer_that_sends_what_no_thymio_sends_loses_the_robot_with_the_reason(tmp_path, case):
    hostile, then, reason = LOST[case]
    robot = FakeThymio(hostile, then=then)
    done, report = run_against(tmp_path, robot)
    assert robot.sent_hostile.is_set()
    assert done.returncode == 1, done.stderr
    assert (report["status"], report["code"]) == ("FAILURE", "ROBOT_LOST"), report["reason"]
    assert reason in report["reason"] and reason in done.stderr
    assert report["sim_time"] < 1.5  # before the Wait ended


def test_a_robot_silent_in_the_middle_of_a_message_cut_it_short_whichever_timer_ends_first():
    """Both timers are 0.8 s: the reader's (a message begun, nothing more) and the run's (nothing
    whole from the robot). Before, under load the run's could end first and say 'stopped answering'
    (test_a_peer_that_sends..., 'a message cut short, then silence', failed so once)."""
    from types import SimpleNamespace

    from thymio_bt.backends.real.aseba import AsebaNode
    from thymio_bt.robot.interface import RobotLost

    link = SimpleNamespace(failed=None, midway=True)  # the reader has not given up on the message yet
    remote = SimpleNamespace(last_msg_time=time.time() - 1.0)
    connection = SimpleNamespace(io=link, comm_error=None, input_thread=SimpleNamespace(comm_error=None))
    connection.remote_nodes = {1: remote}
    node = AsebaNode(connection, 1, None, "tcp:127.0.0.1:1", None)
    with pytest.raises(RobotLost, match="failed: a message was cut short: nothing more for 0.8 s"):
        node.read_prox()
    link.midway = False  # between messages: silence
    with pytest.raises(RobotLost, match=r"stopped answering \(nothing for 0.8 s\)"):
        node.read_prox()


@pytest.mark.parametrize("case", IGNORED)
def test_a_message_a_thymio_may_ignore_is_ignored(tmp_path, case):
    robot = FakeThymio(IGNORED[case])
    done, report = run_against(tmp_path, robot)
    assert robot.sent_hostile.is_set()
    assert done.returncode == 0, done.stderr
    assert report["status"] == "SUCCESS"


# --- a hostile peer while connecting ----------------------------------------------------------------


def connect_to(robot: FakeThymio, timeout: int) -> subprocess.CompletedProcess:
    _require.module("thymiodirect")
    done = thymio_bt(
        "run", "square", "--backend", "aseba", "--backend-opt", f"device={robot.device}",
        "--backend-opt", f"timeout={timeout}", "--backend-opt", "placed=true",
    )  # fmt: skip
    robot.close()
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    return done


def test_garbage_while_connecting_is_a_message_at_once_not_a_timeout():
    """At once: the connection's timeout is 60 s (the most it may be), so a command that waited for it
    would not end within thymio_bt()'s 60 s, and fail the test."""
    done = connect_to(FakeThymio(GARBAGE, after=0), timeout=60)
    assert "failed while connecting: a message" in done.stderr and "carries garbage" in done.stderr
    assert "(hint: is it a Thymio" in done.stderr


def test_a_node_without_the_thymios_variables_is_refused():
    done = connect_to(FakeThymio(variables=(("prox.horizontal", 7), ("motor.left.target", 1))), timeout=2)
    assert "no Thymio answered" in done.stderr
    assert "node 1 is no Thymio II: it has no variable motor.left.speed of 1 words" in done.stderr


def test_a_node_that_never_describes_itself_is_no_thymio():
    done = connect_to(FakeThymio(describe=False), timeout=2)
    assert "no Thymio answered on tcp:127.0.0.1:" in done.stderr and "within 2 s" in done.stderr


# --- a signal while the Playground starts ----------------------------------------------------------


def _ours(tmp: Path) -> dict[int, str]:
    """The live processes whose command line names ``tmp`` (the Playground and its bus run there)."""
    found = {}
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            line = cmdline.read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if str(tmp) in line and "pytest" not in line:
            found[int(cmdline.parent.name)] = line
    return found


def _reached(tmp: Path, moment: str) -> bool:
    folders = list(tmp.glob("thymio-bt-playground-*"))
    if moment == "folder" or not folders:
        return bool(folders)
    if moment == "bus":
        return (folders[0] / "bus").exists()
    return any(listening_ports(pid) for pid, line in _ours(tmp).items() if "asebaplayground" in line)


@pytest.mark.parametrize("moment", ["folder", "bus", "port"])
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_while_the_playground_starts_leaves_nothing_behind(moment, signum):
    """Before: a SIGTERM from the moment the Playground was launched until the run took over killed
    thymio-bt and left asebaplayground, its dbus-daemon and its folder behind."""
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    _require.module("thymiodirect")
    _require.module("jeepney")
    tmp = Path(tempfile.mkdtemp(prefix="tbt-", dir="/tmp"))  # short: the bus's socket path has a limit
    try:
        process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "thymio_bt",
                "run",
                f"{ROOT}/missions/maze_part1_2.yaml",
                "--backend",
                "playground",
                "-q",
            ],
            stderr=subprocess.PIPE,
            text=True,
            env={**os.environ, "TMPDIR": str(tmp)},
        )
        reached = lambda: _reached(tmp, moment) or process.poll() is not None  # noqa: E731
        wait_until(reached, f"the Playground's {moment}", every=0.002)  # the signal then at once
        assert process.poll() is None, process.stderr.read()
        process.send_signal(signum)
        _, err = process.communicate(timeout=20)
        assert process.returncode == 128 + signum, err
        assert "Traceback" not in err
        assert _ours(tmp) == {}
        assert list(tmp.iterdir()) == []
    finally:  # what a failing version left behind is this test's to end
        for pid in _ours(tmp):
            os.kill(pid, signal.SIGKILL)
        shutil.rmtree(tmp, ignore_errors=True)


class _Started:
    """Stands for a running Playground in the signal guard: records that it was stopped."""

    def __init__(self):
        self.stopped = 0

    def stop(self):
        self.stopped += 1
        _GUARD.remove(self)


def test_a_signal_while_a_playground_runs_stops_it_then_ends_the_command():
    playground = _Started()
    _GUARD.add(playground)
    try:
        with pytest.raises(PlaygroundInterrupted) as info:
            signal.raise_signal(signal.SIGTERM)  # the handler runs (and raises) before this returns
        assert info.value.exit_code == 143 and playground.stopped == 1
        assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL  # the last one stopped: the default again
    finally:
        playground.stop()


def test_a_signal_as_the_playground_s_folder_is_made_is_held_until_it_is_recorded(monkeypatch, tmp_path):
    """Before: a signal between making the folder and recording the Playground found the default
    handler, and the folder was left behind (the 'folder' moment above, a race: it failed under load)."""
    _require.program("asebaplayground")
    _require.program("dbus-daemon")
    from thymio_bt.backends.playground import process

    made = []

    def mkdtemp(prefix: str, dir: str) -> str:  # the folder made, then the signal, before it is returned
        made.append(tmp_path / f"{prefix}1")
        made[-1].mkdir()
        signal.raise_signal(signal.SIGINT)
        return str(made[-1])

    monkeypatch.setattr(process.tempfile, "mkdtemp", mkdtemp)
    with pytest.raises(KeyboardInterrupt) as info:
        process.Playground.start("")
    assert type(info.value) is PlaygroundInterrupted and info.value.exit_code == 130
    assert len(made) == 1 and not made[0].exists() and not _GUARD.alive
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the handler put back


def test_a_signal_while_a_process_is_started_waits_until_it_is_recorded():
    playground = _Started()
    _GUARD.add(playground)
    try:
        with pytest.raises(PlaygroundInterrupted) as info, _GUARD.held():
            signal.raise_signal(signal.SIGINT)  # the handler runs before this returns
            assert playground.stopped == 0  # not yet: held
        assert info.value.exit_code == 130 and playground.stopped == 1
    finally:
        playground.stop()


def test_once_every_playground_stopped_a_handler_put_back_by_another_acts_as_the_default():
    """A run's own handler takes SIGINT over and puts the guard's back when it ends, after the
    Playground was closed: Ctrl-C is then a plain KeyboardInterrupt again, and the default is restored."""
    playground = _Started()
    _GUARD.add(playground)
    guard = signal.signal(signal.SIGINT, lambda *_: None)  # the run's handler
    playground.stop()
    signal.signal(signal.SIGINT, guard)  # the run ends: the guard's handler is back, no Playground
    with pytest.raises(KeyboardInterrupt) as info:
        signal.raise_signal(signal.SIGINT)
    assert type(info.value) is KeyboardInterrupt and playground.stopped == 1
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_closing_a_connection_s_loop_after_asyncio_run_elsewhere_in_the_thread():
    """asyncio.run() (the --dask probe does one) leaves the main thread without a current loop, and
    closing the Aseba connection's idle loop then raised 'There is no current event loop' (CI's
    Playground test, after the Dask tests in the same process)."""
    import asyncio

    from thymio_bt.backends.real.aseba import _finish

    asyncio.run(asyncio.sleep(0))
    loop = asyncio.new_event_loop()
    _finish(loop)
    assert loop.is_closed()
