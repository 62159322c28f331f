"""The worlds of an assignment's variants, made ready to run: a maze file, a start and settings.

A generated or mirrored maze is written once into a ``worlds`` folder (next to the results), so
that the command reproducing a failed run names a file a student can open and run again.

Example::

    >>> import tempfile
    >>> from thymio_bt.grade.assignment import Variant
    >>> folder = Path(tempfile.mkdtemp())
    >>> world = World.of(Variant(name="corridor", generate={"kind": "path", "seed": 4, "turns": "left"}),
    ...                  Path("."), folder)
    >>> world.maze_file.name, world.start, world.turns, world.settings["robot"]
    ('corridor.yaml', 'start', 'LL', 'course')
    >>> world.run_arguments()[:4]
    ['--maze', '.../corridor.yaml', '--start', 'start']
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.grade.assignment import Assignment, GoalDisc, Variant
from thymio_bt.maze import Maze
from thymio_bt.maze.files import load_maze, resolve_maze
from thymio_bt.maze.generate import contest_maze, mirrored, path_maze, perfect_maze, random_path, turns_along
from thymio_bt.outputs import Output
from thymio_bt.robot.noise import REALISTIC, NoiseConfig

if TYPE_CHECKING:
    from thymio_bt.plan.model import Mission


@dataclass
class World:
    """A variant ready to run: its maze (as a file), start, ``--set`` settings and expectations."""

    name: str
    maze_file: Path | None
    maze: Maze | None
    start: str | None
    settings: dict[str, str]
    seeds: list[int]
    goal: GoalDisc | None = None
    turns: str | None = None
    robot: str = "course"
    extra: dict[str, Any] = field(default_factory=dict)
    #: the maze's grid pitch (m): a generated maze's, else the course's
    cell: float = 0.2
    #: ``public`` or ``hidden`` (never shown to students)
    visibility: str = "public"

    @classmethod
    def of(cls, variant: Variant, base: Path, folder: Path, secret: str | None = None) -> World:
        """``variant`` (its maze file relative to ``base``; a made maze written into ``folder``;
        ``secret``: the course's secret, for a generated maze whose seed is ``secret``)."""
        turns = variant.turns
        maze: Maze | None = None
        maze_file: Path | None = None
        if variant.generate is not None:
            maze, made_turns = _generated(variant, secret)
            turns = turns or made_turns
        elif variant.maze is not None:
            maze_file = Path(os.path.normpath(resolve_maze(variant.maze, base, "the assignment file")))
            maze = load_maze(maze_file)
        if variant.mirror:
            if maze is None:
                raise ValueError("mirror needs the variant's maze")
            x0, _, x1, _ = maze.bounds()
            maze = mirrored(maze, (x0 + x1) / 2)
            turns = turns and turns.translate(str.maketrans("LR", "RL"))
        # a maze that is not shipped by name is written beside the results too: the commands that
        # reproduce a run name it there, never by the grader's own path
        if maze is not None and (maze_file is None or variant.mirror or not _named(maze_file)):
            folder.mkdir(parents=True, exist_ok=True)
            maze_file = folder / f"{variant.name}.yaml"
            Output(maze_file, "worlds").write_text(yaml.safe_dump(maze.to_yaml_dict(), sort_keys=False))
        start = variant.start
        if start is not None and not isinstance(start, str):
            start = f"{start.x:.6g},{start.y:.6g},{start.yaw:.6g}"
        elif start is None and variant.generate is not None:
            start = "start"
        if maze is not None and start is not None:
            _check_start(variant.name, maze, start, variant.robot)
        noise = (REALISTIC if variant.noise == "realistic" else NoiseConfig()).settings()
        settings = {**noise, **{k: str(v) for k, v in variant.set.items()}, "robot": variant.robot}
        return cls(
            variant.name,
            maze_file,
            maze,
            start,
            settings,
            variant.seed_list,
            variant.goal,
            turns,
            variant.robot,
            cell=_pitch(variant),
            visibility=variant.visibility,
        )

    def run_arguments(self, relative_to: Path | None = None) -> list[str]:
        """The ``thymio-bt run`` arguments that put a mission in this world (all but the seed): a
        shipped maze by its name, another by its path relative to ``relative_to`` (the folder of
        the results; the current one when None), never by the grader's absolute path."""
        out = ["--maze", maze_ref(self.maze_file, relative_to)] if self.maze_file else []
        out += ["--start", self.start] if self.start else []
        for key, value in sorted(self.settings.items()):
            out += ["--set", f"{key}={value}"]
        return out

    def mission(self, path: str | Path, run_plugins: bool = True, time_limit: float | None = None) -> Mission:
        """The mission at ``path`` in this world (its own ``expect:`` dropped: the criteria judge)."""
        from dataclasses import replace

        from thymio_bt.mission import load_mission

        settings = dict(self.settings)
        if time_limit is not None:
            settings["time_limit"] = f"{time_limit:g}"
        mission = load_mission(
            path,
            settings,
            maze=str(self.maze_file) if self.maze_file else None,
            start=self.start,
            run_plugins=run_plugins,
        )
        return replace(mission, expect=None)


def _check_start(name: str, maze: Maze, start: str, robot: str) -> None:
    """A variant's start must be a spawn of its maze, or a pose where its robot can stand."""
    from thymio_bt.geometry import Pose
    from thymio_bt.inputs.units import UnitError, parse_pose
    from thymio_bt.robot.model import robot_model
    from thymio_bt.robot.placement import placement_problem

    if start in maze.spawns:
        pose = maze.spawns[start].pose()
    else:
        try:
            pose = Pose(*parse_pose(start))
        except UnitError:
            raise UserError(
                Problem(
                    f"variant '{name}': its maze has no spawn '{start}'",
                    path="start",
                    hint=did_you_mean(start, maze.spawns),
                )
            ) from None
    problem = placement_problem(maze, robot_model(robot), pose)
    if problem:
        message = f"variant '{name}': impossible start {start}: {problem}"
        raise UserError(Problem(message, path="start", hint="pick a free pose"))


def _pitch(variant: Variant) -> float:
    """The grid pitch of the variant's maze: a generated one's, else the course's 0.2 m."""
    spec = variant.generate
    if spec is None:
        return 0.2
    if spec.kind == "contest":
        from thymio_bt.maze.micromouse import CELL

        return CELL
    return spec.cell


def _named(path: Path) -> bool:
    """Whether ``path`` is a shipped maze, which commands name by its name."""
    from thymio_bt.data import MAZES

    shipped = MAZES / path.name
    return path.suffix in (".yaml", ".yml", ".txt") and shipped.is_file() and path.resolve() == shipped.resolve()


def maze_ref(path: Path, relative_to: Path | None = None) -> str:
    """How a command names the maze file ``path``: a shipped maze by its name, another by its path
    relative to ``relative_to`` (the current folder when None).

    >>> from thymio_bt.data import MAZES
    >>> maze_ref(MAZES / "two_parts_maze.yaml"), maze_ref(Path("/r/worlds/w.yaml"), Path("/r"))
    ('two_parts_maze', 'worlds/w.yaml')
    """
    if _named(path):
        return path.stem
    return os.path.relpath(path.resolve(), (relative_to or Path.cwd()).resolve())


#: the environment variable that holds a course's secret (``grade --secret FILE`` instead)
SECRET_VARIABLE = "THYMIO_BT_SECRET"


def course_secret(file: Path | None = None) -> str | None:
    """The course's secret: the file's first line (``--secret FILE``), else the environment
    variable :data:`SECRET_VARIABLE`; None when neither is given."""
    if file is not None:
        try:
            text = file.read_text().strip().splitlines()
        except OSError as exc:
            raise UserError(f"--secret {file}: cannot read it: {exc.strerror or exc}") from None
        if not text or not text[0].strip():
            raise UserError(f"--secret {file}: the file is empty (hint: write the course's secret on its first line)")
        return text[0].strip()
    return os.environ.get(SECRET_VARIABLE) or None


def secret_seed(secret: str, variant: str) -> int:
    """A generated maze's seed drawn from the course's ``secret`` and the variant's name: the same
    for the same secret, unguessable without it.

    >>> secret_seed("course secret", "hidden_1") == secret_seed("course secret", "hidden_1")
    True
    >>> secret_seed("course secret", "hidden_1") != secret_seed("another", "hidden_1")
    True
    """
    import hashlib

    digest = hashlib.sha256(f"{secret}\0{variant}".encode()).digest()
    return int.from_bytes(digest[:4], "big") % 2**31


def _generated(variant: Variant, secret: str | None = None) -> tuple[Maze, str | None]:
    """The variant's generated maze, and its turns when it is a corridor."""
    spec = variant.generate
    assert spec is not None
    if spec.seed == "secret":
        if not secret:
            raise UserError(
                Problem(
                    f"variant '{variant.name}': its maze's seed is secret, and no secret was given",
                    path="generate",
                    hint=f"set {SECRET_VARIABLE} or give grade --secret FILE",
                )
            )
        drawn = variant.model_copy(
            update={"generate": spec.model_copy(update={"seed": secret_seed(secret, variant.name)})}
        )
        maze, turns = _generated(drawn)
        return maze.model_copy(update={"name": variant.name}), turns  # its name keeps the seed secret
    assert isinstance(spec.seed, int)
    if spec.kind == "perfect":
        return perfect_maze(spec.cols, spec.rows, spec.seed, cell=spec.cell), None
    if spec.kind == "contest":
        from thymio_bt.maze.micromouse import maze_from_cells

        return maze_from_cells(contest_maze(spec.seed, spec.size), f"contest_{spec.size}_seed{spec.seed}"), None
    wanted = {"left": "R", "right": "L", "any": ""}[spec.turns]  # the turn it must not have
    for attempt in range(10_000):
        path = random_path(spec.length, spec.seed * 10_007 + attempt)
        turns = turns_along(path)
        if len(turns) >= spec.length // 3 and not (wanted and wanted in turns):  # a turn every 3 cells
            maze = path_maze(path, cell=spec.cell)
            return maze.model_copy(update={"name": f"path_{spec.length}_seed{spec.seed}"}), turns
    raise ValueError(f"no corridor of {spec.length} cells with only {spec.turns} turns")


def variant_mission(
    mission_path: str | Path, variant: Variant, run_plugins: bool = True, base: Path | None = None
) -> Mission:
    """The mission at ``mission_path`` in ``variant``'s world (a made maze goes to a temporary
    folder; ``base``: the folder the variant's maze file is relative to, the current one if None; a
    secret seed from :data:`SECRET_VARIABLE`)."""
    import tempfile

    folder = Path(tempfile.mkdtemp(prefix="thymio-bt-world-"))
    return World.of(variant, base or Path("."), folder, course_secret()).mission(mission_path, run_plugins)


def make_worlds(assignment: Assignment, path: Path, folder: Path) -> list[World]:
    """Every variant's world (made mazes written into ``folder``); the variants that cannot be made
    are one :class:`UserError`, each problem at its variant's place in the assignment file ``path``."""
    from thymio_bt.inputs.yamlio import load_yaml

    worlds, problems = _worlds(list(enumerate(assignment.variants)), load_yaml(path, "assignment"), path, folder)
    if problems:
        raise UserError(problems)
    return worlds


def load_worlds(
    path: str | Path, folder: Path, secret: str | None = None, hidden_folder: Path | None = None
) -> tuple[Assignment, list[World]]:
    """Read the assignment at ``path`` and make its worlds in ``folder`` (the hidden variants' in
    ``hidden_folder``, when given; ``secret``: the course's, for secret seeds): every problem of the
    file, its schema, variants, criteria, palette, mazes and starts, found and reported at once."""
    from thymio_bt.grade.assignment import read_assignment

    reading = read_assignment(path)
    worlds, problems = _worlds(reading.variants, reading.data, Path(reading.file), folder, secret, hidden_folder)
    problems = reading.problems + problems
    if problems or reading.assignment is None:
        raise UserError(problems)
    return reading.assignment, worlds


def _worlds(
    variants: list[tuple[int, Variant]],
    data: Any,
    path: Path,
    folder: Path,
    secret: str | None = None,
    hidden_folder: Path | None = None,
) -> tuple[list[World], list[Problem]]:
    """The worlds of ``variants`` (each with its index in the file; made mazes into ``folder``, a
    hidden variant's into ``hidden_folder`` when given) and the problems of those that cannot be
    made."""
    from thymio_bt.inputs.validation import locate

    worlds, problems = [], []
    for i, variant in variants:
        try:
            made_in = hidden_folder if variant.visibility == "hidden" and hidden_folder is not None else folder
            worlds.append(World.of(variant, path.parent, made_in, secret))
        except UserError as exc:
            for problem in exc.problems:
                key = "start" if problem.path == "start" else "generate" if variant.generate is not None else "maze"
                line, column = locate(data, ["variants", i, key])
                problems.append(Problem(problem.message, str(path), line, column, f"variants.{i}.{key}", problem.hint))
    return worlds, problems
