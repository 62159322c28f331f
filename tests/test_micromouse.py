"""Micromouse contest mazes: the public text format read with located errors, the coordinates of the
issue (origin at the bottom-left post, y up), the S spawn facing its opening, the G cells as the
maze's goal region reported by runs, and generated mazes of the contest kind."""

import math
from collections import deque
from pathlib import Path

import pytest
from click.testing import CliRunner

from thymio_bt.cli import main
from thymio_bt.errors import UserError
from thymio_bt.maze import load_maze
from thymio_bt.maze.generate import contest_maze
from thymio_bt.maze.micromouse import CELL, parse_micromouse, read_micromouse, to_text
from thymio_bt.mission import load_mission
from thymio_bt.run.runner import Run

ROOT = Path(__file__).resolve().parents[1]

EXAMPLE = f"{ROOT}/mazes/micromouse_4x4.txt"


def test_the_example_reads_in_the_issues_coordinates():
    maze = read_micromouse(EXAMPLE)
    assert maze.bounds() == pytest.approx((-0.006, -0.006, 4 * CELL + 0.006, 4 * CELL + 0.006))
    start = maze.spawns["start"]
    assert (start.x, start.y, start.yaw) == pytest.approx((0.09, 0.09, math.pi / 2))  # S opens north
    assert [(a.start, a.end) for a in maze.goal] == [((0.0, 0.54), (0.18, 0.72))]  # G: cell (0, 3)
    walls = {(w.start, w.end) for w in maze.walls}
    assert ((0.18, 0.0), (0.18, 0.18)) in walls  # the wall east of S
    assert ((0.0, 0.36), (0.18, 0.36)) in walls  # the line 'o---o---o---o   o' is y = 2 cells
    assert all(w.thickness == 0.012 for w in maze.walls)


def test_text_round_trips():
    text = Path(EXAMPLE).read_text()
    assert to_text(parse_micromouse(text)) == text


@pytest.mark.parametrize(
    "text, line, col, message",
    [
        ("o---o---o\n|   |   |\no   o\n| S     |\no---o---o\n", 3, 9, "a post 'o' is missing"),
        ("o---o---o\n| S |   |   x\no---o---o\n", 2, 10, "this line has 13 characters"),
        ("o---o---o\n|       |\no---o---o\n", 1, 1, "no start cell 'S'"),
        ("o---o---o\n| S      \no---o---o\n", 2, 9, "the outline is open"),
        ("o---o   o\n| S     |\no---o---o\n", 1, 6, "the outline is open"),
        ("o---o---o\n| S   X |\no---o---o\n", 2, 7, "unexpected 'X' in a cell"),
        ("o---o---o\n| S | S |\no---o---o\n", 2, 7, "a second start cell"),
        ("o--o\n", 1, 1, "not a micromouse maze"),
    ],
)
def test_broken_mazes_are_located(tmp_path, text, line, col, message):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(UserError) as err:
        read_micromouse(path)
    problem = err.value.problems[0]
    assert message in problem.message and (problem.line, problem.column) == (line, col), str(err.value)
    result = CliRunner().invoke(main, ["validate", str(path)])
    assert result.exit_code == 2 and f"bad.txt:{line}:{col}" in result.output


def reachable(cells, start):
    seen, todo = {start}, deque([start])
    while todo:
        i, j = todo.popleft()
        for side, (di, dj) in zip("NESW", ((0, 1), (1, 0), (0, -1), (-1, 0)), strict=True):
            nxt = (i + di, j + dj)
            if side in cells.open_sides(i, j) and nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


@pytest.mark.parametrize("seed", range(5))
def test_generated_contest_mazes_have_the_contests_shape(seed):
    cells = contest_maze(seed)
    assert (cells.cols, cells.rows) == (16, 16) and cells.goal == {(7, 7), (8, 7), (7, 8), (8, 8)}
    assert cells.open_sides(0, 0) == ["N"]
    assert len(reachable(cells, cells.start)) == 256  # every cell reachable
    entrances = sum(
        1
        for i, j in cells.goal
        for s in cells.open_sides(i, j)
        if (i + {"E": 1, "W": -1}.get(s, 0), j + {"N": 1, "S": -1}.get(s, 0)) not in cells.goal
    )
    assert entrances == 1
    passages = sum(len(cells.open_sides(i, j)) for i in range(16) for j in range(16)) // 2
    assert passages > 255  # loops: more than a tree
    assert parse_micromouse(to_text(cells)) == cells


def test_a_run_reports_when_it_reaches_the_goal(tmp_path):
    maze = tmp_path / "tiny.txt"
    maze.write_text("o---o---o\n| G     |\no   o---o\n| S     |\no---o---o\n")
    mission = tmp_path / "m.yaml"
    mission.write_text(f"maze: {maze}\nstart: start\ntree:\n  MoveDistance: {{distance: 18cm}}\n")
    assert load_maze(maze).goal
    result = Run(load_mission(mission)).run()
    assert result.status == "SUCCESS" and result.report()["goal"]["reached"]
    assert 0 < result.report()["goal"]["t"] <= result.sim_time
    mission.write_text(f"maze: {maze}\nstart: start\ntree:\n  MoveDistance: {{distance: 5cm}}\n")
    assert Run(load_mission(mission)).run().report()["goal"] == {"reached": False, "t": None}


def test_maze_import_writes_the_maze_format_with_its_goal(tmp_path):
    out = tmp_path / "m.yaml"
    result = CliRunner().invoke(main, ["maze", "import", EXAMPLE, "--cell", "0.2", "-o", str(out)])
    assert result.exit_code == 0, result.output
    maze = load_maze(out)
    assert [(a.start, a.end) for a in maze.goal] == [((0.0, 0.6), (0.2, 0.8))] and maze.spawns["start"].x == 0.1
