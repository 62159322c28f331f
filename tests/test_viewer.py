"""The run's page (``view LOG``, ``run --html``): what it embeds, and its DOM contract in a real
headless Chromium (driven as tests/test_grade_site.py drives it): every shipped mission's page opens
without a console error or a request, and at several ``#t=`` and ``#tick=`` the tree's statuses, the
robot's pose and the clock say what the log says. Screenshots at 1280 and 400 px go to
``$THYMIO_BT_ARTEFACTS`` (else the test's tmp folder)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from _chromium import Tab
from _waiting import wait_until
from test_grade_site import Page

from thymio_bt.logs import read_log
from thymio_bt.logs.recording import Recorder, Recording
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.viz.page import write_page
from thymio_bt.viz.page_data import page_data, status_changes, statuses_at

ROOT = Path(__file__).resolve().parent.parent
MISSIONS = sorted((ROOT / "missions").glob("*.yaml"))
WORDS = {"S": "SUCCESS", "F": "FAILURE", "R": "RUNNING", "-": "INVALID"}
#: what the page says at the shown moment, per the DOM contract
CONTRACT = """(() => {
  const clock = document.querySelector('[data-time]');
  const robot = document.querySelector('[data-pose]');
  return {
    time: clock.getAttribute('data-time'), tick: clock.getAttribute('data-tick'),
    pose: robot.getAttribute('data-pose'),
    nodes: Object.fromEntries(
      [...document.querySelectorAll('[data-node]')].map(e => [e.dataset.node, e.dataset.status])),
    clocks: document.querySelectorAll('[data-time]').length,
  };
})()"""


def record(mission: str | Path, log: Path | None = None, seed: int | None = None, **settings: str) -> Recording:
    """A run of ``mission`` recorded with its statuses (and written to ``log``)."""
    recorder = Recorder(log_path=log, statuses=True)
    return recorder.finish(Run(load_mission(mission, settings), seed=seed).run(on_tick=recorder))


@pytest.fixture(scope="module")
def part12(tmp_path_factory) -> tuple[Path, Path]:
    """maze_part1_2's log (JSON lines) and the page ``view`` writes of it."""
    folder = tmp_path_factory.mktemp("part12")
    log = folder / "run.jsonl"
    record("maze_part1_2", log)
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "view", str(log)], capture_output=True, text=True, cwd=folder
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"wrote {folder / 'run.html'}"
    return log, folder / "run.html"


def artefacts(tmp_path: Path) -> Path:
    folder = Path(os.environ["THYMIO_BT_ARTEFACTS"]) if os.environ.get("THYMIO_BT_ARTEFACTS") else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def screenshot(tab: Tab, path: Path, width: int, height: int) -> Path:
    """What the viewport shows, as a PNG."""
    import base64

    shot = tab.browser.call(
        "Page.captureScreenshot",
        {"format": "png", "clip": {"x": 0, "y": 0, "width": width, "height": height, "scale": 1}},
        tab.session,
    )
    path.write_bytes(base64.b64decode(shot["data"]))
    return path


def js(number: float) -> str:
    """A number as JavaScript writes it (20.0 is "20")."""
    return str(int(number)) if number == int(number) else repr(number)


def expected(sample: dict[str, Any]) -> dict[str, Any]:
    """What the DOM contract must say at a logged tick."""
    pose = sample["pose"]
    return {
        "time": js(sample["t"]),
        "tick": str(sample["tick"]),
        "pose": "" if pose is None else " ".join(f"{pose[k]:.4f}" for k in ("x", "y", "yaw")),
        "nodes": {path: WORDS[letter] for path, letter in sample["nodes"].items()},
        "clocks": 1,
    }


# ---------------------------------------------------------------- the data, without a browser


def test_the_status_changes_give_back_every_tick_of_the_log(part12):
    recording = read_log(part12[0])
    paths = [node["path"] for node in recording.header["tree"]]
    changes = status_changes(recording.samples, paths)
    for i, sample in enumerate(recording.samples):
        assert dict(zip(paths, statuses_at(changes, i), strict=True)) == sample["nodes"], i
    assert sum(len(letters) for _, letters in changes) < len(paths) * len(recording.samples) / 10


def test_the_page_embeds_the_run_and_nothing_from_outside(part12):
    log, page = part12
    tags = Page(page).tags
    assert [a for t, a in tags if t == "script"] == [{"type": "application/json", "id": "run-data"}, {}]
    assert Page(page).links() == ["data:,"]
    text = page.read_text().replace("http://www.w3.org/2000/svg", "")
    assert "http://" not in text and "https://" not in text and "url(" not in text and "@import" not in text
    data = page_data(read_log(log))
    assert len(data["t"]) == len(data["x"]) == len(data["prox"]["values"][0]) > 300
    assert set(data["bb"]) >= {"/turn"}


def test_view_refuses_three_logs_and_an_unwritable_page(part12, tmp_path):
    log, _ = part12
    for args, message in (
        ([str(log)] * 3, "view takes one or two logs, got 3"),
        ([str(log), "-o", str(tmp_path / "no" / "page.html")], "the folder"),
    ):
        done = subprocess.run([sys.executable, "-m", "thymio_bt", "view", *args], capture_output=True, text=True)
        assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr


def test_run_html_writes_the_page_of_the_run_just_made(tmp_path):
    page = tmp_path / "square.html"
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "run", "square", "-q", "--html", str(page)], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    data = json.loads(page.read_text().split('id="run-data">', 1)[1].split("</script>", 1)[0])
    run = data["runs"][0]
    assert run["mission"] == "square" and run["end"]["status"] == "SUCCESS"
    assert len(run["t"]) == 228 and len(run["status"]) == len(run["tree"]) > 1


# ---------------------------------------------------------------- the page in Chromium


@pytest.mark.parametrize("mission", MISSIONS, ids=[m.stem for m in MISSIONS])
def test_every_shipped_missions_page_opens_cleanly(browser, tmp_path, mission):
    recording = record(mission)
    page = write_page([recording], tmp_path / f"{mission.stem}.html")
    last = recording.samples[-1]
    tab = browser.open(page.as_uri() + "#tick=" + str(last["tick"]))
    assert tab.problems() == []
    assert tab.evaluate(CONTRACT) == expected(last)
    tab.close()


def test_the_dom_contract_matches_the_log_at_several_moments(browser, part12, tmp_path):
    log, page = part12
    samples = read_log(log).samples
    tab = browser.open(page.as_uri() + "#t=12.3")
    at = {s["t"]: s for s in samples}
    assert tab.evaluate(CONTRACT) == expected(at[12.3])
    # a time between two ticks shows the tick before it; before the first tick, the first
    moments = [("t=0", samples[0]), ("t=20.05", at[20.0]), ("t=4.5", at[4.5]), ("t=-3", samples[0])]
    moments += [(f"tick={s['tick']}", s) for s in (samples[1], samples[150], samples[-1])]
    moments += [(f"t={samples[-1]['t'] + 50}", samples[-1])]
    for fragment, sample in moments:
        tab.evaluate(f"location.hash = {json.dumps('#' + fragment)}")
        tab.evaluate("new Promise(r => setTimeout(r, 0))")
        assert tab.evaluate(CONTRACT) == expected(sample), fragment
    assert tab.problems() == []
    tab.close()


def test_keys_step_through_ticks_and_events(browser, part12):
    log, page = part12
    recording = read_log(log)
    samples = recording.samples
    tab = browser.open(page.as_uri() + "#tick=" + str(samples[10]["tick"]))

    def key(name: str, shift: bool = False) -> Any:
        options = json.dumps({"key": name, "shiftKey": shift})
        tab.evaluate(f"document.dispatchEvent(new KeyboardEvent('keydown', {options}))")
        return tab.evaluate(CONTRACT)

    assert key("ArrowRight")["tick"] == str(samples[11]["tick"])
    assert key("ArrowLeft")["tick"] == str(samples[10]["tick"])
    assert key("ArrowRight", shift=True)["time"] == js(samples[20]["t"])
    events = sorted({e["t"] for e in recording.events if e["t"] > samples[20]["t"]})
    assert key("]")["time"] == js(events[0])
    assert key("]")["time"] == js(events[1])
    assert key("[")["time"] == js(events[0])
    assert key("End")["time"] == js(samples[-1]["t"])
    shown = key("Home")
    assert shown["time"] == js(samples[0]["t"])
    whole = tab.evaluate("document.querySelector('svg.maze').getAttribute('viewBox')")
    key("z")  # up close: 70 cm around the robot
    x, y, _ = (float(v) for v in shown["pose"].split())
    box = [float(v) for v in tab.evaluate("document.querySelector('svg.maze').getAttribute('viewBox')").split()]
    assert box == pytest.approx([x - 0.35, -y - 0.35, 0.7, 0.7])
    key("z")
    assert tab.evaluate("document.querySelector('svg.maze').getAttribute('viewBox')") == whole
    assert tab.problems() == []
    tab.close()


def test_a_breakpoint_pauses_play_where_the_node_ends(browser, part12):
    log, page = part12
    samples = read_log(log).samples
    ends = next(s for s in samples if s["nodes"]["course/part 1"] == "S")
    tab = browser.open(page.as_uri() + "#t=0")
    tab.evaluate(
        "(() => { const [node, when] = document.querySelectorAll('.bp-form select');"
        " node.value = 'course/part 1'; when.value = 'ends';"
        " document.querySelector('.bp-form button').click();"
        " document.dispatchEvent(new KeyboardEvent('keydown', {key: '3'}));"
        " document.dispatchEvent(new KeyboardEvent('keydown', {key: ' '})); })()"
    )
    playing = "document.querySelector('.controls button[aria-pressed=\"true\"]:not(.speed)') !== null"
    wait_until(lambda: not tab.evaluate(playing), "play to pause", every=0.05)
    shown = tab.evaluate(CONTRACT)
    assert shown["time"] == js(ends["t"]) and shown["nodes"]["course/part 1"] == "SUCCESS"
    assert "breakpoint course/part 1 ends" in tab.evaluate("document.getElementById('announce').textContent")
    assert tab.problems() == []
    tab.close()


def test_the_page_is_usable_at_1280_and_on_a_phone(browser, part12, tmp_path):
    _, page = part12
    shots = artefacts(tmp_path)
    for width, height in ((1280, 720), (400, 860)):
        tab = browser.open(page.as_uri() + "#t=12.3", width, height)
        assert tab.problems() == []
        layout = tab.evaluate(
            """({overflow: document.documentElement.scrollWidth > innerWidth,
            maze: document.querySelector('svg.maze').getBoundingClientRect().toJSON(),
            scrub: document.getElementById('scrub').getBoundingClientRect().toJSON()})"""
        )
        assert not layout["overflow"], width
        assert layout["maze"]["width"] > 300 and layout["maze"]["height"] > 200, (width, layout)
        if width == 1280:  # the maze, the tree and the timeline on one screen
            assert layout["scrub"]["bottom"] <= height, layout
        shot = screenshot(tab, shots / f"viewer_part1_2_{width}.png", width, height)
        assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 10_000
        tab.close()


def test_a_hostile_log_runs_nothing_in_the_page(browser, part12, tmp_path):
    log, _ = part12
    payload = "</script><script>window.__pwned=1</script><img src=x onerror=window.__pwned=1>"
    lines = log.read_text().splitlines()
    header = json.loads(lines[0])
    header["mission"] = payload
    header["tree"][1]["name"] = payload
    tick = json.loads(lines[40])
    tick["bb"] = {payload: payload}
    lines[0], lines[40] = json.dumps(header), json.dumps(tick)
    hostile = tmp_path / "hostile.jsonl"
    hostile.write_text("\n".join(lines) + "\n")
    page = write_page([read_log(hostile)], tmp_path / "hostile.html")
    tab = browser.open(page.as_uri() + "#t=30")
    assert tab.problems() == []
    found = tab.evaluate(
        "({pwned: window.__pwned === 1, imgs: document.images.length, scripts: document.scripts.length})"
    )
    assert found == {"pwned": False, "imgs": 0, "scripts": 2}
    assert tab.evaluate("document.title") == payload + " - thymio-bt"
    tab.close()


def test_two_seeds_diverge_where_the_statuses_or_poses_first_differ(browser, tmp_path):
    noise = {"noise.wheel": "0.027", "noise.range_sd": "0.001"}
    logs = [tmp_path / "seed3.jsonl", tmp_path / "seed4.jsonl"]
    a, b = (record("maze_part1_2", log, seed=seed, **noise) for log, seed in zip(logs, (3, 4), strict=True))
    first = None
    for sa, sb in zip(a.samples, b.samples, strict=False):
        assert sa["t"] == sb["t"]
        pa, pb = sa["pose"], sb["pose"]
        apart = (pa is None) != (pb is None) or (
            pa is not None
            and (
                math.dist((pa["x"], pa["y"]), (pb["x"], pb["y"])) > 0.01
                or abs(math.remainder(pa["yaw"] - pb["yaw"], math.tau)) > math.radians(5)
            )
        )
        if sa["nodes"] != sb["nodes"] or apart:
            first = sa
            break
    assert first is not None
    page = tmp_path / "two.html"
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "view", *map(str, logs), "-o", str(page)], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert f"first divergence at t = {first['t']} s" in done.stdout
    tab = browser.open(page.as_uri())
    assert tab.problems() == []
    assert tab.evaluate("document.documentElement.getAttribute('data-divergence')") == js(first["t"])
    assert "first diverge at t = " + js(first["t"]) in tab.evaluate("document.getElementById('announce').textContent")
    tab.evaluate("document.dispatchEvent(new KeyboardEvent('keydown', {key: 'd'}))")
    shown = tab.evaluate(
        "[...document.querySelectorAll('[data-pose]')].map(r => [r.dataset.run, r.dataset.pose, r.dataset.tick])"
    )
    assert [s[0] for s in shown] == ["0", "1"] and {s[2] for s in shown} == {str(first["tick"])}
    assert tab.evaluate("document.querySelectorAll('.tree').length") == 2
    screenshot(tab, artefacts(tmp_path) / "viewer_two_seeds_1280.png", 1280, 800)
    tab.close()


def test_a_live_run_streams_its_ticks_to_the_page(browser, tmp_path):
    """``run --web 0`` serves a page with no tick in it; the page fetches every tick and the end as
    the run goes, and then says what the log says."""
    log = tmp_path / "live.jsonl"
    command = [sys.executable, "-m", "thymio_bt", "run", "square", "-q", "--web", "0", "--realtime", "8", "--log"]
    proc = subprocess.Popen([*command, str(log)], stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stderr is not None
        line = proc.stderr.readline()
        assert line.startswith("watch the run at http://127.0.0.1:"), line
        url = line.split()[-1]
        tab = browser.open(url)
        assert tab.evaluate("JSON.parse(document.getElementById('run-data').textContent).runs[0].t") == []
        verdict = "document.querySelector('.verdict').dataset.verdict"
        ended = lambda: tab.evaluate(verdict) == "SUCCESS" or proc.poll() not in (None, 0)  # noqa: E731
        wait_until(ended, "the page to get the run's end", timeout=120, every=0.1)
        assert proc.poll() in (None, 0) and tab.evaluate(verdict) == "SUCCESS", "the run failed"
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()
        proc.wait()
    samples = read_log(log).samples
    assert tab.evaluate(CONTRACT) == expected(samples[-1])  # it follows the run to its last tick
    tab.evaluate("location.hash = '#tick=100'")
    assert tab.evaluate(CONTRACT) == expected(samples[99])  # and keeps every tick it received
    served = f"request off the machine's files: {url}"  # the page and its polls: the run's own server
    assert [p for p in tab.problems() if p != served and not p.startswith(served + "ticks?from=")] == []
    tab.close()


def test_the_live_server_answers_only_its_own_host_and_a_busy_port_is_a_user_error():
    import http.client
    import socket

    from thymio_bt.viz.live import LiveServer

    server = LiveServer(0)
    try:
        for host, path, status in (
            ("evil.example", "/ticks?from=0", 403),  # DNS rebinding
            ("127.0.0.1", "/ticks?from=x", 400),
            ("localhost", "/../etc/passwd", 404),
            ("127.0.0.1", "/", 503),  # no run yet
            ("127.0.0.1", "/ticks?from=0", 200),
        ):
            connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
            connection.request("GET", path, headers={"Host": f"{host}:{server.port}"})
            assert connection.getresponse().status == status, (host, path)
            connection.close()
    finally:
        server.close()
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        command = ["run", "square", "-q", "--web", str(busy.getsockname()[1])]
        done = subprocess.run([sys.executable, "-m", "thymio_bt", *command], capture_output=True, text=True)
    assert done.returncode == 2 and "error: --web: cannot serve on 127.0.0.1:" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_an_mcap_log_gives_the_same_page(browser, part12, tmp_path):
    """``view`` reads any log the project reads: the rosbag2 (MCAP) export of the run shows what
    the JSON lines log shows (a tick without /odom has no speeds: a gap, not an error)."""
    from _require import module

    module("rosbags")
    log, page = part12
    bag = tmp_path / "run.mcap"
    for args in (["export", str(log), "-o", str(bag)], ["view", str(bag)]):
        done = subprocess.run([sys.executable, "-m", "thymio_bt", *args], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
    samples = read_log(log).samples
    for fragment in ("#t=4.5", "#t=12.3", "#tick=300"):
        shown = []
        for path in (page, tmp_path / "run.html"):
            tab = browser.open(path.as_uri() + fragment)
            assert tab.problems() == []
            shown.append(tab.evaluate(CONTRACT))
            tab.close()
        assert shown[0] == shown[1], fragment
    assert shown[1] == expected(next(s for s in samples if s["tick"] == 300))


def test_two_runs_in_different_mazes_are_drawn_side_by_side(browser, part12, tmp_path):
    log, _ = part12
    square = tmp_path / "square.jsonl"
    record("square", square)
    page = write_page([read_log(square), read_log(log)], tmp_path / "two.html", {"time": 0.0, "tick": 1, "reason": "x"})
    tab = browser.open(page.as_uri() + "#t=10")
    assert tab.problems() == []
    dom = tab.evaluate(
        """({mazes: [...document.querySelectorAll('svg.maze')].map(s => s.querySelectorAll('.robot').length),
        trees: [...document.querySelectorAll('.tree')].map(t => t.querySelectorAll('[data-node]').length),
        divergence: document.documentElement.dataset.divergence})"""
    )
    assert dom == {"mazes": [1, 1], "trees": [4, 16], "divergence": "0"}
    tab.close()


def test_a_log_cut_before_its_first_tick_shows_the_maze_and_the_tree(browser, part12, tmp_path):
    log, _ = part12
    cut = tmp_path / "cut.jsonl"
    cut.write_text(log.read_text().splitlines()[0] + "\n")
    page = write_page([read_log(cut)], tmp_path / "cut.html")
    tab = browser.open(page.as_uri() + "#tick=3")
    for name in ("ArrowRight", "]", "End", " ", "z"):
        tab.evaluate(f"document.dispatchEvent(new KeyboardEvent('keydown', {{key: {json.dumps(name)}}}))")
    assert tab.problems() == []
    shown = tab.evaluate(CONTRACT)
    assert (shown["time"], shown["pose"], set(shown["nodes"].values())) == ("0", "", {"INVALID"})
    assert len(shown["nodes"]) == 16
    tab.close()
