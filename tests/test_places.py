"""Place conditions (OutsideMaze, InRegion) on small generated worlds, and the wall followers made
of primitives (examples/wall_follower_*.yaml) leaving generated perfect mazes by their exit."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError

from thymio_bt.backends.sim import Simulation
from thymio_bt.behaviours.base import Context
from thymio_bt.behaviours.flow.ticking import tick
from thymio_bt.behaviours.places import InRegion, InRegionParams, OutsideMaze, OutsideMazeParams
from thymio_bt.errors import UserError
from thymio_bt.maze import Maze
from thymio_bt.maze.generate import perfect_maze
from thymio_bt.maze.model import Area
from thymio_bt.mission import load_mission
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.placement import MazeShapes
from thymio_bt.run.runner import Run, RunResult
from thymio_bt.testing import run_tree, world

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = {hand: ROOT / "examples" / f"wall_follower_{hand}.yaml" for hand in ("left", "right")}
NOISE = {"noise.wheel": "0.027", "noise.odometry": "0.01", "noise.range_sd": "0.001"}

#: a corridor open at its east end: the walls' box ends at x = 0.405
OPEN_END = """
+--+--+
|>
+--+--+
"""


def drive_then(distance: float, condition: object) -> dict[str, object]:
    """Drive ``distance`` straight on from the start, then answer ``condition``."""
    return {"sequence": [{"MoveDistance": {"distance": distance}}, condition]}


# ------------------------------------------------------------------ OutsideMaze
def test_outside_maze_fails_inside_the_maze():
    result = run_tree("OutsideMaze", world("corridor"))
    assert result.status == "FAILURE"
    assert result.failed_path == "OutsideMaze"


@pytest.mark.parametrize(
    ("distance", "margin", "status"),
    [
        (0.2, 0.0, "FAILURE"),  # base_link at x = 0.3: still inside the walls' box
        (0.34, 0.05, "FAILURE"),  # 3.5 cm out: within the margin
        (0.34, 0.02, "SUCCESS"),  # 3.5 cm out: beyond the margin
        (0.5, 0.05, "SUCCESS"),  # a cell out
    ],
)
def test_outside_maze_needs_base_link_beyond_the_margin(distance, margin, status):
    result = run_tree(drive_then(distance, {"OutsideMaze": {"margin": margin}}), world(OPEN_END), seconds=20)
    assert result.status == status, result.reason
    assert result.final_pose.x == pytest.approx(0.1 + distance, abs=0.002)


def test_outside_maze_ends_a_loop_once_out():
    tree = {"repeat": {"until": "OutsideMaze", "do": {"MoveDistance": {"distance": "10cm"}}}}
    result = run_tree(tree, world(OPEN_END), seconds=30)
    assert (result.status, result.collisions) == ("SUCCESS", 0)
    # 0.405 + 0.05 is first passed at x = 0.5: four 10 cm steps, not one more
    assert result.final_pose.x == pytest.approx(0.5, abs=0.002)
    assert sum(1 for e in result.events if e["kind"] == "behaviour_end" and e["name"] == "MoveDistance") == 4


def test_outside_maze_without_bounds_is_invalid_input():
    sim = Simulation(world("corridor"), spawn=Pose(0.1, 0.1, 0.0))
    node = OutsideMaze("out", OutsideMazeParams(), Context(robot=sim, entities=sim))  # no bounds
    tick(node)
    assert node.status.name == "FAILURE"
    assert node.failure is not None and node.failure[0] == "INVALID_INPUT"


# ------------------------------------------------------------------ InRegion
@pytest.mark.parametrize(
    ("params", "status"),
    [
        ({"rect": [0.6, 0.4, 0.8, 0.6]}, "SUCCESS"),
        ({"rect": [0.7, 0.5, 0.9, 0.9]}, "SUCCESS"),  # on the corner: borders count
        ({"rect": [0.75, 0.4, 0.9, 0.6]}, "FAILURE"),
        ({"centre": [0.73, 0.54], "radius": "51mm"}, "SUCCESS"),
        ({"centre": [0.73, 0.54], "radius": "49mm"}, "FAILURE"),
    ],
)
def test_in_region_reads_base_link_against_a_rectangle_or_a_disc(params, status):
    result = run_tree({"InRegion": params}, world("arena"))  # base_link at (0.7, 0.5)
    assert result.status == status


def test_in_region_follows_the_robot():
    region = {"InRegion": {"rect": [0.95, 0.4, 1.1, 0.6]}}
    assert run_tree(region, world("arena")).status == "FAILURE"
    assert run_tree(drive_then(0.3, region), world("arena"), seconds=20).status == "SUCCESS"


def with_goal(maze: Maze, corner: tuple[float, float], other: tuple[float, float]) -> Maze:
    return maze.model_copy(update={"goal": [Area.model_validate({"from": corner, "to": other})]})


def test_in_region_without_a_region_is_the_mazes_goal():
    arena = world("arena")
    assert run_tree("InRegion", with_goal(arena, (0.6, 0.4), (0.8, 0.6))).status == "SUCCESS"
    assert run_tree("InRegion", with_goal(arena, (0.0, 0.0), (0.4, 0.4))).status == "FAILURE"
    result = run_tree("InRegion", arena)  # no goal in the maze, none given
    assert (result.status, result.code) == ("FAILURE", "INVALID_INPUT")


@pytest.mark.parametrize(
    "params",
    [
        {"rect": [0, 0, 1, 1], "centre": [0.5, 0.5]},
        {"rect": [1, 0, 0, 1]},
        {"rect": [0, 1, 1, 1]},
        {"centre": [0.5, "nan"]},
        {"radius": 0},
    ],
)
def test_in_region_refuses_a_region_that_is_not_one(params):
    with pytest.raises(ValidationError):
        InRegionParams.model_validate(params)


def test_a_mission_with_a_bad_region_is_a_user_error():
    with pytest.raises(UserError, match="rect"):
        run_tree({"InRegion": {"rect": [1, 0, 0, 1]}}, world("arena"))


@pytest.mark.parametrize("loop", ["repeat", "retry"])
@pytest.mark.parametrize(
    "node", [{"OutsideMaze": {}}, {"InRegion": {"centre": [0.7, 0.5]}}, {"InRegion": {"centre": [0.1, 0.1]}}]
)
def test_the_conditions_answer_again_each_time_they_are_ticked(loop, node):
    force = "force_success" if loop == "repeat" else "force_failure"
    tree = {loop: {"times": 3, "do": {force: node}}}
    result = run_tree(tree, world("arena"), seconds=5)
    assert result.status == ("SUCCESS" if loop == "repeat" else "FAILURE"), result.reason
    assert next(s["ticks"] for p, s in result.node_stats.items() if p.endswith(next(iter(node)))) == 3


def test_both_conditions_are_registered_with_their_parameters():
    from thymio_bt.mission import default_registry

    assert default_registry()["OutsideMaze"] is OutsideMaze and default_registry()["InRegion"] is InRegion
    assert OutsideMaze.Params is OutsideMazeParams and InRegion.Params is InRegionParams
    schema = (ROOT / "schema" / "mission.schema.json").read_text()
    assert '"OutsideMaze"' in schema and '"InRegion"' in schema


# ------------------------------------------------------------------ wall followers of primitives
def exit_gap(maze: Maze, cell: float = 0.2) -> tuple[float, float, float]:
    """A generated perfect maze's exit: (x from, x to, y) of the gap in its top wall."""
    top = max(max(w.start[1], w.end[1]) for w in maze.walls)
    covered = [
        (min(w.start[0], w.end[0]), max(w.start[0], w.end[0]))
        for w in maze.walls
        if abs(w.start[1] - top) < 1e-6 and abs(w.end[1] - top) < 1e-6
    ]
    cols = round(max(max(w.start[0], w.end[0]) for w in maze.walls) / cell)
    (gap,) = [c for c in range(cols) if not any(x0 <= (c + 0.5) * cell <= x1 for x0, x1 in covered)]
    return gap * cell, (gap + 1) * cell, top


def run_example(hand: str, maze: Maze, tmp_path: Path, robot: str = "course", noisy: bool = False) -> RunResult:
    maze_file = tmp_path / f"{maze.name}.yaml"
    maze_file.write_text(yaml.safe_dump(maze.to_yaml_dict(), sort_keys=False))
    overrides = {"--robot": robot, **(NOISE if noisy else {})}
    return Run(load_mission(EXAMPLES[hand], overrides, maze=maze_file, start="start"), seed=0).run()


def assert_left_by_the_exit(result: RunResult, maze: Maze) -> None:
    """SUCCESS without touching a wall, base_link out of the maze (ground truth), through the gap,
    and stopped there: one cell out, not wandering on."""
    assert result.status == "SUCCESS", f"{result.code} at {result.failed_path}: {result.reason}"
    assert result.collisions == 0
    xmin, ymin, xmax, ymax = MazeShapes.of(maze).bounds
    x0, x1, top = exit_gap(maze)
    out = next((x, y) for _, x, y, _ in result.trajectory if not (xmin <= x <= xmax and ymin <= y <= ymax))
    assert x0 < out[0] < x1 and out[1] > top, f"left the maze at {out}, not through the gap"
    final = result.final_pose
    assert final is not None
    assert x0 < final.x < x1 and top + 0.08 < final.y < top + 0.17


@pytest.mark.parametrize("hand", ["left", "right"])
def test_the_course_maze_is_left_through_its_top_gap(hand):
    result = Run(load_mission(EXAMPLES[hand])).run()  # its expect: one cell above the gap, no collision
    assert (result.status, result.collisions, result.expectations) == ("SUCCESS", 0, [])
    assert -0.4 < result.final_pose.x < -0.2 and 0.25 < result.final_pose.y < 0.4
    assert "WallFollow" not in yaml.safe_dump(yaml.safe_load(EXAMPLES[hand].read_text())["tree"])


@pytest.mark.parametrize("noisy", [False, True], ids=["exact", "noisy"])
@pytest.mark.parametrize(("size", "seed"), [(4, 1), (5, 2), (6, 3)])
@pytest.mark.parametrize("hand", ["left", "right"])
def test_the_examples_leave_generated_perfect_mazes(hand, size, seed, noisy, tmp_path):
    maze = perfect_maze(size, size, seed)
    assert_left_by_the_exit(run_example(hand, maze, tmp_path, noisy=noisy), maze)


def test_a_maze_without_an_exit_is_never_left(tmp_path):
    """The end condition is the way out, not a count of cells: closed, the follower goes round and round."""
    closed = perfect_maze(3, 3, 4, exit_cell=(9, 9))  # no gap: the exit is off the grid
    assert len(closed.walls) == len(perfect_maze(3, 3, 4).walls) + 1
    loaded = load_mission(EXAMPLES["left"], {"time_limit": "120"}, maze=write(closed, tmp_path), start="start")
    result = Run(loaded).run()
    assert (result.status, result.collisions) == ("TIMEOUT", 0)


def write(maze: Maze, folder: Path) -> Path:
    path = folder / "maze.yaml"
    path.write_text(yaml.safe_dump(maze.to_yaml_dict(), sort_keys=False))
    return path


@pytest.mark.slow
@pytest.mark.parametrize("noisy", [False, True], ids=["exact", "noisy"])
@pytest.mark.parametrize("robot", ["course", "enki", "real"])
@pytest.mark.parametrize("hand", ["left", "right"])
def test_the_examples_leave_ten_mazes_of_each_size(hand, robot, noisy, tmp_path):
    failed = []
    for size in (4, 5, 6):
        for seed in range(10):
            maze = perfect_maze(size, size, seed)
            try:
                assert_left_by_the_exit(run_example(hand, maze, tmp_path, robot, noisy), maze)
            except AssertionError as exc:
                failed.append(f"{maze.name}: {exc}")
    assert not failed, "\n".join(failed)
