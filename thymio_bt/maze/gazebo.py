"""Import a Gazebo classic SDF ``.world`` of box walls as a :class:`Maze`.

Every box ``<collision>`` of the wall model(s) becomes one wall named after its link. Poses are
composed as Gazebo does on load: a ``<state>`` block wins over the definitions (its model *and*
link poses are world poses, applied by ``World::SetState``), else model pose ∘ link pose; then the
collision's own ``<pose>`` offset. The box's long horizontal side gives the segment direction, the
short one the thickness, and the segment is ``length - thickness`` long (walls extend thickness/2
past both ends). Segments point towards +x (or +y), values are rounded to 1e-6 m and walls are
sorted by name in natural order (Wall_2 before Wall_10).

Spawns are not part of a world (the launch file places the robot): pass them as ``spawns=``
(the CLI's ``maze import`` may add them later, as ``mazes/*.yaml`` do).

Example (a world of one 0.61 m box, as the course's walls are)::

    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "box.world"
    >>> box = "<collision name='c'><geometry><box><size>0.61 0.01 0.1</size></box></geometry></collision>"
    >>> link = f"<link name='Wall_1'><pose>0.3 0 0 0 0 0</pose>{box}</link>"
    >>> _ = path.write_text(f"<sdf version='1.6'><world name='w'><model name='walls'>{link}</model></world></sdf>")
    >>> maze = import_world(path, spawns={"part1": (0.1, 0.1, 0)})
    >>> wall = maze.walls[0]
    >>> wall.name, wall.start, wall.end, wall.thickness, maze.spawn("part1")
    ('Wall_1', (0.0, 0.0), (0.6, 0.0), 0.01, Pose(x=0.1, y=0.1, yaw=0.0))
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.reading import read_bytes
from thymio_bt.inputs.validation import Wording, problems_from
from thymio_bt.inputs.xmlparse import parse_xml
from thymio_bt.maze.model import Maze, Spawn, Wall

Vec = tuple[float, float, float]
Mat = tuple[Vec, Vec, Vec]
#: |z component| of a box axis above which it counts as vertical (about 0.8 degrees of tilt).
_UPRIGHT = 0.9999


@dataclass(frozen=True)
class _Pose:
    """A rigid transform: position ``p`` and rotation matrix ``r`` (rows)."""

    p: Vec = (0.0, 0.0, 0.0)
    r: Mat = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

    def __mul__(self, child: _Pose) -> _Pose:
        """``self ∘ child``: the child's pose expressed in self's parent frame."""
        a, b = self.r, child.r
        p = tuple(self.p[i] + sum(a[i][k] * child.p[k] for k in range(3)) for i in range(3))
        r = tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3))
        return _Pose(p, r)  # type: ignore[arg-type]


def _rpy(x: float, y: float, z: float, roll: float, pitch: float, yaw: float) -> _Pose:
    """SDF's ``x y z roll pitch yaw``: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return _Pose(
        (x, y, z),
        (
            (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
            (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
            (-sp, cp * sr, cp * cr),
        ),
    )


@dataclass
class _Doc:
    """A parsed file that remembers the (line, column) of every element."""

    file: str
    root: ET.Element
    marks: dict[ET.Element, tuple[int, int]]

    def error(self, message: str, el: ET.Element | None, hint: str = "") -> UserError:
        line, col = self.marks.get(el, (0, 0)) if el is not None else (0, 0)
        return UserError(Problem(message, self.file, line, col, hint=hint))

    def floats(self, el: ET.Element, count: int, what: str) -> list[float]:
        words = (el.text or "").split()
        try:
            values = [float(w) for w in words]
        except ValueError:
            values = []
        if len(values) != count or not all(map(math.isfinite, values)):
            raise self.error(f"<{el.tag}> must hold {count} numbers ({what}), got '{(el.text or '').strip()}'", el)
        return values

    def pose(self, el: ET.Element | None) -> _Pose:
        """The transform of a ``<pose>`` element (identity when absent or empty)."""
        if el is None or not (el.text or "").strip():
            return _Pose()
        if el.get("relative_to") or el.get("frame"):
            raise self.error(
                "poses relative to a named frame are not supported",
                el,
                hint="save the world from Gazebo classic, which writes plain poses",
            )
        if el.get("rotation_format", "euler_rpy") != "euler_rpy":
            raise self.error("only 'x y z roll pitch yaw' poses are supported", el)
        v = self.floats(el, 6, "x y z roll pitch yaw")
        if el.get("degrees", "false").strip().lower() in ("true", "1"):
            v[3:] = [math.radians(a) for a in v[3:]]
        return _rpy(*v)


def _parse(path: Path) -> _Doc:
    """Parse the world with line numbers, under :func:`~thymio_bt.inputs.xmlparse.parse_xml`'s guards
    (no DOCTYPE or ENTITY, bounded nesting)."""
    file = str(path)
    builder = ET.TreeBuilder()
    marks: dict[ET.Element, tuple[int, int]] = {}

    def start(tag: str, attrs: dict[str, str], line: int, column: int) -> None:
        marks[builder.start(tag, attrs)] = (line, column)

    parse_xml(
        read_bytes(path, "world"),
        file,
        "world file",
        start,
        builder.end,
        builder.data,
        hint="a Gazebo .world file is SDF (XML) starting with <sdf version=...>",
    )
    root = builder.close()
    doc = _Doc(file, root, marks)
    if root.tag != "sdf":
        raise doc.error(f"not an SDF file: the root element is <{root.tag}>, expected <sdf>", root)
    return doc


@dataclass
class _State:
    """What ``<state>`` blocks say about one model: its world pose, link world poses, sub-models."""

    pose: ET.Element | None = None
    scale: ET.Element | None = None
    links: dict[str, ET.Element] = field(default_factory=dict)
    models: dict[str, _State] = field(default_factory=dict)

    def merge(self, el: ET.Element) -> None:
        self.pose = el.find("pose") if el.find("pose") is not None else self.pose
        self.scale = el.find("scale") if el.find("scale") is not None else self.scale
        for link in el.findall("link"):
            if link.find("pose") is not None:
                self.links[link.get("name", "")] = link.find("pose")  # type: ignore[assignment]
        for sub in el.findall("model"):
            self.models.setdefault(sub.get("name", ""), _State()).merge(sub)


def _has_box(model: ET.Element) -> bool:
    return any(c.find("geometry/box") is not None for c in model.iter("collision"))


def _walls(doc: _Doc, model: ET.Element, parent: _Pose, state: _State | None, prefix: str) -> list[Wall]:
    """The walls of one model (and its nested models), in world coordinates."""
    if state is not None and state.scale is not None and doc.floats(state.scale, 3, "x y z") != [1, 1, 1]:
        raise doc.error(f"model '{model.get('name')}' is scaled in <state>; scaling is not supported", state.scale)
    if state is not None and state.pose is not None:
        pose = doc.pose(state.pose)  # a world pose
    else:
        pose = parent * doc.pose(model.find("pose"))
    walls: list[Wall] = []
    for link in model.findall("link"):
        name = link.get("name", "")
        link_state = state.links.get(name) if state is not None else None
        link_pose = doc.pose(link_state) if link_state is not None else pose * doc.pose(link.find("pose"))
        collisions = link.findall("collision")
        for col in collisions:
            geometry = col.find("geometry")
            shape = geometry[0] if geometry is not None and len(geometry) else None
            if shape is None or shape.tag != "box":
                raise doc.error(
                    f"link '{name}' has a {'<' + shape.tag + '>' if shape is not None else 'missing'}"
                    " collision geometry; only boxes can become walls",
                    shape if shape is not None else col,
                    hint="import only the wall model with model=..., or make it a <box>",
                )
            size = shape.find("size")
            if size is None:
                raise doc.error(f"the <box> of link '{name}' has no <size>", shape)
            wall_name = prefix + name + (f"/{col.get('name')}" if len(collisions) > 1 else "")
            walls.append(_box_wall(doc, size, link_pose * doc.pose(col.find("pose")), wall_name))
    for sub in model.findall("model"):
        sub_state = state.models.get(sub.get("name", "")) if state is not None else None
        walls += _walls(doc, sub, pose, sub_state, f"{prefix}{sub.get('name')}::")
    return walls


def _box_wall(doc: _Doc, size_el: ET.Element, pose: _Pose, name: str) -> Wall:
    """The wall segment of an upright box of ``size`` at world ``pose``."""
    size = doc.floats(size_el, 3, "x y z")
    if min(size) <= 0:
        raise doc.error(f"box of '{name}' must have positive sizes", size_el)
    r = pose.r
    upright = [k for k in range(3) if abs(r[2][k]) > _UPRIGHT]
    if not upright:
        raise doc.error(f"box of '{name}' is tilted; only upright boxes can become walls", size_el)
    a, b = [k for k in range(3) if k != upright[0]]
    long, short = (a, b) if size[a] >= size[b] else (b, a)
    length, thickness = size[long], size[short]
    if length - thickness < 1e-9:
        raise doc.error(
            f"box of '{name}' is square in plan ({length} x {thickness}); its direction is unknown",
            size_el,
            hint="a wall box is longer than it is thick",
        )
    ux, uy = r[0][long], r[1][long]
    norm = math.hypot(ux, uy)
    ux, uy = ux / norm, uy / norm
    if (ux if abs(ux) >= abs(uy) else uy) < 0:  # point towards +x (mostly horizontal) or +y
        ux, uy = -ux, -uy
    half = (length - thickness) / 2.0
    cx, cy = pose.p[0], pose.p[1]

    def rnd(v: float) -> float:
        return round(v, 6) + 0.0

    try:
        return Wall(
            start=(rnd(cx - ux * half), rnd(cy - uy * half)),
            end=(rnd(cx + ux * half), rnd(cy + uy * half)),
            thickness=rnd(thickness),
            name=name,
        )
    except ValidationError as exc:
        wording = Wording(invalid=f"box of '{name}' cannot be a wall: {{msg}}")
        at = doc.marks.get(size_el, (0, 0))
        raise UserError(problems_from(exc, None, doc.file, Wall, at=at, wording=wording)) from None


def _natural(name: str | None) -> list[Any]:
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", name or "")]


def _states(worlds: list[ET.Element]) -> dict[str, _State]:
    """The models' states of the worlds' ``<state>`` blocks, by model name (later blocks win, as on load)."""
    state: dict[str, _State] = {}
    for st in (s for w in worlds for s in w.findall("state")):
        for m in st.findall("model"):
            state.setdefault(m.get("name", ""), _State()).merge(m)
    return state


def _chosen(doc: _Doc, models: list[ET.Element], model: str | None) -> list[ET.Element]:
    """The models to import: the one named ``model`` (a user error if none is), else every model
    with a box collision."""
    if model is None:
        return [m for m in models if _has_box(m)]
    chosen = [m for m in models if m.get("name") == model]
    if not chosen:
        names = [m.get("name", "") for m in models]
        raise UserError(
            Problem(
                f"no model named '{model}' in the world",
                doc.file,
                hint=did_you_mean(model, names) if names else "the world has no <model>",
            )
        )
    return chosen


def _no_walls(doc: _Doc, worlds: list[ET.Element], model: str | None) -> UserError:
    """The error of a world (or ``model``) without box walls, with a hint for ``<include>``d models."""
    includes = doc.root.find(".//include") is not None
    return doc.error(
        f"no box walls found in {'model ' + repr(model) if model else 'the world'}",
        worlds[0] if worlds else doc.root,
        hint="<include>d models are not followed: paste their <model> into the world"
        if includes
        else "walls are <link>s with a <collision><geometry><box>",
    )


def import_world(
    path: str | Path,
    model: str | None = None,
    *,
    spawns: Mapping[str, Spawn | Mapping[str, Any] | tuple[Any, Any, Any]] | None = None,
    name: str | None = None,
    description: str = "",
) -> Maze:
    """Read the box walls of a Gazebo classic world into a :class:`Maze`.

    ``model`` picks one model by name; by default every model with a box collision is imported
    (link names get a ``model::`` prefix when there are several). ``name`` defaults to the file's
    stem, ``source`` is the file name. Any user mistake is a :class:`UserError` with file:line.
    """
    path = Path(path)
    doc = _parse(path)
    worlds = doc.root.findall("world")
    models = [m for w in worlds for m in w.findall("model")] + doc.root.findall("model")
    state = _states(worlds)
    chosen = _chosen(doc, models, model)
    walls: list[Wall] = []
    for m in chosen:
        prefix = f"{m.get('name')}::" if len(chosen) > 1 else ""
        walls += _walls(doc, m, _Pose(), state.get(m.get("name", "")), prefix)
    if not walls:
        raise _no_walls(doc, worlds, model)
    walls.sort(key=lambda w: _natural(w.name))
    return Maze(name=name or path.stem, description=description, source=path.name, walls=walls, spawns=_spawns(spawns))


def _spawns(spawns: Mapping[str, Spawn | Mapping[str, Any] | tuple[Any, Any, Any]] | None) -> dict[str, Spawn]:
    """The spawns given to :func:`import_world` (in Python, not a file), checked: a :class:`UserError`
    names each bad one."""
    checked, problems = {}, []
    for key, value in (spawns or {}).items():
        try:
            checked[key] = value if isinstance(value, Spawn) else Spawn.model_validate(value)
        except ValidationError as exc:
            wording = Wording(invalid="bad spawn: {msg}")
            problems += problems_from(exc, value, "<spawns>", Spawn, f"{key}.", at=(0, 0), wording=wording)
    if problems:
        raise UserError(problems)
    return checked
