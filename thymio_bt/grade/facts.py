"""A finished run as the checks see it (:class:`RunFacts`): its ground truth, the maze, the robot
and what the variant expects, with what the checks ask of it: where the robot was at a moment, when
it arrived there and which node drove it, when a phase began, the turns of its route and its
cruise speed.

Example::

    >>> from thymio_bt.maze.generate import path_maze
    >>> from thymio_bt.robot.model import robot_model
    >>> from types import SimpleNamespace
    >>> drive = [(0.1 * i, 0.1 + 0.04 * i, 0.1, 0.0) for i in range(11)]   # 40 cm/s to x = 0.5
    >>> model = robot_model("course")
    >>> axle = model.axle_of(Pose(0.5, 0.1, 0.0))                         # then a turn on the spot
    >>> turn = [(1.0 + 0.1 * i, p.x, p.y, p.yaw) for i in range(1, 6) for p in [model.base_of(*axle[:2], 0.3 * i)]]
    >>> events = [{"t": 1.0, "kind": "behaviour_end", "name": "MoveUntilWall", "path": "m/go"},
    ...           {"t": 1.5, "kind": "behaviour_end", "name": "TurnAngle", "path": "m/turn"}]
    >>> run = SimpleNamespace(trajectory=drive + turn, events=events)
    >>> facts = RunFacts(run, path_maze([(0, 0), (1, 0), (2, 0)]), model, time_limit=60.0)
    >>> facts.arrived(), facts.node_that_drove(), facts.node_before(math.inf)
    (1.0, 'm/go', 'm/turn')
    >>> speed, t = cruise_speed(facts, 0.0, math.inf)
    >>> round(speed, 3), 0 < t <= 1.0
    (0.4, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from typing import TYPE_CHECKING, Any

from thymio_bt.geometry import Pose
from thymio_bt.grade.assignment import GoalDisc
from thymio_bt.maze import Maze
from thymio_bt.robot.model import RobotModel

if TYPE_CHECKING:
    from thymio_bt.run.result import RunResult

#: a quarter heading is a turn of the route once the robot has driven this far (m) holding it: a look
#: to the side and back, turning on the spot, is not a turn taken
TURN_TRAVEL = 0.02
#: the robot has arrived where it stops once its wheel axle stays this close (m) to that place
ARRIVED = 0.003
#: the robot has come to rest once it stays in place this long (s)
REST = 0.5
#: the phase markers every run knows, by the event that marks them
MARKERS = {"delete": "delete_entity", "spawn": "spawn_entity"}


@dataclass
class RunFacts:
    """A finished run as the checks see it: its result, the maze it ran in (and its grid pitch), the
    robot, and what the variant expects (``goal``, ``turns``)."""

    result: RunResult
    maze: Maze
    model: RobotModel
    time_limit: float
    goal: GoalDisc | None = None
    turns: str | None = None
    #: the maze's grid pitch (m): what "a side wall close by" means at a dead end
    cell: float = 0.2
    cache: dict[str, Any] = field(default_factory=dict)

    def sample(self, t: float | None = None) -> tuple[float, float, float, float] | None:
        """The trajectory's true (t, x, y, yaw) at ``t``: the last sample at or before it, the first
        when none is; the end when ``t`` is None; None without a trajectory."""
        trajectory = self.result.trajectory
        if not trajectory:
            return None
        if t is None:
            return trajectory[-1]
        return max((s for s in trajectory if s[0] <= t + 1e-9), default=trajectory[0], key=lambda s: s[0])

    def moment(self, t: float | None = None) -> dict[str, float] | None:
        """The true position at ``t`` (the end when None), as results show a failing moment."""
        sample = self.sample(t)
        return (
            None if sample is None else {"t": round(sample[0], 3), "x": round(sample[1], 4), "y": round(sample[2], 4)}
        )

    def pose_at(self, t: float | None) -> Pose | None:
        """The true pose at ``t`` (the end when None)."""
        sample = self.sample(t)
        return None if sample is None else Pose(*sample[1:4])

    def first(self, kind: str) -> dict[str, Any] | None:
        """The first event of ``kind``."""
        return next((e for e in self.result.events if e["kind"] == kind), None)

    def node_before(self, t: float, event: dict[str, Any] | None = None) -> str | None:
        """The path of the last node that ended at or before ``t`` (before ``event``, when given):
        the one that brought the robot there."""
        events = self.result.events
        if event is not None:
            events = events[: next((i for i, e in enumerate(events) if e is event), len(events))]
        ended = [e for e in events if e["kind"] == "behaviour_end" and e["t"] <= t + 1e-9]
        return ended[-1]["path"] if ended else None

    def axle(self, sample: tuple[float, float, float, float]) -> tuple[float, float]:
        """Where the wheel axle's centre was at a trajectory ``sample``: the point a turn on the
        spot leaves in place (base_link, ahead of it, swings 2.4 cm in a quarter turn)."""
        return self.model.axle_of(Pose(*sample[1:4]))[:2]

    def arrived(self, t: float | None = None) -> float | None:
        """When the robot reached the place it is at at ``t`` (the end when None) and stayed within
        :data:`ARRIVED` of it (its axle: turning on the spot is staying): the moment its last
        drive there ended."""
        trajectory = self.result.trajectory
        here = self.sample(t)
        if here is None:
            return None
        at = self.axle(here)
        until = [s for s in trajectory if s[0] <= here[0] + 1e-9]
        for before, after in zip(reversed(until[:-1]), reversed(until), strict=False):
            if math.dist(self.axle(before), at) > ARRIVED:
                return after[0]
        return until[0][0] if until else here[0]

    def first_stop(self) -> float | None:
        """When the robot first came to rest after driving: it then stayed within :data:`ARRIVED`
        of that place for :data:`REST` s (a turn on the spot is rest), or the run ended; None
        without a trajectory."""
        trajectory = self.result.trajectory
        if not trajectory:
            return None
        axles = [self.axle(s) for s in trajectory]
        for i, here in enumerate(trajectory):
            if math.dist(axles[i], axles[0]) <= ARRIVED:
                continue  # not driven yet
            still = [j for j in range(i, len(trajectory)) if trajectory[j][0] <= here[0] + REST + 1e-9]
            rested = trajectory[still[-1]][0] >= here[0] + REST - 1e-9
            if rested and all(math.dist(axles[j], axles[i]) <= ARRIVED for j in still):
                return float(here[0])
        return float(trajectory[-1][0])

    def node_that_drove(self, t: float | None = None, event: dict[str, Any] | None = None) -> str | None:
        """The node that brought the robot where it is at ``t`` (the end when None): the first to
        end once it arrived there (it notices its stop a tick later, perhaps), not a turn on the
        spot or a check made after it; only nodes that ended before ``event``, when given."""
        end = math.inf if t is None else t
        arrived = self.arrived(t)
        events = self.result.events
        if event is not None:
            events = events[: next((i for i, e in enumerate(events) if e is event), len(events))]
        if arrived is not None:
            for e in events:
                if e["kind"] == "behaviour_end" and e["t"] >= arrived - 1e-9:
                    return str(e["path"])
        return self.node_before(end, event)

    def node_running(self, t: float) -> str | None:
        """The path of the first node to end at or after ``t``: the one running then."""
        ended = (e for e in self.result.events if e["kind"] == "behaviour_end" and e["t"] >= t - 1e-9)
        return next((str(e["path"]) for e in ended), None)

    def ended(self, node: str) -> dict[str, Any] | None:
        """The first end of a node of type ``node`` (its name) or at a path matching the glob."""
        return next(
            (
                e
                for e in self.result.events
                if e["kind"] == "behaviour_end" and (e["name"] == node or fnmatchcase(e["path"], node))
            ),
            None,
        )

    def marker(self, marker: str) -> float | None:
        """When ``marker`` happened: ``delete`` or ``spawn`` (the first), or a node ended (its type
        or a path glob); None when it never did."""
        event = self.first(MARKERS[marker]) if marker in MARKERS else self.ended(marker)
        return None if event is None else float(event["t"])


def turns_taken(facts: RunFacts) -> list[tuple[str, float]]:
    """The quarter turns of the robot's route (L or R, and when the robot reached each heading), from
    its true poses; a respawn starts the count afresh, and a heading counts once the robot has driven
    :data:`TURN_TRAVEL` holding it (looking to a side and back is no turn)."""
    if "turns" in facts.cache:
        return facts.cache["turns"]
    spawns = [e["t"] for e in facts.result.events if e["kind"] == "spawn_entity"]
    out: list[tuple[str, float]] = []
    quarter = math.pi / 2
    segment_start: float | None = None
    for t, x, y, yaw in facts.result.trajectory:
        if segment_start is None or any(segment_start < s <= t for s in spawns):
            segment_start, base, heading, stable, candidate, since, origin = t, yaw, yaw, 0, 0, t, (x, y)
            continue
        # not wrap_angle: math.remainder is exact where wrap_angle rounds (kept: the same bits as before)
        heading += math.remainder(yaw - heading, math.tau)  # unwrapped
        steps = (heading - base) / quarter
        q = round(steps)
        if abs(steps - q) > 1 / 3:  # between two quarter headings: no decision
            continue
        if q != candidate:
            candidate, since, origin = q, t, (x, y)
        elif q != stable and math.hypot(x - origin[0], y - origin[1]) >= TURN_TRAVEL - 1e-9:
            out += [("L" if q > stable else "R", since)] * abs(q - stable)
            stable = q
    facts.cache["turns"] = out
    return out


def cruise_speed(facts: RunFacts, start: float, end: float) -> tuple[float, float] | None:
    """The robot's cruise speed (m/s) between ``start`` and ``end``, and a moment it drove at it:
    the median of its speeds while it drove at least half its top speed of the phase (not
    speeding up, slowing at a wall, turning on the spot); None when it never moved. A respawn is
    a jump, not a drive."""
    spawns = [e["t"] for e in facts.result.events if e["kind"] == "spawn_entity"]
    samples = [s for s in facts.result.trajectory if start - 1e-9 <= s[0] <= end + 1e-9]
    speeds = [
        (math.dist(a[1:3], b[1:3]) / (b[0] - a[0]), b[0])
        for a, b in zip(samples, samples[1:], strict=False)
        if b[0] > a[0] and not any(a[0] < s <= b[0] for s in spawns)
    ]
    top = max((v for v, _ in speeds), default=0.0)
    if top < 1e-3:
        return None
    cruising = sorted((v, t) for v, t in speeds if v >= top / 2)
    return cruising[len(cruising) // 2]
