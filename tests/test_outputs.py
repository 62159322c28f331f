"""Files written on the user's request: '-' is standard output, targets are checked before any work,
nothing half-written or temporary is left, and special files are never replaced."""

import json
import os
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.outputs import Output

SQUARE = str(Path(__file__).resolve().parents[1] / "missions" / "square.yaml")


def invoke(*args: str):
    return CliRunner().invoke(main, list(args))


def test_report_dash_is_standard_output(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = invoke("run", SQUARE, "--quiet", "--report", "-")
    assert result.exit_code == 0
    assert json.loads(result.stdout)["status"] == "SUCCESS"
    assert list(tmp_path.iterdir()) == []  # no file named '-'


@pytest.mark.parametrize(
    "command", [["run", SQUARE, "--report"], ["sweep", SQUARE, "--runs", "1", "--out"], ["schema", "-o"]]
)
def test_a_missing_folder_is_refused_before_any_work(tmp_path, command):
    result = invoke(*command, str(tmp_path / "nowhere" / "out.json"))
    assert result.exit_code == 2
    assert "does not exist" in result.output and "Traceback" not in result.output
    assert "succeeded" not in result.output and "SUCCESS" not in result.output  # nothing ran


def test_a_fifo_or_a_folder_is_never_replaced(tmp_path):
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    result = invoke("run", SQUARE, "--quiet", "--report", str(fifo))
    assert result.exit_code == 2 and "not a regular file" in result.output
    assert fifo.exists() and not fifo.is_file()
    result = invoke("run", SQUARE, "--quiet", "--report", str(tmp_path))
    assert result.exit_code == 2 and "is a folder" in result.output


def test_writes_are_atomic_and_leave_no_temporary(tmp_path):
    target = tmp_path / "report.json"
    target.write_text("old")
    out = Output(target, "--report")
    with pytest.raises(RuntimeError), out.staged() as tmp:
        tmp.write_text("half")
        raise RuntimeError("crash while writing")
    assert target.read_text() == "old"  # the old file survives a failed write
    out.write_text("new")
    assert target.read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_a_write_error_names_the_target(tmp_path, monkeypatch):
    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    out = Output(tmp_path / "r.json", "--report")
    monkeypatch.setattr(Path, "write_text", full_disk)
    with pytest.raises(UserError, match=r"cannot write .*r\.json: No space left on device"):
        out.write_text("{}")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "option, name", [("--gif", "x.webm"), ("--gif", "x.bmp"), ("--gif", "noext"), ("--plot", "x.gif")]
)
def test_an_unsupported_picture_format_is_refused_before_the_run(tmp_path, option, name):
    result = invoke("run", SQUARE, option, str(tmp_path / name))
    assert result.exit_code == 2
    assert "cannot write" in result.output and "hint: use" in result.output
    assert "SUCCESS" not in result.output and "Traceback" not in result.output


def test_schema_and_maze_import_print_by_default_and_write_with_o(tmp_path):
    printed = invoke("schema")
    assert printed.exit_code == 0 and json.loads(printed.stdout)["title"]
    assert invoke("schema", "-o", str(tmp_path / "s.json")).exit_code == 0
    assert json.loads((tmp_path / "s.json").read_text()) == json.loads(printed.stdout)


def test_log_dash_streams_json_lines_and_moves_the_summary_to_stderr(tmp_path):
    result = invoke("run", SQUARE, "--log", "-")
    assert result.exit_code == 0
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert lines[0]["kind"] == "header" and lines[-1]["kind"] == "end" and lines[-1]["status"] == "SUCCESS"
    assert "SUCCESS after" in result.stderr


def test_a_log_that_cannot_be_written_mid_run_ends_the_run_and_keeps_the_report(tmp_path):
    import resource
    import subprocess
    import sys

    def small_files():  # like a full disk: writes past 200 kB fail with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))

    mission = str(Path(__file__).resolve().parents[1] / "missions" / "maze_6x6_left.yaml")
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "run", mission, "--log", "big.jsonl", "--report", "r.json"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        preexec_fn=small_files,
    )
    assert done.returncode == 1 and "Traceback" not in done.stderr
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["code"] == "STOPPED" and "cannot write the log big.jsonl: File too large" in report["reason"]
    assert 0 < report["sim_time"] < 100
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.jsonl", "r.json"]


@pytest.mark.parametrize(
    "command",
    [
        ["run", SQUARE, "--report"],
        ["tree", SQUARE, "--btcpp"],
        ["sweep", SQUARE, "--runs", "1", "--out"],
        ["schema", "-o"],
    ],
)
def test_a_folder_the_system_refuses_is_refused_before_any_work(command):
    """/proc exists and root may 'write' there by its mode bits, but no file can be created in it."""
    result = invoke(*command, "/proc/thymio-bt-out.json")
    assert result.exit_code == 2, result.output
    assert "cannot create a file in /proc" in result.output and "Traceback" not in result.output
    assert "SUCCESS" not in result.output and "succeeded" not in result.output  # nothing ran


def test_a_new_file_follows_the_umask_and_a_replaced_file_keeps_its_mode(tmp_path):
    old = os.umask(0o027)
    try:
        Output(tmp_path / "new.json", "--report").write_text("{}")
        replaced = tmp_path / "kept.json"
        replaced.write_text("old")
        replaced.chmod(0o604)
        Output(replaced, "--report").write_text("{}")
    finally:
        os.umask(old)
    assert (tmp_path / "new.json").stat().st_mode & 0o777 == 0o640  # 0666 less the umask, not mkstemp's 0600
    assert replaced.stat().st_mode & 0o777 == 0o604
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.json", "new.json"]  # no probe or temporary left
