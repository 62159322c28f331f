"""The figures of the README and docs/missions.md are what the code prints: the README's quick start
output, the missions page's mission table and the size of the broken-input corpus. A change that moves
one fails here, and the page is updated with it."""

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.behaviours.maze import turns_decided
from thymio_bt.cli import main
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
MISSIONS = (ROOT / "docs" / "missions.md").read_text()


def mission_row(name: str) -> str:
    return next(line for line in MISSIONS.splitlines() if line.startswith(f"| `missions/{name}.yaml`"))


@pytest.fixture(scope="module")
def runs():
    return {
        name: Run(load_mission(ROOT / "missions" / f"{name}.yaml")).run()
        for name in ("maze_part1_2", "maze_bonus", "waypoints", "waypoints_obstacles")
    }


def test_the_quick_start_output_is_what_run_prints():
    shown = re.search(r"maze_part1_2\.yaml\n```\n\n```text\n(.*?)```", README, re.S).group(1).splitlines()
    printed = CliRunner().invoke(main, ["run", str(ROOT / "missions/maze_part1_2.yaml")]).output.splitlines()
    wall = re.compile(r"\([\d.]+ s wall, [\d,]+x real time\)")  # the only figures that vary
    assert [wall.sub("", line) for line in printed[:3]] == [wall.sub("", line) for line in shown]


def test_the_mission_table_figures(runs):
    part = runs["maze_part1_2"]
    stop = next(e for e in part.events if e["kind"] == "behaviour_end" and e["name"] == "MoveUntilWall")
    assert f"stops at {stop['range']:.3f} m" in mission_row("maze_part1_2")
    pose = part.final_pose
    assert f"({pose.x:.3f}, {pose.y:.3f})" in mission_row("maze_part1_2")
    bonus = runs["maze_bonus"]
    turns = " ".join(turns_decided(bonus.events))
    assert f"turns {turns}, stops at ({bonus.final_pose.x:.3f}, {bonus.final_pose.y:.3f})" in mission_row("maze_bonus")
    assert f"5 waypoints in {runs['waypoints'].sim_time:.1f} s" in mission_row("waypoints")
    obstacles = runs["waypoints_obstacles"]
    assert (
        f"5 waypoints in {obstacles.sim_time:.1f} s, no collision, closest approach "
        f"{obstacles.min_clearance * 1000:.1f} mm"
    ) in mission_row("waypoints_obstacles")
    assert all(r.collisions == 0 for r in runs.values())


def test_the_broken_corpus_count():
    count = len(list((ROOT / "tests/broken").glob("*.yaml"))) + len(list((ROOT / "tests/broken/mazes").glob("*.yaml")))
    assert f"{count} broken missions and mazes" in MISSIONS.replace("\n", " ")
