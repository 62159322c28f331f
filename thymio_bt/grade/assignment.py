"""An assignment file: the worlds a submission runs in, the criteria it is graded on, its palette.

Checked like a mission (file:line errors with hints, a JSON Schema). A minimal one::

    name: stop_at_wall
    submission: part1.yaml            # the file a student's folder must hold
    variants:                         # the worlds: the course's and ones the students never saw
      - {name: course, maze: two_parts_maze, start: part1, seeds: 2}
      - {name: shifted, maze: two_parts_maze, start: [0.25, 0.1, 0], robot: enki}
    criteria:                         # judged on the ground truth, never on the tree's own SUCCESS
      - {name: stops 5 cm from the wall, points: 2, gap: {at: end, distance: 5cm, tolerance: 5mm}}
      - {name: never touches a wall, points: 1, no_collision: true}
    palette: {forbid: [WallFollow], penalty: 3}

Example::

    >>> from thymio_bt.inputs.yamlio import loads_yaml
    >>> a = Assignment.model_validate(loads_yaml(EXAMPLE, "a.yaml"))
    >>> [v.name for v in a.variants], [c.check for c in a.criteria], a.max_points
    (['course', 'shifted'], ['gap', 'no_collision'], 3.0)
    >>> a.variants[0].seed_list, a.criteria[0].applies_to(a.variants[1])
    ([0, 1], True)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from thymio_bt.data import ASSIGNMENTS
from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.inputs.fields import Angle, Duration, Length, Memory, Point, Speed
from thymio_bt.inputs.validation import locate, validate
from thymio_bt.inputs.yamlio import load_yaml
from thymio_bt.maze.model import Spawn
from thymio_bt.robot.model import DEFAULT_ROBOT, ROBOTS

EXAMPLE = """\
name: stop_at_wall
submission: part1.yaml
variants:
  - {name: course, maze: two_parts_maze, start: part1, seeds: 2}
  - {name: shifted, maze: two_parts_maze, start: [0.25, 0.1, 0], robot: enki}
criteria:
  - {name: stops 5 cm from the wall, points: 2, gap: {at: end, distance: 5cm, tolerance: 5mm}}
  - {name: never touches a wall, points: 1, no_collision: true}
palette: {forbid: [WallFollow], penalty: 3}
"""


class Generate(BaseModel):
    """A maze made for the variant, from a seed: ``perfect`` (wall following, exit gap on top),
    ``path`` (one corridor: a turn at every wall, its far end a dead end) or ``contest``
    (micromouse: start in a corner, goal at the centre, loops)."""

    model_config = ConfigDict(extra="forbid")
    kind: Literal["perfect", "path", "contest"] = Field(description="the kind of maze")
    seed: Annotated[int, Field(ge=0, le=2**31)] | Literal["secret"] = Field(
        0,
        description="the generator's seed, or `secret`: drawn from the course's secret (the "
        "THYMIO_BT_SECRET environment variable or grade --secret FILE), in no file a student has",
    )
    cols: int = Field(6, ge=2, le=32, description="perfect: columns of cells")
    rows: int = Field(6, ge=2, le=32, description="perfect: rows of cells")
    length: int = Field(8, ge=3, le=64, description="path: cells along the corridor")
    size: int = Field(8, ge=4, le=32, description="contest: cells per side (even)")
    turns: Literal["left", "right", "any"] = Field("any", description="path: the turns it may have")
    cell: Length = Field(
        0.2, ge=0.15, le=0.5, description="perfect and path: the cell pitch, wall centre to wall centre"
    )


class GoalDisc(BaseModel):
    """A disc base_link must end in."""

    model_config = ConfigDict(extra="forbid")
    centre: Point = Field(description="[x, y]")
    radius: Length = Field(0.05, gt=0, le=10, description="how far from the centre still counts")


if TYPE_CHECKING:
    BuiltinRobot = str
else:
    #: a built-in robot model's name: a ``Literal`` of :data:`~thymio_bt.robot.model.ROBOTS`' keys,
    #: so that the assignment schema lists them (mypy sees a ``str``: a type cannot be computed)
    BuiltinRobot = Literal[tuple(ROBOTS)]


class Variant(BaseModel):
    """One world a submission runs in: a maze (a file, a shipped name or generated), a start, a
    robot profile and noise seeds; what the criteria compare with (``goal``, ``turns``)."""

    model_config = ConfigDict(extra="forbid")
    name: str = Field(min_length=1, max_length=60, pattern=r"^[A-Za-z0-9_.-]+$", description="the variant's name")
    maze: str | None = Field(None, description="a maze file (relative to the assignment) or a shipped maze's name")
    generate: Generate | None = Field(None, description="a generated maze instead of a file")
    mirror: bool = Field(False, description="mirror the maze left-right (left turns become right turns)")
    start: str | Spawn | None = Field(
        None, description="a spawn name of the maze or [x, y, yaw]; the mission's own if absent"
    )
    visibility: Literal["public", "hidden"] = Field(
        "public",
        description="public: students may see and run it (thymio-bt check); hidden: its maze, path, start "
        "and reproducing command never reach a student-facing output",
    )
    robot: BuiltinRobot = Field(DEFAULT_ROBOT, description="the robot profile")
    seeds: int | list[int] = Field(1, description="how many noise seeds (0, 1, ...) or the list of seeds")
    noise: Literal["realistic", "off"] = Field("realistic", description="the noise models, on or off")
    set: dict[str, str | int | float] = Field(default={}, description="other --set NAME=VALUE settings")
    goal: GoalDisc | None = Field(None, description="where a `goal` criterion wants the robot to end")
    turns: str | None = Field(None, pattern=r"^[LR]*$", description="the turns a `turns` criterion wants, e.g. LLRL")

    @field_validator("noise", mode="before")
    @classmethod
    def _noise(cls, value: Any) -> Any:
        """YAML reads a bare ``off`` (and ``on``) as a boolean."""
        return {False: "off", True: "realistic"}.get(value, value) if isinstance(value, bool) else value

    @field_validator("seeds")
    @classmethod
    def _seeds(cls, value: int | list[int]) -> int | list[int]:
        count = value if isinstance(value, int) else len(value)
        if not 1 <= count <= 1000:
            raise ValueError("a variant runs 1 to 1000 seeds")
        if isinstance(value, list) and (len(set(value)) != len(value) or min(value) < 0):
            raise ValueError("seeds must be distinct and >= 0")
        return value

    @model_validator(mode="after")
    def _one_maze(self) -> Variant:
        if self.maze is not None and self.generate is not None:
            raise ValueError("give `maze` or `generate`, not both")
        return self

    @property
    def seed_list(self) -> list[int]:
        """The seeds this variant runs."""
        return list(range(self.seeds)) if isinstance(self.seeds, int) else list(self.seeds)


class GapCheck(BaseModel):
    """The front gap (the robot's nose to the wall ahead, by geometry) at a moment of the run."""

    model_config = ConfigDict(extra="forbid")
    at: Literal["delete", "end"] | None = Field(
        None, description="delete: as the robot is deleted; end: when the run ends"
    )
    after: str | None = Field(
        None, min_length=1, description="when the first node of this type (MoveUntilWall) or path (a glob) ended"
    )
    distance: Length = Field(gt=0, le=2, description="the gap wanted")
    tolerance: Length = Field(0.005, gt=0, le=1, description="how far off still counts")

    @model_validator(mode="after")
    def _one_moment(self) -> GapCheck:
        if (self.at is None) == (self.after is None):
            raise ValueError("give the moment to measure: `at: delete`, `at: end` or `after: NODE`")
        return self


class DeadEndCheck(GapCheck):
    """The run ends in a dead end: a wall ahead at ``distance`` and walls close on both sides."""

    at: Literal["delete", "end"] | None = Field("end", description="when to look (end)")
    side: Length | None = Field(
        None,
        gt=0,
        le=1,
        description="a side wall at most this far from base_link; by default 3/4 of the maze's grid "
        "pitch (0.15 m on the course's 0.2 m grid)",
    )
    after: str | None = Field(
        None,
        min_length=1,
        description="the stop counts only once this node (a type or a path glob) has ended; by default "
        "only once the route has taken the variant's turns",
    )

    @model_validator(mode="after")
    def _one_moment(self) -> DeadEndCheck:
        """A dead end is judged where the run ends (or at the delete); ``after`` is the phase it
        must come in, not another moment."""
        if self.at is None:
            raise ValueError("a dead end is judged `at: end` or `at: delete`")
        return self


class SpeedCheck(BaseModel):
    """A phase's cruise speed: the median speed while driving at least half the phase's top speed
    (speeding up, slowing down to a wall and turning on the spot are not cruising)."""

    model_config = ConfigDict(extra="forbid")
    speed: Speed = Field(gt=0, le=2, description="the cruise speed wanted")
    tolerance: Speed = Field(0.02, gt=0, le=2, description="how far off still counts")
    after: str | None = Field(
        None, min_length=1, description="the phase starts at this: delete, spawn, or a node (type or path glob) ended"
    )
    before: str | None = Field(
        None, min_length=1, description="the phase ends at this: delete, spawn, or a node (type or path glob) ended"
    )


class RespawnCheck(BaseModel):
    """The robot was spawned again at ``pose`` (a spawn name of the variant's maze or [x, y, yaw])."""

    model_config = ConfigDict(extra="forbid")
    pose: str | Spawn = Field(description="a spawn name or [x, y, yaw]")
    tolerance: Length = Field(0.01, gt=0, le=1, description="position tolerance")
    yaw_tolerance: Angle = Field(0.09, gt=0, le=3.2, description="heading tolerance")


#: the checks a criterion may make, each judged by the function of that name in :mod:`.checks`
CHECKS = (
    "finishes",
    "no_collision",
    "max_time",
    "goal",
    "gap",
    "dead_end",
    "order",
    "respawn",
    "turns",
    "leaves_maze",
    "min_clearance",
    "no_reverse",
    "speed",
)


class Criterion(BaseModel):
    """A named check worth ``points``, over the runs of some variants: passed when at least
    ``pass_rate`` of them pass it."""

    model_config = ConfigDict(extra="forbid")
    name: str = Field(min_length=1, max_length=120, description="what the student sees")
    points: float = Field(gt=0, le=1000, description="what passing it earns")
    variants: list[str] | None = Field(None, description="the variants it judges (all when absent)")
    pass_rate: float = Field(1.0, gt=0, le=1, description="the share of a variant's runs that must pass")
    credit: Literal["shared", "all"] = Field(
        "shared",
        description="shared: the points are shared over its variants, each passed variant earns its share; "
        "all: every variant must pass for any point",
    )
    finishes: Literal[True] | None = Field(None, description="the tree ends by itself before the time limit")
    no_collision: Literal[True] | None = Field(None, description="no contact with a wall")
    max_time: Duration | None = Field(None, gt=0, le=36000, description="the tree ends within this")
    goal: Literal[True] | GoalDisc | None = Field(None, description="ends in this disc (true: the variant's goal)")
    gap: GapCheck | None = Field(None, description="the front gap at a moment")
    dead_end: DeadEndCheck | None = Field(None, description="ends stopped in a dead end")
    order: list[str] | None = Field(None, min_length=2, description="these event kinds happen, in this order")
    respawn: RespawnCheck | None = Field(None, description="the robot is spawned again there")
    turns: Literal[True] | str | None = Field(None, description="the turns taken (true: the variant's)")
    leaves_maze: Literal[True] | None = Field(None, description="base_link ends outside the maze's walls")
    min_clearance: Length | None = Field(None, gt=0, le=1, description="never closer to a wall than this")
    no_reverse: Literal[True] | None = Field(None, description="never drives backwards")
    speed: SpeedCheck | None = Field(None, description="a phase's cruise speed")

    @model_validator(mode="after")
    def _one_check(self) -> Criterion:
        given = [name for name in CHECKS if getattr(self, name) is not None]
        if len(given) != 1:
            raise ValueError(
                f"a criterion makes exactly one check, this one makes {len(given)}"
                + (f" ({', '.join(given)})" if given else "")
                + f"; one of: {', '.join(CHECKS)}"
            )
        return self

    @property
    def check(self) -> str:
        """The name of the check it makes."""
        return next(name for name in CHECKS if getattr(self, name) is not None)

    def applies_to(self, variant: Variant) -> bool:
        """Whether it judges ``variant``'s runs."""
        return self.variants is None or variant.name in self.variants


class Palette(BaseModel):
    """The nodes a student may use, and what breaking a rule costs."""

    model_config = ConfigDict(extra="forbid")
    allow: list[str] | None = Field(None, description="only these node types (behaviours, composites, decorators)")
    forbid: list[str] = Field(default=[], description="these node types are not allowed")
    plugins: bool = Field(False, description="whether a submission may bring Python plugins")
    include_library: bool = Field(True, description="whether it may include the shipped missions' library")
    max_nodes: int | None = Field(None, ge=1, le=100_000, description="the most nodes a tree may have")
    max_depth: int | None = Field(None, ge=1, le=1000, description="the deepest a tree may be")
    penalty: float = Field(0.0, ge=0, le=1000, description="points lost per rule broken (the score stays >= 0)")


class Limits(BaseModel):
    """What one run of a submission may use before it is stopped."""

    model_config = ConfigDict(extra="forbid")
    cpu: Duration = Field(20.0, gt=0, le=3600, description="CPU seconds per run")
    wall: Duration | None = Field(None, gt=0, le=36000, description="wall-clock seconds per run (3 x cpu + 5 s)")
    memory: Memory = Field(
        1024, ge=64, le=65536, description="address space a submission's process may add (MiB, or 512MiB, 2GiB)"
    )


class Assignment(BaseModel):
    """A graded exercise: where submissions run, what they are judged on, which nodes they may use."""

    model_config = ConfigDict(extra="forbid")
    name: str = Field(min_length=1, max_length=80, description="the assignment's name")
    title: str = Field("", description="one line for the class page")
    submission: str | None = Field(None, description="the mission file a student's folder must hold")
    variants: list[Variant] = Field(min_length=1, description="the worlds every submission runs in")
    criteria: list[Criterion] = Field(min_length=1, description="what is graded")
    palette: Palette = Field(default_factory=Palette, description="the nodes allowed")
    limits: Limits = Field(default_factory=Limits, description="per-run CPU and memory limits")
    time_limit: Duration | None = Field(None, gt=0, le=36000, description="overrides the missions' time_limit")

    @property
    def max_points(self) -> float:
        """The score of a perfect submission."""
        return sum(c.points for c in self.criteria)

    def variant(self, name: str) -> Variant:
        """The variant called ``name``."""
        return next(v for v in self.variants if v.name == name)


def assignment_schema() -> dict[str, Any]:
    """The JSON Schema of assignment files (``thymio-bt schema --assignment``), for editors."""
    schema = _loosened(Assignment.model_json_schema())
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = "thymio-bt assignment"
    noise = schema["$defs"]["Variant"]["properties"]["noise"]
    schema["$defs"]["Variant"]["properties"]["noise"] = {"anyOf": [noise, {"type": "boolean"}]}
    return schema


def _loosened(node: Any) -> Any:
    """The schema as the YAML is written: numbers also as text with units (``5cm``, ``pi/2``),
    spawns also as ``[x, y, yaw]``."""
    if isinstance(node, list):
        return [_loosened(n) for n in node]
    if not isinstance(node, dict):
        return node
    out = {k: _loosened(v) for k, v in node.items()}
    if out.get("type") == "number":
        return {"anyOf": [out, {"type": "string"}]}
    if out.get("$ref") == "#/$defs/Spawn":
        return {"anyOf": [out, {"type": "array", "minItems": 3, "maxItems": 3}]}
    if "prefixItems" in out:
        out["prefixItems"] = [{"anyOf": [{"type": "number"}, {"type": "string"}]} for _ in out["prefixItems"]]
    return out


def resolve_assignment(ref: str | Path) -> Path:
    """An assignment by path, or by the name of a shipped one (``course_part1_2``)."""
    path = Path(ref)
    if path.exists() or path.suffix or len(path.parts) != 1:
        return path
    shipped = ASSIGNMENTS / f"{ref}.yaml"
    if shipped.is_file():
        return shipped
    known = sorted(p.stem for p in ASSIGNMENTS.glob("*.yaml"))
    raise UserError(
        Problem(f"assignment not found: '{ref}'", hint=f"a file, or a shipped one: {did_you_mean(str(ref), known)}")
    )


@dataclass
class Reading:
    """An assignment file read as far as it goes: the assignment (None when its schema fails), the
    variants that are valid on their own (with their index) and every problem found."""

    file: str
    data: Any
    assignment: Assignment | None
    variants: list[tuple[int, Variant]]
    problems: list[Problem]


def load_assignment(path: str | Path) -> Assignment:
    """Read and check an assignment file (or a shipped one, by name); a :class:`UserError` with
    file:line for every problem."""
    reading = read_assignment(path)
    if reading.problems or reading.assignment is None:
        raise UserError(reading.problems)
    return reading.assignment


def read_assignment(path: str | Path) -> Reading:
    """Read an assignment file and find every problem in one go: the schema's, and, in the parts
    that are valid on their own, the variants', criteria's and palette's (the worlds' are
    :func:`~thymio_bt.grade.worlds.load_worlds`')."""
    path = resolve_assignment(path)
    file = str(path)
    data = load_yaml(path, "assignment")
    problems: list[Problem] = []
    try:
        assignment: Assignment | None = validate(Assignment, data, file)
    except UserError as exc:
        assignment, problems = None, list(exc.problems)
    raw = data if isinstance(data, dict) else {}
    if assignment is not None:
        variants = list(enumerate(assignment.variants))
        criteria = list(enumerate(assignment.criteria))
        names: list[Any] = [v.name for v in assignment.variants]
    else:
        variants = _valid_alone(Variant, raw.get("variants"))
        criteria = _valid_alone(Criterion, raw.get("criteria"))
        listed = raw.get("variants")
        names = [v.get("name") if isinstance(v, dict) else None for v in (listed if isinstance(listed, list) else [])]
    for i, variant in variants:
        if names.index(variant.name) != i:
            line, col = _mark(data, ["variants", i, "name"])
            problems.append(Problem(f"variant '{variant.name}' is defined twice", file, line, col))
    for i, criterion in criteria:
        problems += _criterion_problems(data, file, i, criterion, names, [v for _, v in variants])
    problems += _palette_problems(data, file)
    return Reading(file, data, assignment, variants, problems)


def _valid_alone(model: type[BaseModel], items: Any) -> list[tuple[int, Any]]:
    """The items of a list that are valid ``model`` s on their own, with their index."""
    out = []
    for i, item in enumerate(items if isinstance(items, list) else []):
        try:
            out.append((i, model.model_validate(item)))
        except ValidationError:
            continue
    return out


def _criterion_problems(
    data: Any, file: str, i: int, criterion: Criterion, names: list[Any], variants: list[Variant]
) -> list[Problem]:
    """A criterion's problems: the variants it names exist and give what it compares with."""
    problems = []
    for j, name in enumerate(criterion.variants or []):
        if name not in names:
            line, col = _mark(data, ["criteria", i, "variants", j])
            message = f"criterion '{criterion.name}' names no variant '{name}'"
            problems.append(Problem(message, file, line, col, hint=did_you_mean(name, [str(n) for n in names])))
    applies = [v for v in variants if criterion.applies_to(v)]
    for check, missing, hint in (
        ("goal", lambda v: v.goal is None and not _maze_may_have_goal(v), "a `goal: {centre: [x, y], radius: 5cm}`"),
        ("turns", lambda v: v.turns is None and not _generated_path(v), "`turns: LLR...` (or the criterion its own)"),
    ):
        if getattr(criterion, check) is True and any(missing(v) for v in applies):
            line, col = _mark(data, ["criteria", i, check])
            message = f"criterion '{criterion.name}' wants the variant's {check}, and a variant gives none"
            problems.append(Problem(message, file, line, col, hint=f"give the variants {hint}"))
    return problems


def _palette_problems(data: Any, file: str) -> list[Problem]:
    """The palette's node names must be node types (a misspelt ``forbid`` would forbid nothing)."""
    from thymio_bt.plan.registry import default_registry

    palette = data.get("palette") if isinstance(data, dict) else None
    if not isinstance(palette, dict):
        return []
    known = list(default_registry())
    problems = []
    for key in ("forbid", "allow"):
        for j, name in enumerate(palette.get(key) or []):
            if isinstance(name, str) and name not in known:
                line, col = _mark(data, ["palette", key, j])
                message = f"palette {key}: '{name}' is no node type, so it {key}s nothing"
                hint = did_you_mean(name, known) + "; `thymio-bt behaviours` lists them"
                problems.append(Problem(message, file, line, col, f"palette.{key}.{j}", hint))
    return problems


def _maze_may_have_goal(variant: Variant) -> bool:
    """A maze file or a contest maze may hold goal areas (checked when the run is judged)."""
    return variant.generate is None or variant.generate.kind == "contest"


def _generated_path(variant: Variant) -> bool:
    return variant.generate is not None and variant.generate.kind == "path"


def _mark(data: Any, loc: list[Any]) -> tuple[int, int]:
    return locate(data, loc)
