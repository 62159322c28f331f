"""Plots, animation, JSON-lines log and replay, tree exports and the live tree (headless)."""

import json
from pathlib import Path

import _require
import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.logs import read_log

_require.module("matplotlib")
PIL = _require.module("PIL.Image")
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def bonus_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("viz")
    result = CliRunner().invoke(
        main,
        [
            "run",
            "missions/maze_bonus.yaml",
            "--report",
            str(out / "report.json"),
            "--log",
            str(out / "run.jsonl"),
            "--plot",
            str(out / "path.png"),
            "--plot-signals",
            str(out / "signals.png"),
            "--gif",
            str(out / "run.gif"),
            "--speedup",
            "20",
        ],
    )
    assert result.exit_code == 0, result.output
    return out


def test_plots_are_real_pictures(bonus_run):
    for name, min_size in (("path.png", (800, 500)), ("signals.png", (800, 800))):
        image = PIL.open(bonus_run / name)
        assert image.size[0] >= min_size[0] and image.size[1] >= min_size[1]
        assert len(image.getcolors(maxcolors=1 << 20) or []) > 20  # not a blank canvas


def test_gif_is_animated(bonus_run):
    gif = PIL.open(bonus_run / "run.gif")
    assert gif.n_frames > 10


def test_log_has_a_header_one_line_per_tick_and_an_end(bonus_run):
    lines = [json.loads(line) for line in (bonus_run / "run.jsonl").read_text().splitlines()]
    report = json.loads((bonus_run / "report.json").read_text())
    assert lines[0]["kind"] == "header" and lines[-1]["kind"] == "end"
    ticks = [line for line in lines if line["kind"] == "tick"]
    assert len(ticks) == report["ticks"]
    assert set(ticks[0]) >= {"t", "pose", "cmd", "vel", "prox", "nodes"}
    assert any("bb" in tick and tick["bb"].get("/turn") == "right" for tick in ticks)


def test_replay_reproduces_the_final_pose_exactly(bonus_run):
    report = json.loads((bonus_run / "report.json").read_text())
    recording = read_log(bonus_run / "run.jsonl")
    assert recording.final_pose == report["final_pose"]
    # the log keeps the pose exactly (what a what-if replay feeds back), the report to 6 decimals
    assert {k: round(v, 6) for k, v in recording.samples[-1]["pose"].items()} == report["final_pose"]
    result = CliRunner().invoke(main, ["replay", str(bonus_run / "run.jsonl"), "--plot", str(bonus_run / "again.png")])
    assert result.exit_code == 0 and (bonus_run / "again.png").stat().st_size > 10_000


def test_a_truncated_log_is_still_readable(bonus_run, tmp_path):
    text = (bonus_run / "run.jsonl").read_text()
    cut = tmp_path / "crashed.jsonl"
    cut.write_text(text[: len(text) // 2])  # a run that died mid-line
    recording = read_log(cut)
    assert recording.end["status"] == "INCOMPLETE" and len(recording.samples) > 100


def test_replay_of_a_file_that_is_not_a_log_is_a_user_error(tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"kind": "tick"}\n')
    result = CliRunner().invoke(main, ["replay", str(bad)])
    assert result.exit_code == 2 and "first line must be its header" in result.output


def test_tree_prints_the_tree_and_writes_nothing_unasked(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(main, ["tree", str(ROOT / "missions/maze_bonus.yaml")])
    assert result.exit_code == 0 and "ChooseTurn" in result.output
    assert list(tmp_path.iterdir()) == []


def test_tree_writes_dot_by_flag_or_suffix_and_to_standard_output(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    mission = str(ROOT / "missions/maze_bonus.yaml")
    assert CliRunner().invoke(main, ["tree", mission, "--dot"]).exit_code == 0  # default: ./maze_bonus.dot
    assert (tmp_path / "maze_bonus.dot").read_text().startswith("digraph")
    assert CliRunner().invoke(main, ["tree", mission, "-o", "t.dot"]).exit_code == 0
    assert "MoveUntilWall" in (tmp_path / "t.dot").read_text()
    printed = CliRunner().invoke(main, ["tree", mission, "--dot", "-o", "-"])
    assert printed.exit_code == 0 and printed.stdout.startswith("digraph")
    unknown = CliRunner().invoke(main, ["tree", mission, "-o", "t.txt"])
    assert unknown.exit_code == 2 and "cannot tell the format" in unknown.output


def test_tree_draws_svg_with_graphviz(tmp_path):
    _require.program("dot")
    result = CliRunner().invoke(main, ["tree", "missions/maze_bonus.yaml", "--svg", "-o", str(tmp_path / "t.svg")])
    assert result.exit_code == 0, result.output
    assert "<svg" in (tmp_path / "t.svg").read_text() and "MoveUntilWall" in (tmp_path / "t.svg").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.svg"]  # no .dot or temporary left


def test_tree_explains_missing_graphviz(tmp_path, monkeypatch):
    monkeypatch.setattr("shutil.which", lambda name: None)
    result = CliRunner().invoke(main, ["tree", "missions/maze_bonus.yaml", "--png", "-o", str(tmp_path / "t.png")])
    assert result.exit_code == 2 and "needs Graphviz's 'dot' program" in result.output
    assert list(tmp_path.iterdir()) == []


def test_live_tree_prints_statuses_as_they_change():
    result = CliRunner().invoke(main, ["run", "missions/square.yaml", "--live-tree"])
    assert result.exit_code == 0
    assert result.output.count("t = ") > 8
    assert "[✓]" in result.output and "[*]" in result.output


def test_a_failed_run_prints_the_failing_branch():
    result = CliRunner().invoke(main, ["run", "missions/maze_part1_2.yaml", "--set", "time_limit=10"])
    assert result.exit_code == 1
    assert "failed at: course/part 2" in result.output
    assert "TurnAngle [*]" in result.output and "[TIMEOUT]" in result.output


def test_the_signals_plot_unwraps_yaw():
    from thymio_bt.viz.plots import unwrapped

    yaws = [3.0, 3.1, -3.1, -3.0, float("nan"), 3.1, -3.1]
    out = unwrapped(yaws)
    assert out[:4] == pytest.approx(
        [3.0, 3.1, 3.1 + (2 * 3.141592653589793 - 6.2), 3.0 + (2 * 3.141592653589793 - 6.0)]
    )
    assert all(abs(b - a) < 0.5 for a, b in zip(out[:3], out[1:4], strict=True))
    assert out[5] == 3.1 and abs(out[6] - out[5]) < 0.5  # after a gap: restarts where it is
