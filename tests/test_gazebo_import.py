"""Tests of the Gazebo SDF world importer (thymio_bt.maze.gazebo) and the mazes made with it."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from thymio_bt.errors import UserError
from thymio_bt.maze import load_maze
from thymio_bt.maze.gazebo import import_world

COURSE = Path(__file__).resolve().parent / "data" / "course"  # the course package's worlds and walls
WORLDS = COURSE
MAZES = Path(__file__).resolve().parents[1] / "mazes"

GROUND = """
    <model name='ground_plane'><static>1</static>
      <link name='link'><collision name='collision'>
        <geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
      </collision></link>
    </model>"""


def link(
    name: str, pose: str, size: str = "0.61 0.01 0.1", offset: str = "0 0 0.05 0 -0 0", geometry: str | None = None
) -> str:
    """A wall link as Gazebo's building editor writes it (collision pose before the link pose)."""
    geometry = geometry or f"<box><size>{size}</size></box>"
    return f"""
      <link name='{name}'>
        <collision name='{name}_Collision'>
          <geometry>{geometry}</geometry>
          <pose>{offset}</pose>
        </collision>
        <visual name='{name}_Visual'><geometry><box><size>9 9 9</size></box></geometry></visual>
        <pose>{pose}</pose>
      </link>"""


def world(tmp_path: Path, body: str, state: str = "", name: str = "test.world") -> Path:
    path = tmp_path / name
    path.write_text(
        f"<?xml version='1.0'?>\n<sdf version='1.7'>\n  <world name='default'>{GROUND}"
        f"{body}\n{state}  </world>\n</sdf>\n"
    )
    return path


def model(name: str, pose: str, *links: str) -> str:
    return f"\n    <model name='{name}'>\n      <pose>{pose}</pose>{''.join(links)}\n    </model>"


def approx_segment(wall, start, end, tol=1e-6) -> None:
    """The wall runs start→end (in either direction)."""
    got = [wall.start, wall.end]
    want = [start, end]
    if math.dist(got[0], want[0]) > math.dist(got[0], want[1]):
        want.reverse()
    for g, w in zip(got, want, strict=True):
        assert g == pytest.approx(w, abs=tol), (wall.name, got, want)


# --- (a) composition of poses -----------------------------------------------------------------


def test_model_pose_then_link_pose(tmp_path):
    path = world(
        tmp_path,
        model(
            "maze",
            "1 2 0 0 -0 1.5707963267948966",
            link("Wall_0", "0.5 0 0 0 -0 0", "0.41 0.01 0.1"),
            link("Wall_1", "0 0 0 0 -0 1.5707963267948966", "0.21 0.01 0.1"),
        ),
    )
    maze = import_world(path)
    assert [w.name for w in maze.walls] == ["Wall_0", "Wall_1"]
    w0, w1 = maze.walls
    # the model turns the link's +x onto world +y: (1, 2) + (0, 0.5), running along y
    approx_segment(w0, (1.0, 2.3), (1.0, 2.7))
    assert w0.thickness == pytest.approx(0.01)
    # model yaw + link yaw = pi: back along x, centred on the model origin
    approx_segment(w1, (0.9, 2.0), (1.1, 2.0))
    assert maze.name == "test" and maze.source == "test.world"


def test_collision_offset_is_in_the_link_frame(tmp_path):
    # like Wall_8 / Wall_21 of the course: the box is offset along the link's own x axis
    path = world(
        tmp_path,
        model("maze", "0 0 0 0 0 0", link("Wall_8", "1 0 0 0 0 1.5707963267948966", offset="0.1 0 0.05 0 0 0")),
    )
    (wall,) = import_world(path).walls
    approx_segment(wall, (1.0, -0.2), (1.0, 0.4))


def test_long_axis_may_be_the_box_y(tmp_path):
    path = world(tmp_path, model("maze", "0 0 0 0 0 0", link("W", "0.2 0.3 0 0 0 0", "0.02 0.42 0.1")))
    (wall,) = import_world(path).walls
    approx_segment(wall, (0.2, 0.1), (0.2, 0.5))
    assert wall.thickness == pytest.approx(0.02)


def test_state_overrides_the_model_pose(tmp_path):
    state = """    <state world_name='default'>
      <model name='maze'><pose>0 0 0 0 -0 3.141592653589793</pose><scale>1 1 1</scale></model>
    </state>\n"""
    path = world(tmp_path, model("maze", "5 5 0 0 -0 0", link("W", "0.3 0 0 0 -0 0")), state)
    (wall,) = import_world(path).walls
    approx_segment(wall, (-0.6, 0.0), (0.0, 0.0))


def test_state_link_poses_are_world_poses(tmp_path):
    state = """    <state world_name='default'>
      <model name='maze'><pose>1 0 0 0 -0 0</pose>
        <link name='W'><pose>2 3 0 0 -0 1.5707963267948966</pose></link>
      </model>
    </state>\n"""
    path = world(
        tmp_path, model("maze", "0 0 0 0 0 0", link("W", "9 9 0 0 0 0", "0.41 0.01 0.1", offset="0.1 0 0 0 0 0")), state
    )
    (wall,) = import_world(path).walls
    # not composed with the model's state pose (1, 0): Gazebo sets the link's world pose
    approx_segment(wall, (2.0, 2.9), (2.0, 3.3))


def test_names_sorted_naturally_and_values_rounded(tmp_path):
    links = [link(f"Wall_{i}", f"0 {i / 10} 0 0 0 3.14159") for i in (10, 2, 1)]
    links.append(link("Wall_0", "0 0 0 0 0 1.5708", "0.21 0.01 0.1"))  # x ends at -3.7e-7 and +3.7e-7
    maze = import_world(world(tmp_path, model("maze", "0 0 0 0 0 0", *links)))
    assert [w.name for w in maze.walls] == ["Wall_0", "Wall_1", "Wall_2", "Wall_10"]
    assert maze.walls[0].start[1] < maze.walls[0].end[1]  # vertical walls point towards +y
    for w in maze.walls[1:]:
        assert w.start[0] < w.end[0]  # horizontal ones towards +x
    for w in maze.walls:
        for v in (*w.start, *w.end):
            assert v == round(v, 6)
            assert math.copysign(1.0, v) == 1.0 or v < 0, "no -0.0"
    assert maze.walls[0].start == (0.0, -0.1)


def test_pick_one_model_or_all(tmp_path):
    path = world(
        tmp_path,
        model("a", "0 0 0 0 0 0", link("W", "0 0 0 0 0 0")) + model("b", "0 1 0 0 0 0", link("W", "0 0 0 0 0 0")),
    )
    assert [w.name for w in import_world(path).walls] == ["a::W", "b::W"]
    (wall,) = import_world(path, model="b").walls
    assert wall.name == "W" and wall.start[1] == pytest.approx(1.0)
    with pytest.raises(UserError, match="no model named 'c'"):
        import_world(path, model="c")


def test_spawns_argument(tmp_path):
    path = world(tmp_path, model("maze", "0 0 0 0 0 0", link("W", "0 0 0 0 0 0")))
    maze = import_world(path, spawns={"start": (0.1, 0.1, "pi/2")}, name="m", description="d")
    assert maze.spawn("start").yaw == pytest.approx(math.pi / 2)
    assert (maze.name, maze.description) == ("m", "d")


# --- (b) user errors --------------------------------------------------------------------------


def test_missing_file(tmp_path):
    with pytest.raises(UserError, match="world file not found") as exc:
        import_world(tmp_path / "nope.world")
    assert exc.value.problems[0].file.endswith("nope.world")


def test_not_xml(tmp_path):
    path = tmp_path / "bad.world"
    path.write_text("<sdf>\n  <world>\n</sdf>\n")
    with pytest.raises(UserError, match="not a valid XML file") as exc:
        import_world(path)
    assert exc.value.problems[0].line == 3


def test_not_sdf(tmp_path):
    path = tmp_path / "x.world"
    path.write_text("<html><body/></html>")
    with pytest.raises(UserError, match="root element is <html>"):
        import_world(path)


def test_no_box_walls(tmp_path):
    with pytest.raises(UserError, match="no box walls found") as exc:
        import_world(world(tmp_path, ""))
    assert exc.value.problems[0].line == 3  # the <world> element


def test_non_box_geometry_in_a_wall_model(tmp_path):
    cylinder = "<cylinder><radius>0.1</radius><length>0.1</length></cylinder>"
    path = world(
        tmp_path,
        model("maze", "0 0 0 0 0 0", link("W", "0 0 0 0 0 0"), link("Pillar", "0 0 0 0 0 0", geometry=cylinder)),
    )
    with pytest.raises(UserError, match="link 'Pillar' has a <cylinder>") as exc:
        import_world(path)
    problem = exc.value.problems[0]
    assert (
        problem.line
        == path.read_text().splitlines().index(next(ln for ln in path.read_text().splitlines() if "<cylinder>" in ln))
        + 1
    )
    with pytest.raises(UserError, match="<plane>"):
        import_world(path, model="ground_plane")


def test_bad_numbers_point_at_the_line(tmp_path):
    path = world(tmp_path, model("maze", "0 0 zero 0 0 0", link("W", "0 0 0 0 0 0")))
    with pytest.raises(UserError, match="6 numbers") as exc:
        import_world(path)
    assert "zero" in path.read_text().splitlines()[exc.value.problems[0].line - 1]


def test_doctype_and_entities_are_refused(tmp_path):
    path = tmp_path / "lol.world"
    path.write_text(
        '<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
        ' <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">\n]>\n'
        "<sdf><world name='w'><model name='m'><link name='&lol2;'/></model></world></sdf>\n"
    )
    with pytest.raises(UserError, match="DOCTYPE and ENTITY declarations are not allowed") as exc:
        import_world(path)
    assert exc.value.problems[0].line == 2


def test_tilted_and_square_boxes(tmp_path):
    tilted = world(tmp_path, model("m", "0 0 0 0 0 0", link("W", "0 0 0 0.5 0 0")), name="t.world")
    with pytest.raises(UserError, match="tilted"):
        import_world(tilted)
    square = world(tmp_path, model("m", "0 0 0 0 0 0", link("W", "0 0 0 0 0 0", "0.1 0.1 0.1")))
    with pytest.raises(UserError, match="square"):
        import_world(square)


# --- (c) the course worlds --------------------------------------------------------------------


def course(name: str) -> tuple[Path, dict]:
    return WORLDS / f"{name}.world", json.loads((COURSE / f"{name}.json").read_text())


@pytest.mark.parametrize("name, count", [("two_parts_maze", 21), ("maze_6x6", 24)])
def test_course_world_matches_json(name, count):
    path, ref = course(name)
    maze = import_world(path)
    walls = {w["name"]: w for w in ref["walls"]}
    assert len(maze.walls) == count and {w.name for w in maze.walls} == set(walls)
    for wall in maze.walls:
        want = walls[wall.name]
        (x0, y0), (x1, y1) = wall.start, wall.end
        assert ((x0 + x1) / 2, (y0 + y1) / 2) == pytest.approx((want["cx"], want["cy"]), abs=1e-3)
        assert wall.length + wall.thickness == pytest.approx(want["length"], abs=1e-3)
        assert wall.thickness == pytest.approx(want["thickness"], abs=1e-3)
        yaw_error = (math.atan2(y1 - y0, x1 - x0) - want["yaw"] + math.pi / 2) % math.pi - math.pi / 2
        assert abs(yaw_error) < 1e-3, wall.name
    bbox = ref["bbox"]
    assert maze.bounds() == pytest.approx((bbox["xmin"], bbox["ymin"], bbox["xmax"], bbox["ymax"]), abs=1e-5)


def test_course_state_pose_and_offsets():
    path, _ = course("maze_6x6")
    walls = {w.name: w for w in import_world(path).walls}
    # <state> puts the model at (-0.2, -0.4, yaw -pi), not at its own <pose> (0.6, 0.6)
    approx_segment(walls["Wall_21"], (-0.8, -1.0), (0.4, -1.0), tol=1e-5)  # offset 0.4 along it
    path, _ = course("two_parts_maze")
    walls = {w.name: w for w in import_world(path).walls}
    approx_segment(walls["Wall_8"], (0.0, 0.2), (0.6, 0.2), tol=1e-5)  # offset 0.1 along it


# --- (d) the committed mazes ------------------------------------------------------------------

SPAWNS = {
    "two_parts_maze": {"part1": (0.1, 0.1, 0.0), "part2": (0.5, 0.3, math.pi / 2), "bonus": (1.3, 0.1, math.pi)},
    "maze_6x6": {"start": (0.1, 0.1, 0.0)},
}


@pytest.mark.parametrize("name", sorted(SPAWNS))
def test_committed_maze_files(name):
    maze = load_maze(MAZES / f"{name}.yaml")
    assert maze.name == name and maze.description and maze.source == f"{name}.world"
    assert {k: (s.x, s.y, s.yaw) for k, s in maze.spawns.items()} == {
        k: pytest.approx(v, abs=1e-6) for k, v in SPAWNS[name].items()
    }
    path, _ = course(name)
    imported = import_world(path)
    assert [(w.name, w.start, w.end, w.thickness) for w in maze.walls] == [
        (w.name, w.start, w.end, w.thickness) for w in imported.walls
    ]
