"""``--backend playground``: a mission on the Aseba Playground's simulated Thymio, in real time.

The robot is driven exactly as a real Thymio is (:class:`~thymio_bt.backends.real.thymio.ThymioRobot` over
:class:`~thymio_bt.backends.real.aseba.AsebaNode`: odometry from its wheel speeds, its own proximity
readings); what only a simulator gives comes from the Playground's D-Bus interface: the true pose
(the report's pose and trajectory, the clearance to the maze's walls and contact episodes, all from
geometry), spawning (teleport) and deleting (parking the robot in a bay beside the maze).

From the shell (the Playground installed)::

    thymio-bt run missions/maze_part1_2.yaml --backend playground --robot enki
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

from thymio_bt.backends.playground.enki import EnkiRobot
from thymio_bt.backends.playground.enki_fix import HINT, enki_fix
from thymio_bt.backends.playground.process import Playground
from thymio_bt.backends.playground.world import PlaygroundWorld, playground_world
from thymio_bt.backends.real.aseba import AsebaNode
from thymio_bt.backends.real.thymio import ThymioRobot
from thymio_bt.geometry import Pose, wrap_angle
from thymio_bt.maze import Maze
from thymio_bt.robot.interface import RobotLost
from thymio_bt.robot.model import ROBOTS, RobotModel
from thymio_bt.robot.placement import ContactTracker, placement_problem

if TYPE_CHECKING:
    from thymio_bt.backends import MissionWorld
    from thymio_bt.backends.playground.options import PlaygroundOptions

#: the Playground's Thymio covers this fraction of what its motor units say (Enki's 16.6 cm/s at 500):
#: against its ground truth, 2.9 s straight read 0.983, 2.1 s turning 0.985, thymio-bt calibrate 0.986
#: (its simulated time runs behind the wall clock, or its wheels slip); odometry 1.5 % long made each
#: 90° turn 1.4° short and maze_bonus lose its way, and with it the bonus succeeds
SPEED_SCALE = 0.985

#: after a teleport, how long (real s) until the robot's cached readings are from its new place: a
#: Playground step (~30 ms) and two refreshes of the variables (50 ms each), with room to spare
SETTLE = 0.2


class PlaygroundRobot(ThymioRobot):
    """A :class:`ThymioRobot` whose world is a Playground it started (and stops on :meth:`close`)."""

    def __init__(
        self,
        node: AsebaNode,
        playground: Playground,
        enki: EnkiRobot,
        world: PlaygroundWorld,
        maze: Maze,
        model: RobotModel,
        speed_scale: float,
        latency: float = 0.2,
    ) -> None:
        self.playground, self.enki, self.world, self.maze = playground, enki, world, maze
        self._contacts = ContactTracker(maze, model)
        self.latency = latency
        # deleting needs nobody: the robot is parked
        super().__init__(node, say=lambda text: None, model=model, speed_scale=speed_scale)

    def true_pose(self) -> Pose | None:
        """The pose the simulation has (None once the Playground is gone)."""
        try:
            return self._truth()
        except RobotLost:
            return None

    def _truth(self) -> Pose | None:
        if not self._present:
            return None
        x_cm, y_cm, angle = self.enki.pose()
        x, y = self.world.from_enki(x_cm, y_cm)
        base = self.model.base_of(x, y, angle)
        return Pose(base.x, base.y, wrap_angle(angle))  # the range of the simulator's ground truth

    def spawn_problem(self, name: str, pose: Pose) -> str | None:
        """Why the robot cannot stand at ``pose``: a real robot's reasons, then the maze's geometry."""
        return super().spawn_problem(name, pose) or (
            placement_problem(self.maze, self.model, pose) if self.maze.walls or self.maze.obstacles else None
        )

    def advance(self, duration: float) -> None:
        """A real robot's tick, then the clearance and contacts of the Playground's true pose."""
        super().advance(duration)
        self._contacts.update(self, self._truth())  # RobotLost when the Playground is gone: the run ends there

    def _place_entity(self, name: str, pose: Pose) -> str | None:
        self.device.set_motors(0, 0)
        x, y, yaw = self.model.axle_of(pose)
        self.enki.place(*self.world.to_enki(x, y), yaw)
        self._sleep(SETTLE)  # the robot's readings are from before the teleport until then
        self._place(pose)
        return None

    def _remove(self, name: str) -> str | None:
        problem = super()._remove(name)
        if problem is None:
            self.enki.place(*self.world.to_enki(*self.world.parking), 0.0)
        return problem

    def close(self) -> None:
        """Stop the robot, then the D-Bus connection and the Playground with its bus."""
        try:
            super().close()
        finally:
            self.enki.close()
            self.playground.stop()


#: whether the warning that Enki's sensors could not be corrected was given (once per process)
_WARNED: list[str] = []


def _enki_fix() -> Path | None:
    """The library correcting Enki's stale sensor rays (:mod:`.enki_fix`); None, with a warning
    the first time, when it cannot be built here."""
    library, why = enki_fix()
    if library is None and not _WARNED:
        _WARNED.append(why)
        sys.stderr.write(
            "warning: the Playground's Enki 1.6.99 keeps stale sensor rays (enki-community/enki#68), so its "
            f"readings can show walls that are not there; {why} (hint: {HINT})\n"
        )
    return library


def create_playground(mission: MissionWorld, seed: int, options: PlaygroundOptions) -> PlaygroundRobot:
    """The ``playground`` backend kind: start a Playground on the mission's maze, connect to its
    Thymio; its model is ``enki`` unless the mission names another than the course's."""
    from thymio_bt.backends import robot_for

    model = robot_for(mission, "playground")
    world = playground_world(mission.maze, Pose(*model.axle_of(mission.start)), port=0)  # its own pick
    playground = Playground.start(world.text, options.timeout, _enki_fix() if options.enki_fix else None)
    try:
        node = AsebaNode.connect(f"tcp:127.0.0.1:{playground.port}", options.timeout)
        enki = EnkiRobot.find(playground.bus, options.timeout)
    except BaseException:
        playground.stop()
        raise
    scale = options.speed_scale
    if scale is None:
        scale = SPEED_SCALE if ROBOTS.get(model.name) is model else 1.0  # a profile measured its own
    return PlaygroundRobot(node, playground, enki, world, mission.maze, model, scale, options.latency)
