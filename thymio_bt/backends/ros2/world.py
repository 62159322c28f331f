"""What ``thymio-bt serve ros2`` tells its clients: which world it serves, and how to step it in lock.

The stand-in publishes a :class:`WorldInfo` as JSON in a std_msgs/String on ``/thymio_bt/world``,
latched (transient local, depth 1): any node that subscribes later, at any time, gets it at once,
``ros2 topic echo /thymio_bt/world`` shows it, and nothing is sent when nobody listens. The course's
Gazebo publishes no such topic: a client that hears none knows nothing of the world, and checks
nothing.

``--backend ros2`` reads it to refuse a mission on another maze (:func:`maze_problem`: the run would
drive blind into walls it does not know) and to step the world in lock (:data:`STEP_TOPIC`).

Lockstep: each tick the client publishes a geometry_msgs/TwistStamped on :data:`STEP_TOPIC`: "drive with this
twist until ``header.stamp``". The stand-in steps its physics until that simulated time, publishes
what it senses there, then holds (the clock stops) until the next one, and says where it holds on
:data:`HELD_TOPIC` (a std_msgs/Header: ``stamp`` that time, ``frame_id`` the robot's name when the
robot is in the world, else empty). ``header.frame_id == "release"`` lets it run freely again, as does a
client that goes away or stays silent for :data:`HOLD_TIMEOUT` wall seconds.

Example::

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> from thymio_bt.robot.interface import Pose
    >>> maze = load_maze(resolve_maze("two_parts_maze"))
    >>> info = WorldInfo.of(maze, Pose(0.1, 0.1, 0.0), "course", 4.0)
    >>> WorldInfo.from_json(info.to_json()) == info
    True
    >>> maze_problem(info, maze) is None
    True
    >>> other = load_maze(resolve_maze("maze_6x6"))
    >>> print(maze_problem(info, other))
    the server serves maze 'two_parts_maze' (robot at x=0.1 y=0.1 yaw=0), not the mission's 'maze_6x6'
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass

from thymio_bt.geometry import Pose
from thymio_bt.maze import Maze

#: the latched topic where ``serve ros2`` says what it serves
WORLD_TOPIC = "/thymio_bt/world"
#: a client's command of a tick and the simulated time the world may run until (TwistStamped)
STEP_TOPIC = "/thymio_bt/step"
#: where the stand-in holds, waiting for the next step (std_msgs/Header)
HELD_TOPIC = "/thymio_bt/held"
#: ``header.frame_id`` of a step message that lets the world run freely again
RELEASE = "release"
#: a held world runs freely again after this many wall seconds without a step message
HOLD_TIMEOUT = 10.0


def maze_digest(maze: Maze) -> str:
    """A short digest of the maze's geometry (walls, obstacles: their corners to the µm); two mazes
    with the same digest are the same world, whatever their names or files.

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> len(maze_digest(load_maze(resolve_maze("two_parts_maze"))))
    16
    """
    shapes = [[(round(x, 6), round(y, 6)) for x, y in shape.corners()] for shape in maze.shapes()]
    return hashlib.sha256(json.dumps(sorted(shapes)).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class WorldInfo:
    """What a ``serve ros2`` serves: the maze (name, geometry digest), the robot's start, the robot
    model, the speed-up, and whether it steps in lock (on :data:`STEP_TOPIC` and :data:`HELD_TOPIC`)."""

    maze: str
    digest: str
    start: tuple[float, float, float]
    robot: str
    speedup: float
    lockstep: bool = True

    @classmethod
    def of(cls, maze: Maze, start: Pose, robot: str, speedup: float) -> WorldInfo:
        """The information of a stand-in serving ``maze`` with the robot at ``start``."""
        return cls(maze.name, maze_digest(maze), start.as_tuple(), robot, speedup)

    def to_json(self) -> str:
        """The JSON text published on :data:`WORLD_TOPIC`."""
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> WorldInfo | None:
        """The information in a :data:`WORLD_TOPIC` message; None when it is not one (another tool's).

        >>> WorldInfo.from_json("not json") is None
        True
        """
        try:
            data = json.loads(text)
            data["start"] = tuple(data["start"])
            return cls(**{key: data[key] for key in cls.__dataclass_fields__ if key in data})
        except (ValueError, TypeError, KeyError):
            return None

    def where(self) -> str:
        """The start as the messages say it."""
        x, y, yaw = self.start
        return f"x={x:g} y={y:g} yaw={yaw:g}"


def maze_problem(info: WorldInfo, maze: Maze) -> str | None:
    """Why a mission on ``maze`` cannot run in the world ``info`` describes (another maze), or None."""
    if info.digest == maze_digest(maze):
        return None
    return f"the server serves maze '{info.maze}' (robot at {info.where()}), not the mission's '{maze.name}'"
