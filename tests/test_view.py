"""The live window (run --view, replay --view), offscreen through SDL's dummy video driver."""

import json
import sys
from pathlib import Path

import _require
import numpy as np
import pytest

from thymio_bt.errors import UserError
from thymio_bt.logs import read_log
from thymio_bt.logs.recording import Recorder
from thymio_bt.maze import Maze
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run
from thymio_bt.testing import world
from thymio_bt.viz import window
from thymio_bt.viz.window import Frame, Viewer, live_hook, replay

ROOT = Path(__file__).resolve().parents[1]

FAST = 1e9  # a speed-up at which the pacing never waits


@pytest.fixture
def pg(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    return _require.module("pygame")


def _key(pg, key):
    pg.event.post(pg.event.Event(pg.KEYDOWN, key=key))


def _colours(pg, path):
    pixels = pg.surfarray.array3d(pg.image.load(str(path))).reshape(-1, 3).astype(np.int64)
    packed = np.unique(pixels @ np.array([1 << 16, 1 << 8, 1]))
    return {(int(c) >> 16, (int(c) >> 8) & 255, int(c) & 255) for c in packed}


def _view_with_screenshot(run, tick, screenshot, stop=False):
    """Run ``run`` in a live view, saving the window after ``tick`` (and ending the run there with ``stop``)."""
    view = live_hook(run, FAST, max_fps=None)

    def hook(r):
        view(r)
        if r.ticks == tick:
            view.viewer.save(screenshot)
            if stop:
                raise window.StopRun("enough")

    return view, run.run(on_tick=hook)


def test_a_live_view_draws_every_tick_and_leaves_the_run_unchanged(pg, tmp_path):
    plain = Run(load_mission(f"{ROOT}/missions/square.yaml")).run()
    screenshot = tmp_path / "frame.png"
    view, result = _view_with_screenshot(Run(load_mission(f"{ROOT}/missions/square.yaml")), 60, screenshot)
    view.finish(result)
    assert view.viewer.frames == result.ticks + 1  # every tick, and the outcome
    assert result.final_pose == plain.final_pose and result.trajectory == plain.trajectory
    colours = _colours(pg, screenshot)
    assert len(colours) > 5 and {window.WALL, window.ROBOT_FILL, window.TRAIL} <= colours


class _Clock:
    """The viewer's wall clock, faked: ``sleep`` moves it on at once."""

    def __init__(self) -> None:
        self.now = 1000.0

    def perf_counter(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        assert seconds > 0
        self.now += seconds


def test_frames_come_no_earlier_than_their_time_divided_by_the_speedup(pg, monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(window, "time", clock)
    with_view = Viewer(Maze(), speedup=20, max_fps=None)
    shown_at = []
    for tick in range(6):
        with_view.show(Frame(tick * 0.1, {"x": 0.0, "y": 0.0, "yaw": 0.0}, {}))
        shown_at.append(clock.now - 1000.0)
    with_view.close()
    assert shown_at == pytest.approx([tick * 0.1 / 20 for tick in range(6)])  # each at its time, no earlier


def test_rays_are_drawn_at_the_pose_hit_ones_in_red_with_y_up(pg, tmp_path):
    viewer = Viewer(world("corridor"), FAST, max_fps=None)
    assert viewer.to_screen(0.0, 0.2)[1] < viewer.to_screen(0.0, 0.0)[1]  # y up
    pose = {"x": 0.1, "y": 0.1, "yaw": 0.0}
    viewer.show(Frame(0.0, pose, {"front_center": None}))
    assert window.RAY_HIT not in _colours(pg, viewer.save(tmp_path / "free.png"))
    viewer.show(Frame(0.1, pose, {"front_center": 0.05}))
    hit = viewer.to_screen(0.1 + 0.0557 + 0.05, 0.1)
    assert tuple(viewer.screen.get_at((round(hit[0]), round(hit[1]))))[:3] == window.RAY_HIT
    viewer.close()


def test_the_view_grows_when_the_robot_leaves_the_maze(pg):
    viewer = Viewer(world("corridor"), FAST, max_fps=None)
    viewer.show(Frame(0.0, {"x": 2.0, "y": -1.0, "yaw": 0.0}, {}))
    x, y = viewer.to_screen(2.0, -1.0)
    width, height = viewer.screen.get_size()
    assert 0 < x < width and window.BAR_HEIGHT < y < height
    viewer.close()


def test_replay_of_a_log_draws_its_frames(pg, tmp_path):
    run = Run(load_mission(f"{ROOT}/missions/square.yaml"))
    recorder = Recorder(log_path=tmp_path / "run.jsonl", keep=False)
    recorder.finish(run.run(on_tick=recorder))
    recording = read_log(tmp_path / "run.jsonl")
    viewer = replay(recording, FAST, max_fps=None)
    assert viewer.shown == len(recording.samples) and viewer.frames == len(recording.samples) + 1


def test_pause_waits_and_single_step_advances_one_tick(pg):
    viewer = Viewer(Maze(), FAST, max_fps=None)
    pose = {"x": 0.0, "y": 0.0, "yaw": 0.0}
    for key in (pg.K_SPACE, pg.K_n, pg.K_RIGHT):
        _key(pg, key)
    viewer.show(Frame(0.0, pose, {}))  # SPACE pauses, N steps past this tick
    viewer.show(Frame(0.1, pose, {}))  # RIGHT steps past this one
    assert viewer.paused and viewer.shown == 2
    pg.time.set_timer(pg.event.Event(pg.KEYDOWN, key=pg.K_SPACE), 150, 1)
    viewer.show(Frame(0.2, pose, {}))  # no key queued: waits, paused, until SPACE resumes
    assert not viewer.paused  # it returned only once SPACE (150 ms later) had come
    viewer.close()


def test_plus_and_minus_change_the_speedup(pg):
    viewer = Viewer(Maze(), 100.0, max_fps=None)
    for key in (pg.K_PLUS, pg.K_EQUALS, pg.K_MINUS):
        _key(pg, key)
    viewer.show(Frame(0.0, None, {}))
    assert viewer.speedup == 200.0
    viewer.close()


@pytest.mark.parametrize("close", ["q", "escape", "window"])
def test_closing_the_window_stops_a_live_run(pg, close):
    run = Run(load_mission(f"{ROOT}/missions/square.yaml"))
    view = live_hook(run, FAST)
    if close == "window":
        pg.event.post(pg.event.Event(pg.QUIT))
    else:
        _key(pg, {"q": pg.K_q, "escape": pg.K_ESCAPE}[close])
    result = run.run(on_tick=view)
    assert run.ticks == 1
    assert (result.status, result.code, result.reason) == ("FAILURE", "STOPPED", "the viewer window was closed")
    assert result.failed_path and not run.backend.command().linear  # the running behaviour stopped the robot


def test_a_replay_closed_early_just_ends(pg, tmp_path):
    run = Run(load_mission(f"{ROOT}/missions/square.yaml"))
    recorder = Recorder()
    recording = recorder.finish(run.run(on_tick=recorder))
    pg.display.init()  # to queue the key before replay opens its window
    _key(pg, pg.K_q)
    assert replay(recording, FAST).shown == 1


def test_without_pygame_the_error_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)
    with pytest.raises(UserError, match=r"pygame is not installed \(hint: pip install 'thymio-bt\[viz\]', or in a"):
        Viewer(Maze())


def test_a_speedup_must_be_positive():
    with pytest.raises(UserError, match="speed-up must be > 0"):
        Viewer(Maze(), speedup=0)


def test_run_and_replay_with_view_run_offscreen(pg, tmp_path):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    log = tmp_path / "run.jsonl"
    result = CliRunner().invoke(
        main, ["run", f"{ROOT}/missions/square.yaml", "--view", "--speedup", "1e9", "--log", str(log)]
    )
    assert result.exit_code == 0, result.output
    result = CliRunner().invoke(main, ["replay", str(log), "--view", "--speedup", "1e9"])
    assert result.exit_code == 0 and "nothing to draw" not in result.output


def test_closing_the_window_still_writes_the_report_and_the_log(pg, tmp_path, monkeypatch):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    show = Viewer.show

    def close_at_the_fifth_frame(self, frame):
        if self.shown == 4:
            pg.event.post(pg.event.Event(pg.QUIT))
        return show(self, frame)

    monkeypatch.setattr(Viewer, "show", close_at_the_fifth_frame)
    report, log = tmp_path / "report.json", tmp_path / "run.jsonl"
    result = CliRunner().invoke(
        main,
        [
            "run",
            f"{ROOT}/missions/square.yaml",
            "--view",
            "--speedup",
            "1e9",
            "--report",
            str(report),
            "--log",
            str(log),
        ],
    )
    assert result.exit_code == 1 and "STOPPED" in result.output
    assert json.loads(report.read_text())["code"] == "STOPPED"
    assert read_log(log).end["code"] == "STOPPED" and len(read_log(log).samples) == 5


def test_view_without_pygame_is_a_user_error(monkeypatch):
    from click.testing import CliRunner

    from thymio_bt.cli import main

    monkeypatch.setitem(sys.modules, "pygame", None)
    monkeypatch.delenv("SDL_VIDEODRIVER", raising=False)
    monkeypatch.setenv("DISPLAY", ":0")  # a display: pygame is what is missing
    result = CliRunner().invoke(main, ["run", f"{ROOT}/missions/square.yaml", "--view"])
    assert result.exit_code == 2 and "pip install 'thymio-bt[viz]'" in result.output
    assert "in a checkout: pip install -e '.[viz]'" in result.output  # the PyPI form fails there


def _headless(**env):
    """The environment of a shell with no display (nor SDL driver chosen), plus ``env``."""
    import os

    clean = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "SDL_VIDEODRIVER")}
    return {**clean, **env}


@pytest.mark.parametrize("command", ["run", "replay"])
def test_view_without_a_display_ends_at_once_naming_what_to_use(tmp_path, command):
    import subprocess

    args = ["run", "square", "--set", "time_limit=5", "--report", "r.json"] if command == "run" else ["replay", "x"]
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", *args, "--view"],
        cwd=tmp_path,
        env=_headless(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("error: no display: --view needs a window, and DISPLAY and WAYLAND_DISPLAY")
    assert "--plot" in done.stderr and "--gif" in done.stderr and "Traceback" not in done.stderr
    assert ("--groot2" in done.stderr) == (command == "run")  # replay has no Groot2 monitor
    assert not (tmp_path / "r.json").exists()  # refused before the run


def test_view_refuses_sdl_falling_back_to_its_offscreen_driver(tmp_path):
    import subprocess

    _require.module("pygame")
    done = subprocess.run(
        [sys.executable, "-m", "thymio_bt", "run", "square", "--set", "time_limit=5", "--view"],
        cwd=tmp_path,
        env=_headless(DISPLAY=":9999"),  # a display that does not answer: SDL draws offscreen
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2 and "error: no display: --view needs a window, and SDL found none" in done.stderr


def test_a_mapping_mission_shows_its_map_live(pg, tmp_path):
    screenshot = tmp_path / "map.png"
    view, _ = _view_with_screenshot(Run(load_mission(f"{ROOT}/missions/micromouse.yaml")), 400, screenshot, stop=True)
    view.viewer.close()
    assert view.cells is not None and view.cells.wall_segments()
    assert {window.MAP_WALL, window.MAP_VISITED} <= _colours(pg, screenshot)
