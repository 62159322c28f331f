"""A hostile class: each attack on the grader is a submission with plugins, graded with honest ones
(issue 42's trust boundary). One class is graded once for the module; each test reads it.

Every attack reports what it managed through its own feedback (an exception's message is the run's
reason), so a test reads what leaked, what was written or signalled, from the results.
"""

from __future__ import annotations

import hashlib
import os
import socket
import sys
import textwrap
import threading
from pathlib import Path

import _require
import pytest

from thymio_bt.grade.confine import plan
from thymio_bt.grade.grader import grade
from thymio_bt.grade.reaping import CGROUP_ROOTS

pytestmark = pytest.mark.skipif(  # in CI (THYMIO_BT_REQUIRE_ALL=1) a missing confinement fails instead
    (not sys.platform.startswith("linux") or plan().missing != {}) and not _require.REQUIRE_ALL,
    reason="needs Linux with Landlock ABI 6+",
)

#: the honest tree every attacker wraps: it stops 8 cm from the wall (the criterion wants 5 cm) and ends
STOP_8CM = "      - MoveUntilWall: {speed: 10cm/s, distance: 8cm}\n"

ASSIGNMENT = (
    "name: hostile\nvariants:\n  - {name: course, maze: two_parts_maze, start: part1, seeds: 3, noise: off}\n"
    "criteria:\n  - {name: ends well, points: 1, finishes: true}\n"
    "  - {name: stops 5 cm from the wall, points: 2, gap: {at: end, distance: 5cm}}\n"
    "palette: {plugins: true}\nlimits: {cpu: 1s, wall: 3s, memory: 512}\n"
)

#: each attacker's plugin: code run at import (``top``) and in its node's tick (``step``), which
#: raises with what it managed (``got``) when ``report`` is set
ATTACKS = {
    "forger": {
        "top": """
            import thymio_bt.grade.checks as c, thymio_bt.grade.student as s
            c.judge = s.judge = lambda *a: c.Judgement(True)
            c.CHECK_FUNCTIONS.clear()
        """,
        "step": "pass",
    },
    "wiper": {
        "step": """
            import gc
            for o in gc.get_objects():
                if type(o).__name__ == 'EventLog':
                    o.clear()
            self.ctx.events.clear()
            self.robot._pose, self.robot._time = None, 99.0
        """,
    },
    "reader": {
        "step": """
            got = [sys.argv[1:]]
            for path in [SIBLING, ASSIGNMENT, f'/proc/{os.getppid()}/mem', f'/proc/{os.getppid()}/environ',
                         '/proc/1/environ', '/etc/passwd', WORLDS, '/root/.bashrc']:
                try:
                    open(path, 'rb').close()
                    got.append(path)
                except OSError:
                    pass
            got += [k for k in os.environ if k not in ('HOME', 'TMPDIR', 'PATH')]
            raise RuntimeError(f'leaked {got}')
        """,
    },
    "writer": {
        "step": """
            got = []
            for path in [SIBLING, OUTSIDE, ORIGINAL]:
                try:
                    open(path, 'a').write('# pwned')
                    got.append(path)
                except OSError:
                    pass
            raise RuntimeError(f'wrote {got}')
        """,
    },
    "escaper": {
        "step": """
            import time
            if os.fork() == 0:
                os.setsid()
                if os.fork() == 0:
                    time.sleep(600)
                os._exit(0)
            if os.fork() == 0:
                time.sleep(600)
        """,
    },
    "killer": {
        "step": """
            import signal
            got = []
            for kill in (lambda: os.kill(os.getppid(), signal.SIGKILL),
                         lambda: os.killpg(os.getpgid(os.getppid()), signal.SIGKILL)):
                try:
                    kill()
                    got.append('killed')
                except OSError:
                    pass
            raise RuntimeError(f'signalled {got}')
        """,
    },
    "sleeper": {"step": "import time\ntime.sleep(3600)"},
    "looper": {"step": "while True: pass"},
    "caller": {
        "step": """
            import socket
            got = []
            try:
                socket.socket().connect(('127.0.0.1', PORT))
                got.append('connected')
            except OSError:
                pass
            try:
                socket.socket().bind(('127.0.0.1', 0))
                got.append('bound')
            except OSError:
                pass
            raise RuntimeError(f'network {got}')
        """,
    },
    "bomber": {
        "step": """
            import time
            n = 0
            try:
                while n < 10000:
                    if os.fork() == 0:
                        time.sleep(600)
                        os._exit(0)
                    n += 1
            except OSError:
                pass
            raise RuntimeError(f'forked {n}')
        """,
    },
    "hog": {"step": "x = bytearray(4 << 30)"},
    # a named pipe in its folder (copying it would block the grader): graded as its tree earns
    "piped": {"step": "pass"},
}

#: honest students: a YAML tree that earns everything, one that stops 8 cm away, and a plugin one
HONEST = ("good", "weak", "plugged")


def _write_class(root: Path, port: int) -> tuple[Path, list[Path]]:
    assignment = root / "a.yaml"
    assignment.write_text(ASSIGNMENT)
    good = root / "good"
    good.mkdir()
    (good / "m.yaml").write_text("maze: two_parts_maze\nstart: part1\ntree:\n  MoveUntilWall: {distance: 5cm}\n")
    weak = root / "weak"
    weak.mkdir()
    (weak / "m.yaml").write_text(f"maze: two_parts_maze\nstart: part1\ntree:\n  sequence:\n    children:\n{STOP_8CM}")
    folders = [good, weak, _plugin(root, "plugged", "", "pass", port)]
    folders += [_plugin(root, name, a.get("top", ""), a["step"], port) for name, a in ATTACKS.items()]
    os.mkfifo(root / "piped" / "pipe")
    return assignment, folders


def _plugin(root: Path, name: str, top: str, step: str, port: int) -> Path:
    folder = root / name
    folder.mkdir()
    constants = (
        f"SIBLING = {str(root / 'good' / 'm.yaml')!r}\nASSIGNMENT = {str(root / 'a.yaml')!r}\n"
        f"WORLDS = {str(root / 'worlds')!r}\nOUTSIDE = {str(root / 'outside.txt')!r}\n"
        f"ORIGINAL = {str(folder / 'm.yaml')!r}\nPORT = {port}\n"
    )
    body = textwrap.indent(textwrap.dedent(step).strip(), " " * 8)
    (folder / "nodes.py").write_text(
        "import os, sys\nfrom py_trees.common import Status\nfrom thymio_bt.behaviours import RobotBehaviour\n"
        f"{constants}{textwrap.dedent(top)}"
        "class Bad(RobotBehaviour):\n    '''A node that attacks.'''\n"
        f"    def step(self):\n{body}\n        return Status.SUCCESS\n"
    )
    (folder / "m.yaml").write_text(
        f"maze: two_parts_maze\nstart: part1\nplugins: [nodes.py]\ntree:\n  sequence:\n    children:\n{STOP_8CM}"
        "      - Bad\n"
    )
    return folder


def _hashes(root: Path) -> dict[str, str]:
    return {str(p): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(root.rglob("*")) if p.is_file()}


def _sandbox_processes(grader: int | None = None) -> list[int]:
    """Processes of a submission or zygotes of the grade ``grader`` (this process by default: the grader
    is a child subreaper, so whatever escaped stays beneath it) still alive, and its pids cgroups."""
    from thymio_bt.grade.reaping import descendants

    grader = grader or os.getpid()
    found = []
    for pid in descendants(grader):
        try:
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            continue
        if b"thymio_bt.grade.sandbox" in cmdline:
            found.append(pid)
    return found + [p for root in CGROUP_ROOTS for p in root.glob(f"thymio-bt-{grader}-*")]


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("hostile")
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(0.2)
    accepted: list[object] = []

    def serve() -> None:
        while not stop.is_set():
            try:
                accepted.append(server.accept())
            except OSError:
                continue

    stop = threading.Event()
    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    assignment, folders = _write_class(root, server.getsockname()[1])
    before = _hashes(root)
    honest_alone = grade(assignment, [f for f in folders if f.name in HONEST], workers=2).to_json()
    results = grade(assignment, folders, workers=2).to_json()
    stop.set()
    thread.join()
    server.close()
    return {
        "results": {s["name"]: s for s in results["students"]},
        "summary": results["summary"],
        "alone": {s["name"]: s for s in honest_alone["students"]},
        "before": before,
        "after": _hashes(root),
        "root": root,
        "accepted": accepted,
        "left": _sandbox_processes(),
    }


def _judged(student: dict) -> list[dict]:
    """Each run's judgements, without the file names their places are in."""
    return [{n: {**j, "where": None} for n, j in r["criteria"].items()} for r in student["runs"]]


def _reasons(student: dict) -> list[str]:
    return [run["reason"] or "" for run in student["runs"]]


def test_every_student_is_in_the_results_and_honest_grades_are_unchanged(graded):
    results = graded["results"]
    assert sorted(results) == sorted([*HONEST, *ATTACKS])
    assert all(s["status"] == "graded" and len(s["runs"]) == 3 for s in results.values())
    for name in HONEST:
        alone, among = graded["alone"][name], results[name]
        assert among["score"] == alone["score"]
        assert [r["criteria"] for r in among["runs"]] == [r["criteria"] for r in alone["runs"]]
    assert (results["good"]["score"], results["weak"]["score"], results["plugged"]["score"]) == (3, 1, 1)


def test_a_submission_cannot_forge_its_judgement_nor_wipe_its_record(graded):
    # the forger patched the checks at import, the wiper cleared every event log and result it could
    # reach and faked its robot: both earn what their tree earns honestly (it stops 8 cm away)
    for name in ("forger", "wiper", "piped"):
        student = graded["results"][name]
        assert student["score"] == graded["results"]["plugged"]["score"] == 1
        assert _judged(student) == _judged(graded["results"]["plugged"])


def test_a_submission_reads_nothing_but_its_own_files(graded):
    reasons = _reasons(graded["results"]["reader"])
    assert reasons and all("RuntimeError: leaked [[]]" in r for r in reasons), reasons


def test_a_submission_writes_no_file_outside_its_private_folder(graded):
    reasons = _reasons(graded["results"]["writer"])
    assert all("RuntimeError: wrote []" in r for r in reasons), reasons
    assert graded["after"] == graded["before"]  # every file of the class unchanged
    assert not (graded["root"] / "outside.txt").exists()


def test_a_submission_can_signal_no_process_of_the_grader(graded):
    reasons = _reasons(graded["results"]["killer"])
    assert all("RuntimeError: signalled []" in r for r in reasons), reasons


def test_no_network_from_a_submission(graded):
    reasons = _reasons(graded["results"]["caller"])
    assert all("RuntimeError: network []" in r for r in reasons), reasons
    assert graded["accepted"] == []


def test_forks_are_bounded_and_nothing_outlives_the_grade(graded):
    reasons = _reasons(graded["results"]["bomber"])
    forked = [int(r.split("RuntimeError: forked ")[1].split()[0]) for r in reasons]
    assert all(n < 64 for n in forked), reasons  # RLIMIT_NPROC, not 10000
    assert graded["results"]["escaper"]["score"] == 1  # its tree ends as it would; its processes do not
    assert graded["left"] == []  # no process, no pids cgroup


def test_time_and_memory_limits_fail_the_attackers_runs_with_a_reason(graded):
    results = graded["results"]
    sleeper = _reasons(results["sleeper"])
    assert sleeper[:2] == ["the run went over its wall-clock time limit of 3 s, in 'sequence/Bad'"] * 2
    assert sleeper[2].startswith("skipped: 2 runs went over the time limit (run 1: the run went over")
    looper = _reasons(results["looper"])
    assert "time limit" in looper[0] and "in 'sequence/Bad'" in looper[0]
    assert all("MemoryError" in r for r in _reasons(results["hog"]))
    for name in ("sleeper", "looper", "hog", "reader", "writer", "killer", "caller", "bomber"):
        assert results[name]["score"] == 0, name
        assert all(run["code"] in ("LIMIT", "EXCEPTION", "CRASH") for run in results[name]["runs"]), name


def test_the_summary_says_what_confined_the_plugins(graded):
    assert graded["summary"]["confinement"] == "confined: files, network, signals, processes"


def test_sigterm_ends_a_hostile_class_cleanly(tmp_path):
    # the grade of a class with sleepers is stopped once a student was graded (the progress line of
    # a log): every student is in the results, the unfinished marked interrupted, nothing left running
    import json
    import signal
    import subprocess

    assignment, folders = _write_class(tmp_path, 1)
    chosen = [f for f in folders if f.name in ("good", "sleeper", "looper")]
    out = tmp_path / "r.json"
    cmd = [sys.executable, "-m", "thymio_bt.cli", "grade", str(assignment), *map(str, chosen), "--out", str(out)]
    process = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stderr is not None
    first = process.stderr.readline()
    assert first.startswith("graded 1/3: good, 3 runs"), first
    grader = process.pid
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 143, err
    students = {s["name"]: s for s in json.loads(out.read_text())["students"]}
    assert sorted(students) == ["good", "looper", "sleeper"]
    assert students["good"]["status"] == "graded" and students["good"]["score"] == 3
    assert students["sleeper"]["status"] == "interrupted"
    assert students["sleeper"]["messages"][-1].startswith("interrupted after ")
    # (the grader is gone: its leftovers would have gone to this process, or its cgroups stayed)
    assert _sandbox_processes() == [] and _sandbox_processes(grader) == []


def test_the_command_names_the_confinement_and_prints_a_line_per_student(tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    assignment, folders = _write_class(tmp_path, 1)
    chosen = [str(f) for f in folders if f.name in ("good", "plugged")]
    result = CliRunner().invoke(main, ["grade", str(assignment), *chosen, "--require-confinement"])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    progress = [line.split(": ", 1) for line in lines if line.startswith("graded ")]  # in the order they ended
    assert [p[0] for p in progress] == ["graded 1/2", "graded 2/2"]
    assert sorted(p[1] for p in progress) == ["good, 3 runs", "plugged, 3 runs"]
    assert lines[-1] == "confined: files, network, signals, processes"


def test_require_confinement_is_an_error_where_an_area_is_missing(tmp_path, monkeypatch):
    from click.testing import CliRunner

    import thymio_bt.grade.confine as confine
    from thymio_bt.cli import main

    old_kernel = confine.Confinement(["files", "processes"], {"signals": "Landlock ABI 4 < 6 (kernel older than 6.12)"})
    monkeypatch.setattr(confine, "plan", lambda: old_kernel)
    assignment, folders = _write_class(tmp_path, 1)
    result = CliRunner().invoke(main, ["grade", str(assignment), str(folders[2]), "--require-confinement"])
    assert result.exit_code == 2
    assert result.output == (
        "error: --require-confinement: confined: files, processes; not confined: signals (Landlock ABI 4 < 6 "
        "(kernel older than 6.12)) (hint: grade on Linux 6.12 or later with Landlock enabled, or leave out "
        "--require-confinement)\n"
    )
