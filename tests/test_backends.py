"""Backends by name (--backend NAME, --backend-opt, a mission's backend: block) and robot models (--robot)."""

import dataclasses
import math
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from thymio_bt.backends import BUILTIN, backend_kind
from thymio_bt.errors import UserError
from thymio_bt.mission import load_mission
from thymio_bt.robot.model import COURSE, ENKI, ROBOTS
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]


def test_unknown_backend_names_the_nearest():
    with pytest.raises(UserError, match="no backend named 'simm'.*did you mean 'sim'"):
        backend_kind("simm")


def test_backend_options_are_validated_with_a_hint():
    mission = load_mission(f"{ROOT}/missions/square.yaml")
    with pytest.raises(UserError, match="has no option 'physics'.*did you mean 'physics_hz'"):
        backend_kind("sim").create(mission, 0, {"physics": "200"})
    with pytest.raises(UserError, match="option 'physics_hz'.*greater than or equal to 50"):
        backend_kind("sim").create(mission, 0, {"physics_hz": "5"})


def test_each_kind_reads_its_options_model_from_its_own_backend_and_a_run_imports_only_its_own():
    assert {name: kind.options_model().__module__ for name, kind in BUILTIN.items()} == {
        "sim": "thymio_bt.backends.sim.options",
        "tdm": "thymio_bt.backends.real.options",
        "aseba": "thymio_bt.backends.real.options",
        "playground": "thymio_bt.backends.playground.options",
        "ros2": "thymio_bt.backends.ros2.options",
    }
    code = (
        "import sys\nfrom thymio_bt.backends import backend_kind\nfrom thymio_bt.mission import load_mission\n"
        "backend_kind('sim').create(load_mission('maze_part1_2'), seed=0, options={'physics_hz': '200'})\n"
        "print(sorted(m for m in sys.modules if m.endswith('.options')))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["['thymio_bt.backends.sim.options']"]


def test_sim_backend_takes_physics_rate_and_robot_model():
    mission = load_mission(f"{ROOT}/missions/square.yaml", {"robot": "enki"})
    sim = backend_kind("sim").create(mission, 0, {"physics_hz": "200"})
    assert sim.model is ENKI and sim.config.physics_hz == 200.0


def test_a_mission_names_its_backend_and_robot(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(
        textwrap.dedent("""\
        maze: arena
        start: [0.6, 0.6, 0]
        robot: enki
        backend: {name: sim, physics_hz: 200}
        tree: {Wait: {seconds: 1}}
        """)
    )
    mission = load_mission(path)
    assert (mission.robot, mission.backend, mission.backend_options) == ("enki", "sim", {"physics_hz": 200})
    run = Run(mission)
    assert run.backend.model is ENKI and run.backend.config.physics_hz == 200.0


@pytest.mark.parametrize(
    "text, message",
    [
        ("robot: enkki", "robot must be one of course, enki, real or a profile file (.yaml), got 'enkki'"),
        ("backend: [sim]", "backend must be a name or a mapping with 'name'"),
    ],
)
def test_bad_robot_or_backend_in_a_mission_is_located(tmp_path, text, message):
    path = tmp_path / "m.yaml"
    path.write_text(f"maze: arena\nstart: [0.6, 0.6, 0]\n{text}\ntree: {{wait: {{seconds: 1}}}}\n")
    with pytest.raises(UserError) as info:
        load_mission(path)
    assert message in str(info.value) and f"{path}:3:" in str(info.value)


def test_robot_models_differ_where_robots_do():
    assert set(ROBOTS) == {"course", "enki", "real"}
    assert COURSE.range_max == 0.0975 and ENKI.range_max == 0.14
    assert ENKI.wheel_separation == 0.094 and ENKI.max_wheel_speed == 0.166
    assert ENKI.sensor("front_center").x == pytest.approx(0.0552)  # 7.95 cm ahead of Enki's axle
    for model in ROBOTS.values():
        pose = model.base_of(*model.axle_of(load_mission(f"{ROOT}/missions/square.yaml").start))
        assert pose.x == pytest.approx(load_mission(f"{ROOT}/missions/square.yaml").start.x, abs=1e-12)


def test_the_robot_model_changes_the_simulated_robot():
    def final_proximity(robot):
        result = Run(load_mission(f"{ROOT}/missions/maze_part1_2.yaml", {"robot": robot})).run()
        assert result.status == "SUCCESS"
        return result.final_proximity

    course, enki = final_proximity("course"), final_proximity("enki")
    # Enki's ±40° sensors sit elsewhere and see the side walls at other distances
    assert course["front_left"] != pytest.approx(enki["front_left"], abs=1e-3)
    assert course["front_center"] == pytest.approx(enki["front_center"], abs=1e-3)  # both stop at 5 cm


def test_cli_lists_backends_and_robot_models():
    out = subprocess.run(
        [sys.executable, "-m", "thymio_bt.cli", "backends"], capture_output=True, text=True, check=True
    ).stdout
    for name in [*BUILTIN, *ROBOTS, "physics_hz"]:
        assert name in out


def test_cli_backend_errors_exit_2_without_traceback():
    for args in (
        ["--backend", "nope"],
        ["--backend-opt", "physics=1"],
        ["--backend-opt", "novalue"],
        ["--robot", "nope"],
    ):
        done = subprocess.run(
            [sys.executable, "-m", "thymio_bt.cli", "run", f"{ROOT}/missions/square.yaml", *args],
            capture_output=True,
            text=True,
        )
        assert done.returncode == 2 and "Traceback" not in done.stderr and done.stderr.startswith("error:"), args


def test_the_backend_base_serves_requests_through_two_hooks():
    from thymio_bt.robot.interface import Backend, Pose, RequestState

    class Tiny(Backend):
        """A backend with one robot slot: just enough to check the request loop."""

        def __init__(self):
            super().__init__()
            self.present, self.placed = False, []

        def _remove(self, name):
            if not self.present:
                return f"no entity named '{name}'"
            self.present = False
            return None

        def _place_entity(self, name, pose):
            self.present = True
            self.placed.append(pose)
            return None

        def spawn_problem(self, name, pose):
            return "taken" if self.present else None

        drive = exists = proximity = pose = velocity = command = time = true_pose = advance = None

    backend = Tiny()
    first, again = backend.request_spawn("thymio", Pose(1, 2, 0)), backend.request_spawn("thymio", Pose(3, 4, 0))
    gone, missing = backend.request_delete("thymio"), backend.request_delete("thymio")
    backend.serve_requests()
    assert (first.state, again.state, gone.state, missing.state) == (
        RequestState.SUCCEEDED,
        RequestState.FAILED,
        RequestState.SUCCEEDED,
        RequestState.FAILED,
    )
    assert again.reason == "taken" and missing.reason == "no entity named 'thymio'"
    assert backend.placed == [Pose(1, 2, 0)] and backend.collisions == [] and backend.min_clearance == math.inf


def test_a_backend_that_raises_ends_the_run_failure_with_its_reason():
    from thymio_bt.backends.sim import Simulation

    class Flaky(Simulation):
        def advance(self, dt):
            if self.time() >= 1.0:
                raise OSError("serial port vanished")
            super().advance(dt)

    mission = load_mission(f"{ROOT}/missions/square.yaml")
    backend = Flaky(mission.maze)
    result = Run(mission, backend=backend).run()
    assert (result.status, result.code) == ("FAILURE", "BACKEND_ERROR")
    assert result.reason.startswith("the backend raised OSError: serial port vanished (at test_backends.py:")
    assert result.sim_time == pytest.approx(1.0) and result.failed_path


@pytest.mark.parametrize("given", [True, False], ids=["given", "made by the run"])
def test_a_run_that_cannot_be_prepared_closes_its_backend(given, monkeypatch):
    """An impossible start raises from ``Run(...)``, before any ``run()`` could close the backend: the
    constructor closes it, given or made (a Playground process or a real robot's motors would stay on)."""
    from thymio_bt.backends.sim import Simulation

    closed: list[Simulation] = []
    monkeypatch.setattr(Simulation, "close", lambda self: closed.append(self))
    from thymio_bt.geometry import Pose

    # the loader refuses this start itself: a mission made in code is checked by the run
    mission = dataclasses.replace(load_mission("maze_part1_2"), start=Pose(0.3, 0.2, 0.0))
    backend = Simulation(mission.maze) if given else None
    with pytest.raises(UserError, match="impossible start pose"):
        Run(mission, backend=backend)
    assert len(closed) == 1 and (closed[0] is backend or not given)
