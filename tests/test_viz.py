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
            f"{ROOT}/missions/maze_bonus.yaml",
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


def test_gif_is_animated_and_large_enough_to_read(bonus_run):
    """issue 46 item 12: it was 560x360, its labels unreadable."""
    gif = PIL.open(bonus_run / "run.gif")
    assert gif.n_frames > 10 and gif.size[0] >= 960 and gif.size[1] >= 400
    gif.seek(gif.n_frames // 2)
    assert gif.convert("RGB").getpixel((gif.size[0] // 2, 2)) == (255, 255, 255)  # a white page, not a grey one


def _figure_of(draw, monkeypatch, *args):
    """The matplotlib figure ``draw`` (a function of :mod:`thymio_bt.viz.plots`) saves, drawn again,
    and the texts that drawing drew (a tick label outside the view is kept but not drawn)."""
    from matplotlib.text import Text

    from thymio_bt.viz import plots

    saved = []
    real = plots._save
    monkeypatch.setattr(plots, "_save", lambda fig, plt, path: (saved.append(fig), real(fig, plt, path))[1])
    draw(*args)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig, drawn = saved[0], []
    real_draw = Text.draw
    monkeypatch.setattr(Text, "draw", lambda text, renderer: (drawn.append(text), real_draw(text, renderer))[1])
    FigureCanvasAgg(fig).draw()  # closed once saved: drawn again on a canvas of its own
    monkeypatch.setattr(Text, "draw", real_draw)
    return fig, [t for t in drawn if t.get_visible() and t.get_text().strip()]


@pytest.fixture(scope="module")
def bonus_recording():
    from thymio_bt.logs.recording import Recorder
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run

    recorder = Recorder()
    return recorder.finish(Run(load_mission("maze_bonus")).run(on_tick=recorder))


def test_the_signals_plot_s_behaviour_labels_do_not_overlap(bonus_recording, monkeypatch, tmp_path):
    """issue 46 item 12: MoveUntilWall and ChooseTurn run at once (a parallel), and LookAround for a
    tick: their labels were written over each other. Each behaviour's name is measured where the
    renderer puts it: no two overlap, nor any other text of the figure."""
    from thymio_bt.viz import plots

    fig, texts = _figure_of(plots.plot_signals, monkeypatch, bonus_recording, tmp_path / "s.png")
    renderer = fig.canvas.get_renderer()
    names = {"MoveUntilWall", "ChooseTurn", "LookAround", "TurnAngle"}
    labels = [t for t in texts if t.get_text() in names]
    assert {t.get_text() for t in labels} == names and len(labels) == len(names)  # each once
    boxes = [(t, t.get_window_extent(renderer)) for t in texts]
    for label in labels:
        box = label.get_window_extent(renderer)
        assert [t.get_text() for t, other in boxes if t is not label and box.overlaps(other)] == []


def test_turn_outlines_do_not_pile_up_in_a_cell_by_cell_run(monkeypatch, tmp_path):
    """issue 46 item 12: a wall follower turns up to four times in each cell; each turn drew the
    robot's outline, dozens piled in each cell. No two outlines after a turn overlap now."""
    from matplotlib.colors import to_rgb
    from matplotlib.patches import Polygon

    from thymio_bt.logs.recording import Recorder
    from thymio_bt.mission import load_mission
    from thymio_bt.run.runner import Run
    from thymio_bt.viz import plots

    recorder = Recorder()
    recording = recorder.finish(Run(load_mission(ROOT / "examples" / "wall_follower_left.yaml")).run(on_tick=recorder))
    turns = sum(1 for e in recording.events if e["kind"] == "behaviour_end" and e.get("name") == "TurnAngle")
    fig, _ = _figure_of(plots.plot_run, monkeypatch, recording, tmp_path / "p.png")
    turned = pytest.approx(to_rgb("tab:orange"))
    orange = [p for p in fig.axes[0].patches if isinstance(p, Polygon) and p.get_edgecolor()[:3] == turned]
    outlines = [p.get_path().transformed(p.get_patch_transform()) for p in orange]
    assert turns > 2 * len(outlines) > 20  # one per place, not one per turn
    for i, a in enumerate(outlines):
        assert not any(a.intersects_path(b, filled=True) for b in outlines[i + 1 :])


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
    assert recording.final_pose_json == report["final_pose"]
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
    result = CliRunner().invoke(
        main, ["tree", f"{ROOT}/missions/maze_bonus.yaml", "--svg", "-o", str(tmp_path / "t.svg")]
    )
    assert result.exit_code == 0, result.output
    assert "<svg" in (tmp_path / "t.svg").read_text() and "MoveUntilWall" in (tmp_path / "t.svg").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.svg"]  # no .dot or temporary left


def test_tree_explains_missing_graphviz(tmp_path, monkeypatch):
    monkeypatch.setattr("shutil.which", lambda name: None)
    result = CliRunner().invoke(
        main, ["tree", f"{ROOT}/missions/maze_bonus.yaml", "--png", "-o", str(tmp_path / "t.png")]
    )
    assert result.exit_code == 2 and "needs Graphviz's 'dot' program" in result.output
    assert list(tmp_path.iterdir()) == []


def test_live_tree_prints_statuses_as_they_change():
    result = CliRunner().invoke(main, ["run", f"{ROOT}/missions/square.yaml", "--live-tree"])
    assert result.exit_code == 0
    assert result.output.count("t = ") > 8
    assert "[✓]" in result.output and "[*]" in result.output


def test_a_failed_run_prints_the_failing_branch():
    result = CliRunner().invoke(main, ["run", f"{ROOT}/missions/maze_part1_2.yaml", "--set", "time_limit=10"])
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


def _edges_and_labels(dot: str) -> tuple[list[str], dict[str, list[str]]]:
    """The edge lines of a .dot text, and each node's label lines by node id."""
    import re

    labels = {m[1]: m[2].split("\\n") for m in re.finditer(r'^(n\d+) \[label="((?:[^"\\]|\\.)*)"', dot, re.M)}
    return [line for line in dot.splitlines() if " -> " in line], labels


def test_tree_draws_a_repeat_s_until_and_a_guard_s_condition_as_what_they_are(tmp_path):
    """issue 46 item 12: the until condition was drawn as one more child of the repeat; it hangs on
    a dashed edge that says 'until' (a guard's condition: 'condition'), the body on a plain edge."""
    mission = tmp_path / "m.yaml"
    mission.write_text(
        "maze: arena\nstart: centre\ntree:\n"
        "  sequence:\n"
        "    - repeat: {until: IsDeadEnd, do: {TurnAngle: {angle: 90deg}}}\n"
        "    - guard: {condition: {invert: WallAhead}, do: {MoveDistance: {distance: 1cm}}}\n"
    )
    done = CliRunner().invoke(main, ["tree", str(mission), "--dot", "-o", "-"])
    assert done.exit_code == 0, done.output
    edges, labels = _edges_and_labels(done.stdout)
    by_child = {labels[edge.split(" -> ")[1].split()[0].rstrip(";")][0]: edge for edge in edges}
    assert by_child["IsDeadEnd"].endswith('[label="until", style=dashed];')
    assert by_child["TurnAngle"].endswith(";") and "label" not in by_child["TurnAngle"]
    assert by_child["invert"].endswith('[label="condition", style=dashed];')
    assert "label" not in by_child["MoveDistance"]


def test_tree_and_coverage_drawings_say_each_label_once(tmp_path):
    """issue 46 item 12: a node named by its behaviour showed "SideOpen / SideOpen" (name, then
    behaviour); what a node is is written under its name only when the name does not say it."""
    report = tmp_path / "r.json"
    assert CliRunner().invoke(main, ["run", "maze_part1_2", "-q", "--coverage", "--report", str(report)]).exit_code == 0
    for extra in ([], ["--coverage", str(report)]):
        done = CliRunner().invoke(main, ["tree", "maze_part1_2", "--dot", "-o", "-", *extra])
        assert done.exit_code == 0, done.output
        _, labels = _edges_and_labels(done.stdout)
        assert len(labels) == 16
        repeated = [lines for lines in labels.values() if len(set(lines[:2])) < len(lines[:2])]
        assert repeated == [] and ["IsDeadEnd"] in [lines[:1] for lines in labels.values()]
        assert ["part 1", "MoveUntilWall"] in [lines[:2] for lines in labels.values()]


def test_an_mp4_without_ffmpeg_is_one_clean_error_before_the_run(tmp_path):
    """issue 46 item 12: after the run, the error came with matplotlib's "Animation was deleted
    without rendering anything" warning after it. Now it is refused before the run, alone."""
    import subprocess
    import sys

    empty = tmp_path / "bin"  # a PATH without ffmpeg, whatever this machine has
    empty.mkdir()
    done = subprocess.run(
        [sys.executable, "-W", "always", "-m", "thymio_bt", "run", "square", "--gif", str(tmp_path / "x.mp4")],
        env={"PATH": str(empty), "MPLBACKEND": "Agg"},
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr.splitlines() == [
        f"error: --gif {tmp_path / 'x.mp4'}: cannot write .mp4: ffmpeg is not installed (hint: write a .gif instead)"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin"]


def test_an_mp4_is_piped_to_ffmpeg_as_whole_frames_of_an_even_size(tmp_path, monkeypatch, bonus_recording):
    """The .mp4 path without a real ffmpeg (CI has none): a stand-in on PATH reads what ffmpeg would,
    raw RGB frames of the size given by -s, and writes what it got into the output file."""
    import json
    import stat
    import sys

    from thymio_bt.viz.animation import animate

    program = tmp_path / "bin" / "ffmpeg"
    program.parent.mkdir()
    program.write_text(
        f"#!{sys.executable}\n"
        "import json, sys\n"
        "args = sys.argv[1:]\n"
        "width, height = map(int, args[args.index('-s') + 1].split('x'))\n"
        "got = len(sys.stdin.buffer.read())\n"
        "json.dump({'width': width, 'height': height, 'bytes': got, 'args': args}, open(args[-1], 'w'))\n"
    )
    program.chmod(program.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setenv("PATH", str(program.parent))
    out = animate(bonus_recording, tmp_path / "run.mp4", speedup=20)
    made = json.loads(out.read_text())
    frames = len(bonus_recording.samples[::20]) + 1  # every 20th tick, and the last
    assert made["width"] == 960 and made["height"] % 2 == 0
    assert made["bytes"] == frames * made["width"] * made["height"] * 3
    assert made["args"][made["args"].index("-i") + 2 : made["args"].index("-i") + 4] == ["-pix_fmt", "yuv420p"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin", "run.mp4"]  # the staged file renamed
