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
from importlib import import_module
from typing import TYPE_CHECKING, Any, Literal, Protocol

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from thymio_bt.errors import Problem, UserError, did_you_mean
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
    options: type[BackendOptions] = BackendOptions
    #: whether runs on it take real time (a real robot, a real-time simulator)
    realtime: bool = False
    #: the robot model it drives when the mission names none: the course's (the simulator's Gazebo
    #: robot), a real Thymio's ``real``, the Playground's ``enki``
    robot: str = DEFAULT_ROBOT

    def parse_options(self, raw: Mapping[str, Any], where: tuple[str, int, int] = ("--backend-opt", 0, 0)) -> Any:
        """Validate ``raw`` settings against :attr:`options`; :class:`UserError` says what is wrong."""
        from thymio_bt.inputs.validation import Wording, problems_from

        try:
            return self.options.model_validate(dict(raw))
        except ValidationError as exc:
            wording = Wording(
                unknown=f"backend '{self.name}' has no option '{{key}}'",
                missing=f"backend '{self.name}' needs option '{{key}}'",
                invalid=f"backend '{self.name}' option '{{path}}': {{msg}}",
            )
            problems = problems_from(exc, dict(raw), where[0], self.options, at=where[1:], wording=wording)
            if not self.options.model_fields:
                problems = [replace(p, hint=f"backend '{self.name}' takes no options") for p in problems]
            raise UserError(problems) from None

    def create(self, mission: MissionWorld, seed: int, options: Mapping[str, Any] | None = None) -> Backend:
        """A backend of this kind for ``mission``, with ``options`` validated first."""
        parsed = self.parse_options(options or {})
        factory = self.factory
        if isinstance(factory, str):
            module, _, attr = factory.partition(":")
            factory = getattr(import_module(module), attr)
        return factory(mission, seed, parsed)


class SimOptions(BackendOptions):
    """The ``sim`` backend's settings: the physics sub-step rate."""

    physics_hz: float = Field(100.0, ge=50.0, le=2000.0, description="physics sub-steps per simulated second")


def _placed() -> Any:
    """A ``placed`` option: the robot stands at the mission's start already."""
    return Field(
        False,
        description="the robot already stands at the mission's start: no operator is asked to place it "
        "(for a run with nobody at the keyboard; a later respawn still asks)",
    )


class TdmOptions(BackendOptions):
    """The ``tdm`` backend's settings: where the Thymio Device Manager is."""

    host: str | None = Field(None, description="Thymio Device Manager host (default: found on this machine)")
    port: int | None = Field(None, ge=1, le=65535, description="Thymio Device Manager TCP port")
    password: str | None = Field(None, description="Thymio Device Manager password, if it has one")
    placed: bool = _placed()


def _latency(default: float, more: str) -> Any:
    """A ``latency`` option (s, 0 to 2), its description ending with ``more``."""
    return Field(
        default, ge=0, le=2, description="seconds from the world a reading shows to a new command acting" + more
    )


class AsebaOptions(BackendOptions):
    """The ``aseba`` backend's settings: the device, how long to wait, and the robot's latency."""

    device: str = Field(
        "", description="tcp:HOST:PORT, a serial port such as /dev/ttyACM0, or empty for the only Thymio plugged in"
    )
    timeout: float = Field(5.0, gt=0, le=60, description="how long to wait for the robot to answer (s)")
    latency: float = _latency(
        0.2, " (behaviours stop early by it); 0.2 was measured on the Playground, measure your robot's"
    )
    placed: bool = _placed()


class PlaygroundOptions(BackendOptions):
    """The ``playground`` backend's settings: start-up wait, latency, the speed calibration and Enki's sensor fix."""

    timeout: float = Field(10.0, gt=0, le=60, description="how long to wait for the Playground to start (s)")
    latency: float = _latency(
        0.2,
        ", for the behaviours (measured: readings 40-120 ms behind the true pose, a new motor target acting "
        "~100 ms later)",
    )
    speed_scale: float | None = Field(
        None,
        gt=0.5,
        le=2,
        description="the Playground's Thymio's speed per motor "
        "unit over the robot model's; default: 0.985 (measured against its ground "
        "truth) for a built-in model, 1 for a profile measured by thymio-bt calibrate",
    )
    enki_fix: bool = Field(
        True,
        description="correct Enki 1.6.99's stale sensor rays (enki-community/enki#68) in the Playground "
        "(needs g++ and libenki-dev; false runs Enki as installed)",
    )


class Ros2Options(BackendOptions):
    """The ``ros2`` backend's settings: the topic map, the clock, the latency and the robot's URDF."""

    topics: str = Field("", description="a YAML topic map (default: the course's Gazebo topics and services)")
    timeout: float = Field(
        5.0,
        gt=0,
        le=120,
        description="how long a topic may stay silent, or a service "
        "take to appear or answer, before the run fails (wall s)",
    )
    clock: Literal["auto", "sim", "wall"] = Field(
        "auto",
        description="the run's time: the /clock of a simulator (sim), the wall clock (wall), or sim "
        "when someone publishes /clock (auto)",
    )
    latency: float = _latency(0.0, " (behaviours stop early by it); measure a real robot's")
    robot_xml: str = Field("", description="URDF/SDF file sent when spawning (default: /robot_description)")


#: The backends that come with thymio-bt.
BUILTIN: dict[str, BackendKind] = {
    kind.name: kind
    for kind in (
        BackendKind(
            "sim",
            "the pymunk simulation of the mission's maze (default; instant, deterministic)",
            "thymio_bt.backends.sim.backend:create",
            SimOptions,
        ),
        BackendKind(
            "tdm",
            "a Thymio through Thymio Suite's Thymio Device Manager (needs thymio-bt[thymio]; "
            "untested here: no registry has the Device Manager)",
            "thymio_bt.backends.real.thymio:create_tdm",
            TdmOptions,
            realtime=True,
            robot="real",
        ),
        BackendKind(
            "aseba",
            "a Thymio over its own Aseba protocol: on USB, or a simulated one on TCP (needs thymio-bt[aseba])",
            "thymio_bt.backends.real.aseba:create_aseba",
            AsebaOptions,
            realtime=True,
            robot="real",
        ),
        BackendKind(
            "playground",
            "the Aseba Playground (Enki) started headless on the mission's maze, driven "
            "over Aseba like a real Thymio, in real time (needs the aseba package and thymio-bt[aseba])",
            "thymio_bt.backends.playground.backend:create_playground",
            PlaygroundOptions,
            realtime=True,
            robot="enki",
        ),
        BackendKind(
            "ros2",
            "a Thymio through ROS 2 topics and services: the course's Gazebo, 'thymio-bt serve ros2' "
            "or a robot's driver (needs rclpy: see scripts/ros2-env.sh)",
            "thymio_bt.backends.ros2.backend:create_ros2",
            Ros2Options,
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
