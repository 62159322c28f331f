"""The run's page written by the commands besides ``view`` and ``run --html``: ``replay --html`` (a
logged run, and a what-if replay: the recorded and the re-ticked run, their divergence marked, the
simulated part of ``--continue sim`` shaded), ``compare --html`` (the divergence ``compare`` reports,
with its tolerances), ``sweep --html DIR`` (a page per failed run); and the robot that ran, named in
the log header and drawn (a log without it: the course Thymio, said on the page). Checked in a real
headless Chromium through the DOM contract, as tests/test_viewer.py does; ``replay --view`` of a
what-if replay in pygame's dummy video driver, as tests/test_view.py does."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import test_view
from test_viewer import CONTRACT, expected, js, record

from thymio_bt.logs import read_log
from thymio_bt.robot.model import COURSE, ENKI

# the window's tests' fixture (the browser is conftest's)
pg = test_view.pg

#: the robot(s) the page draws: name, what it says, and each ray's start (its sensor's place)
ROBOTS = """[...document.querySelectorAll('.robot-model')].map(e => ({
  run: e.dataset.run, name: e.dataset.robot, assumed: e.dataset.assumed || null, text: e.textContent,
  rays: [...document.querySelectorAll('.robot[data-run="' + e.dataset.run + '"] .ray')]
    .map(r => [+r.getAttribute('x1'), -r.getAttribute('y1')]),
}))"""


def thymio_bt(*args: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "thymio_bt", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def embedded(page: Path) -> dict[str, Any]:
    """The data a page embeds."""
    return json.loads(page.read_text().split('id="run-data">', 1)[1].split("</script>", 1)[0])


@pytest.fixture(scope="module")
def part12_log(tmp_path_factory) -> Path:
    log = tmp_path_factory.mktemp("log") / "run.jsonl"
    record("maze_part1_2", log)
    return log


# ---------------------------------------------------------------- replay --html


def test_replay_html_writes_the_page_of_the_logged_run(browser, part12_log, tmp_path):
    page = tmp_path / "replayed.html"
    done = thymio_bt("replay", part12_log, "--html", page)
    assert done.returncode == 0, done.stderr
    assert f"wrote {page}" in done.stderr and "nothing to draw" not in done.stderr
    samples = read_log(part12_log).samples
    tab = browser.open(page.as_uri() + "#t=12.3")
    assert tab.problems() == []
    assert tab.evaluate(CONTRACT) == expected(next(s for s in samples if s["t"] == 12.3))
    tab.close()


def test_a_what_if_page_shows_both_runs_and_where_the_tree_decided_differently(browser, part12_log, tmp_path):
    page, report = tmp_path / "whatif.html", tmp_path / "whatif.json"
    done = thymio_bt("replay", part12_log, "--set", "final_stop=6cm", "--html", page, "--report", report)
    assert done.returncode == 1, done.stderr  # stopped where the recording no longer tells
    found = json.loads(report.read_text())["counterfactual"]["divergence"]
    assert (found["time"], found["tick"]) == (3.6, 37)
    runs = embedded(page)["runs"]
    assert [r["label"] for r in runs] == ["recorded", "what if"]
    # the re-ticked run stops at the tick it decides differently: its last tick kept is the one before
    assert runs[1]["t"][-1] == 3.5 and "simulated_from" not in runs[1]
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    assert tab.evaluate("document.documentElement.getAttribute('data-divergence')") == "3.6"
    said = tab.evaluate("document.getElementById('announce').textContent")
    assert "first diverge at t = 3.6 s (tick 37)" in said and "course/part 1 (MoveUntilWall) commanded" in said
    assert tab.evaluate("document.querySelectorAll('.simulated').length") == 0
    tab.close()


def test_a_what_if_page_shades_what_continue_sim_simulated(browser, part12_log, tmp_path):
    page, report, log = tmp_path / "whatif.html", tmp_path / "whatif.json", tmp_path / "whatif.jsonl"
    done = thymio_bt(
        "replay",
        part12_log,
        "--set",
        "final_stop=6cm",
        "--continue",
        "sim",
        "--html",
        page,
        "--report",
        report,
        "--log",
        log,
    )
    assert done.returncode in (0, 1) and f"wrote {page}" in done.stderr, done.stderr
    simulated = json.loads(report.read_text())["counterfactual"]["simulated_ticks"]
    assert f"simulated ticks: {simulated}" in done.stdout
    replayed = read_log(log).samples
    assert 0 < simulated < len(replayed)
    first_simulated = replayed[-simulated]["t"]
    assert first_simulated > 3.6
    tab = browser.open(page.as_uri() + "#t=" + js(first_simulated))
    assert tab.problems() == []
    assert tab.evaluate("document.documentElement.getAttribute('data-divergence')") == "3.6"
    bands = tab.evaluate(
        "[...document.querySelectorAll('.simulated')].map(e => [e.dataset.run, e.dataset.simulatedFrom])"
    )
    assert bands == [["1", js(first_simulated)]]
    assert f"B is simulated from t = {js(first_simulated)} s" in tab.evaluate(
        "document.getElementById('announce').textContent"
    )
    shown = tab.evaluate("document.querySelector('.robot[data-run=\"1\"]').dataset.pose")
    pose = replayed[-simulated]["pose"]
    assert shown == " ".join(f"{pose[k]:.4f}" for k in ("x", "y", "yaw"))
    tab.close()


def test_what_if_replay_view_shows_the_re_ticked_run(pg, part12_log, monkeypatch):
    from click.testing import CliRunner

    from thymio_bt.cli import main
    from thymio_bt.viz.window import Viewer

    shown: list[float] = []
    show = Viewer.show

    def seen(self, frame):
        shown.append(frame.t)
        return show(self, frame)

    monkeypatch.setattr(Viewer, "show", seen)
    result = CliRunner().invoke(
        main, ["replay", str(part12_log), "--set", "final_stop=6cm", "--view", "--speedup", "1e9"]
    )
    assert result.exit_code == 1, result.output
    assert len(shown) == 36 and shown[-1] == 3.5  # the re-ticked run, to the tick before it stopped


# ---------------------------------------------------------------- compare --html


def test_compare_html_marks_the_divergence_compare_reports_with_its_tolerances(browser, tmp_path):
    noise = {"noise.wheel": "0.027", "noise.range_sd": "0.001"}
    logs = [tmp_path / "seed3.jsonl", tmp_path / "seed4.jsonl"]
    for log, seed in zip(logs, (3, 4), strict=True):
        record("maze_part1_2", log, seed=seed, **noise)
    marked = []
    for tolerance in ("position=1mm,angle=0.2deg", "position=1cm"):
        page, out = tmp_path / f"{tolerance}.html", tmp_path / f"{tolerance}.json"
        done = thymio_bt("compare", *logs, "--tolerance", tolerance, "--json", out, "--html", page)
        assert done.returncode in (0, 1), done.stderr
        assert f"wrote {page}" in done.stderr
        found = json.loads(out.read_text())["divergence"]
        tab = browser.open(page.as_uri())
        assert tab.problems() == []
        assert tab.evaluate("document.documentElement.getAttribute('data-divergence')") == js(found["time"])
        assert tab.evaluate("[...document.querySelectorAll('.verdict')].length") == 2
        tab.close()
        marked.append(found["time"])
    assert marked[0] < marked[1]  # the tighter tolerance diverges earlier: the page follows compare's


def test_compare_backends_html_writes_both_runs(browser, tmp_path):
    page = tmp_path / "backends.html"
    done = thymio_bt("compare", "square", "--backends", "sim,sim", "--html", page)
    assert done.returncode == 0, done.stderr
    assert [r["label"] for r in embedded(page)["runs"]] == ["sim", "sim"]
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    assert tab.evaluate("document.documentElement.getAttribute('data-divergence')") is None
    assert "do not diverge" in tab.evaluate("document.getElementById('announce').textContent")
    tab.close()


# ---------------------------------------------------------------- sweep --html


def test_sweep_html_writes_a_page_per_failed_run(browser, tmp_path):
    folder, out = tmp_path / "pages", tmp_path / "sweep.json"
    done = thymio_bt(
        "sweep", "square", "--runs", "3", "--workers", "1", "--set", "time_limit=6", "--out", out, "--html", folder
    )
    assert done.returncode == 0, done.stderr
    failed = [r for r in json.loads(out.read_text())["results"] if r["status"] != "SUCCESS"]
    assert len(failed) == 3
    assert sorted(p.name for p in folder.iterdir()) == [f"square_seed{r['seed']}.html" for r in failed]
    for r in failed:
        page = folder / f"square_seed{r['seed']}.html"
        assert f"seed {r['seed']}: page {page}" in done.stderr
        ended = embedded(page)["runs"][0]["end"]  # the run made again is the sweep's run, bit for bit
        assert {k: ended[k] for k in ("status", "code", "reason", "failed_path", "sim_time", "final_pose")} == {
            k: r[k] for k in ("status", "code", "reason", "failed_path", "sim_time", "final_pose")
        }
        tab = browser.open(page.as_uri() + "#t=1000")
        assert tab.problems() == []
        assert tab.evaluate("document.querySelector('.verdict').dataset.verdict") == r["status"]
        tab.close()


def test_sweep_html_refuses_a_file_for_its_folder_before_sweeping(tmp_path):
    taken = tmp_path / "pages"
    taken.write_text("")
    done = thymio_bt("sweep", "square", "--runs", "1", "--html", taken)
    assert done.returncode == 2 and "--html" in done.stderr and "not a folder" in done.stderr
    assert "Traceback" not in done.stderr and "succeeded" not in done.stdout


# ---------------------------------------------------------------- the robot that ran


def test_the_log_names_the_robot_and_the_page_draws_it(browser, tmp_path):
    log = tmp_path / "enki.jsonl"
    done = thymio_bt("run", "square", "--robot", "enki", "-q", "--log", log)
    assert done.returncode == 0, done.stderr
    robot = read_log(log).header["robot"]
    assert robot["name"] == "enki" and robot["range"] == ENKI.range_max
    page = tmp_path / "enki.html"
    assert thymio_bt("view", log, "-o", page).returncode == 0
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    [drawn] = tab.evaluate(ROBOTS)
    assert drawn["name"] == "enki" and drawn["assumed"] is None
    assert drawn["rays"] == [[round(s.x, 4), round(s.y, 4)] for s in ENKI.sensors]
    assert drawn["rays"] != [[round(s.x, 4), round(s.y, 4)] for s in COURSE.sensors]
    tab.close()


def test_a_log_without_its_robot_is_drawn_as_the_course_thymio_and_says_so(browser, tmp_path):
    log = tmp_path / "enki.jsonl"
    record("square", log, robot="enki")
    lines = log.read_text().splitlines()
    header = json.loads(lines[0])
    assert header["robot"]["name"] == "enki"
    del header["robot"]  # as logs were written before they named their robot
    old = tmp_path / "old.jsonl"
    old.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    page = tmp_path / "old.html"
    assert thymio_bt("view", old, "-o", page).returncode == 0
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    [drawn] = tab.evaluate(ROBOTS)
    assert drawn["name"] == "course" and drawn["assumed"] == "true"
    assert "the log does not say which robot ran: drawn as the course Thymio" in drawn["text"]
    assert drawn["rays"] == [[round(s.x, 4), round(s.y, 4)] for s in COURSE.sensors]
    tab.close()


def test_an_mcap_log_keeps_its_robot(tmp_path):
    from _require import module

    module("rosbags")
    log = tmp_path / "enki.jsonl"
    record("square", log, robot="enki")
    bag = tmp_path / "enki.mcap"
    assert thymio_bt("export", log, "-o", bag).returncode == 0
    assert read_log(bag).header["robot"] == read_log(log).header["robot"]


def test_a_hostile_robot_in_a_log_header_falls_back_to_the_course_thymio(tmp_path):
    from thymio_bt.logs.recording import Recording
    from thymio_bt.maze import Maze
    from thymio_bt.viz.page_data import robot_data

    for hostile in (
        {"name": "x", "hull": [[0, 0], [1, "<script>"], [2, 2]], "sensors": [["a", 0, 0, 0]], "range": 0.1},
        {"name": "x", "hull": [[0, 0], [1, 1], [2, 2]], "sensors": [], "range": 0.1},
        {"name": "x", "hull": [[0, 0], [1, 1], [2, 2]], "sensors": [["a", 0, 0, 0]], "range": float("nan")},
        "enki",
    ):
        drawn = robot_data(Recording(maze=Maze(), header={"robot": hostile}))
        assert drawn["name"] == "course" and "unreadably" in drawn["assumed"]
