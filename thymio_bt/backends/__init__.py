"""Robot backends by name: what ``--backend NAME`` may be, and how each is made.

A backend is a :class:`~thymio_bt.robot.interface.Backend` (the pymunk simulation, a Thymio over Aseba or
ROS 2, ...). Each kind registers a :class:`BackendKind`: a name, a one-line summary, a pydantic model
of its settings (``--backend-opt KEY=VALUE`` or a mission's ``backend:`` block), and a factory named
as ``"module:function"`` so that choosing one backend never imports the others' libraries.
Plugins add kinds through the ``thymio_bt.backends`` entry-point group, whose entries point to a
:class:`BackendKind`.

Example::

    >>> from thymio_bt.mission import load_mission
    >>> kind = backend_kind("sim")
    >>> kind.realtime, kind.parse_options({"physics_hz": "200"}).physics_hz
    (False, 200.0)
    >>> backend = kind.create(load_mission("maze_part1_2"), seed=0, options={"physics_hz": "200"})
    >>> backend.model.name, backend.time()
    ('course', 0.0)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Protocol

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from thymio_bt.errors import Problem, UserError, did_you_mean
from thymio_bt.named import named
from thymio_bt.robot.model import DEFAULT_ROBOT

if TYPE_CHECKING:
    from pathlib import Path

    from thymio_bt.geometry import Pose
    from thymio_bt.maze import Maze
    from thymio_bt.robot.interface import Backend
    from thymio_bt.robot.model import RobotModel
    from thymio_bt.robot.noise import NoiseConfig

ENTRY_POINT_GROUP = "thymio_bt.backends"


class MissionWorld(Protocol):
    """What a backend is made from: the parts of a mission it reads. A
    :class:`~thymio_bt.plan.model.Mission` is one; the backends, below the mission in the layers,
    name only these."""

    @property
    def maze(self) -> Maze:
        """The maze the robot is in."""
        ...

    @property
    def maze_file(self) -> Path | None:
        """The file the maze was read from (None: a maze given as data)."""
        ...

    @property
    def start(self) -> Pose:
        """Where the robot starts (base_link, world frame)."""
        ...

    @property
    def robot(self) -> str | None:
        """The robot model's name, or a profile file (None: the mission names none)."""
        ...

    @property
    def sensor_model(self) -> str:
        """How a simulation turns a range into a reading."""
        ...

    @property
    def noise(self) -> NoiseConfig:
        """The simulation's noise settings."""
        ...


class BackendOptions(BaseModel):
    """Settings of a backend; subclasses add fields (each with a description: ``--help`` shows it)."""

    model_config = ConfigDict(extra="forbid")


@dataclass(frozen=True)
class BackendKind:
    """One kind of backend: ``factory(mission, seed, options)`` makes a connected, ready backend."""

    name: str
    summary: str
    factory: str | Callable[[MissionWorld, int, Any], Backend]
    #: the settings' model, or where it is (``"module:attr"``, imported when first read: a run reads
    #: only its own backend's)
    options: str | type[BackendOptions] = BackendOptions
    #: whether runs on it take real time (a real robot, a real-time simulator)
    realtime: bool = False
    #: the robot model it drives when the mission names none: the course's (the simulator's Gazebo
    #: robot), a real Thymio's ``real``, the Playground's ``enki``
    robot: str = DEFAULT_ROBOT

    def parse_options(self, raw: Mapping[str, Any], where: tuple[str, int, int] = ("--backend-opt", 0, 0)) -> Any:
        """Validate ``raw`` settings against :attr:`options`; :class:`UserError` says what is wrong."""
        from thymio_bt.inputs.validation import Wording, problems_from

        options = self.options_model()
        try:
            return options.model_validate(dict(raw))
        except ValidationError as exc:
            wording = Wording(
                unknown=f"backend '{self.name}' has no option '{{key}}'",
                missing=f"backend '{self.name}' needs option '{{key}}'",
                invalid=f"backend '{self.name}' option '{{path}}': {{msg}}",
            )
            problems = problems_from(exc, dict(raw), where[0], options, at=where[1:], wording=wording)
            if not options.model_fields:
                problems = [replace(p, hint=f"backend '{self.name}' takes no options") for p in problems]
            raise UserError(problems) from None

    def create(self, mission: MissionWorld, seed: int, options: Mapping[str, Any] | None = None) -> Backend:
        """A backend of this kind for ``mission``, with ``options`` validated first."""
        parsed = self.parse_options(options or {})
        factory: Callable[[MissionWorld, int, Any], Backend] = named(self.factory)
        return factory(mission, seed, parsed)

    def options_model(self) -> type[BackendOptions]:
        """The model of this kind's settings (its module imported now if :attr:`options` names it)."""
        model: type[BackendOptions] = named(self.options)
        return model


def placed_option() -> Any:
    """A ``placed`` option (for a backend's options model): the robot stands at the mission's start already."""
    return Field(
        False,
        description="the robot already stands at the mission's start: no operator is asked to place it "
        "(for a run with nobody at the keyboard; a later respawn still asks)",
    )


def latency_option(default: float, more: str) -> Any:
    """A ``latency`` option (s, 0 to 2) for a backend's options model, its description ending with ``more``."""
    return Field(
        default, ge=0, le=2, description="seconds from the world a reading shows to a new command acting" + more
    )


#: The backends that come with thymio-bt.
BUILTIN: dict[str, BackendKind] = {
    kind.name: kind
    for kind in (
        BackendKind(
            "sim",
            "the pymunk simulation of the mission's maze (default; instant, deterministic)",
            "thymio_bt.backends.sim.backend:create",
            "thymio_bt.backends.sim.options:SimOptions",
        ),
        BackendKind(
            "tdm",
            "a Thymio through Thymio Suite's Thymio Device Manager (needs thymio-bt[thymio]; "
            "untested here: no registry has the Device Manager)",
            "thymio_bt.backends.real.thymio:create_tdm",
            "thymio_bt.backends.real.options:TdmOptions",
            realtime=True,
            robot="real",
        ),
        BackendKind(
            "aseba",
            "a Thymio over its own Aseba protocol: on USB, or a simulated one on TCP (needs thymio-bt[aseba])",
            "thymio_bt.backends.real.aseba:create_aseba",
            "thymio_bt.backends.real.options:AsebaOptions",
            realtime=True,
            robot="real",
        ),
        BackendKind(
            "playground",
            "the Aseba Playground (Enki) started headless on the mission's maze, driven "
            "over Aseba like a real Thymio, in real time (needs the aseba package and thymio-bt[aseba])",
            "thymio_bt.backends.playground.backend:create_playground",
            "thymio_bt.backends.playground.options:PlaygroundOptions",
            realtime=True,
            robot="enki",
        ),
        BackendKind(
            "ros2",
            "a Thymio through ROS 2 topics and services: the course's Gazebo, 'thymio-bt serve ros2' "
            "or a robot's driver (needs rclpy: see scripts/ros2-env.sh)",
            "thymio_bt.backends.ros2.backend:create_ros2",
            "thymio_bt.backends.ros2.options:Ros2Options",
            realtime=True,
        ),
    )
}


def backend_kinds() -> dict[str, BackendKind]:
    """Every backend kind: the built-in ones, then those of installed plugins (entry points)."""
    from importlib.metadata import entry_points

    kinds = dict(BUILTIN)
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name not in kinds:
            kind = ep.load()
            if not isinstance(kind, BackendKind):
                raise UserError(
                    f"backend plugin '{ep.name}' ({ep.value}) is not a BackendKind "
                    f"(hint: point the entry point at a thymio_bt.backends.BackendKind)"
                )
            kinds[ep.name] = kind
    return kinds


def backend_kind(name: str) -> BackendKind:
    """The backend kind called ``name``; a :class:`UserError` naming the known ones otherwise."""
    if name in BUILTIN:
        return BUILTIN[name]
    kinds = backend_kinds()
    if name not in kinds:
        raise UserError(Problem(f"no backend named '{name}'", "--backend", hint=did_you_mean(name, kinds)))
    return kinds[name]


def robot_for(mission: MissionWorld, backend: str, say: Callable[[str], None] | None = None) -> RobotModel:
    """The robot model backend ``backend`` drives ``mission`` with: the mission's (its ``robot:``
    or ``--robot``), or when it names none the backend's own (:attr:`BackendKind.robot`), and
    ``say`` (standard error by default) tells the user if that is not the course's. A wrong model
    is no small matter: the course's sensor model on Enki's robot took a wall it was pushing for
    open space and reported SUCCESS.

    >>> from thymio_bt.mission import load_mission
    >>> robot_for(load_mission("maze_part1_2"), "sim").name
    'course'
    >>> robot_for(load_mission("maze_part1_2"), "playground", say=print).name
    [thymio-bt] --backend playground: robot model 'enki', not the course's (--robot chooses): Enki's Thymio2 ...
    'enki'
    >>> robot_for(load_mission("maze_part1_2", overrides={"--robot": "course"}), "playground").name
    'course'
    """
    from thymio_bt.robot.model import robot_model

    own = backend_kind(backend).robot
    if mission.robot is not None or own == DEFAULT_ROBOT:
        return robot_model(mission.robot)
    model = robot_model(own)
    text = (
        f"[thymio-bt] --backend {backend}: robot model '{own}', not the course's (--robot chooses): {model.description}"
    )
    if say is None:
        import sys

        print(text, file=sys.stderr)
    else:
        say(text)
    return model
