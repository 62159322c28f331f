"""The checks a criterion makes on one finished run, on its ground truth (the simulator's poses,
the maze's geometry, the run's events), never on what the tree itself returned.

Each check answers with a :class:`Judgement`: passed or not, the feedback a student can act on
("stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm"), the moment it went wrong and the node to
blame, if one is.

Example::

    >>> from thymio_bt.grade.assignment import Criterion
    >>> from thymio_bt.maze.generate import path_maze
    >>> from thymio_bt.robot.model import robot_model
    >>> from types import SimpleNamespace
    >>> maze = path_maze([(0, 0), (1, 0), (2, 0)])     # a corridor 0.6 m long, closed at x = 0.6
    >>> run = SimpleNamespace(status="SUCCESS", reason=None, failed_path=None, sim_time=1.0,
    ...     final_pose={"x": 0.469, "y": 0.1, "yaw": 0.0}, collisions=0, min_clearance=0.04, events=[],
    ...     trajectory=[(0.1 * i, 0.1 + 0.0369 * i, 0.1, 0.0) for i in range(11)], goal=None)
    >>> seen = RunFacts(run, maze, robot_model("course"), time_limit=60.0)
    >>> gap = Criterion(name="stop", points=1, gap={"at": "end", "distance": "5cm", "tolerance": "5mm"})
    >>> judged = judge(gap, seen)
    >>> judged.passed, judged.feedback, judged.moment
    (False, 'stopped 7.0 cm from the wall, wanted 5.0 +- 0.5 cm', {'t': 1.0, 'x': 0.469, 'y': 0.1})
    >>> judge(Criterion(name="forward", points=1, no_reverse=True), seen).passed
    True
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from typing import Any

from thymio_bt.grade.assignment import Criterion, GoalDisc
from thymio_bt.maze import Maze
from thymio_bt.mission.expect import stop_problem
from thymio_bt.robot.interface import Pose
from thymio_bt.robot.model import RobotModel

#: a quarter heading is a turn of the route once the robot has driven this far (m) holding it: a look
#: to the side and back, turning on the spot, is not a turn taken
TURN_TRAVEL = 0.02
#: at a dead end a side wall is at most this many grid pitches from base_link (3/4: the cell's half
#: and room for a robot off its centre line; an open side's ray reaches the next cell's far wall,
#: 1.5 pitches away, or further)
DEAD_END_SIDE = 0.75
#: backwards travel (m) below this is noise, not driving backwards
REVERSE_SLACK = 0.01


@dataclass(frozen=True)
class Judgement:
    """One check on one run: passed, what to tell the student, when it went wrong, whose fault."""

    passed: bool
    feedback: str | None = None
    moment: dict[str, float] | None = None
    path: str | None = None


@dataclass
class RunFacts:
    """A finished run as the checks see it: its result, the maze it ran in (and its grid pitch), the
    robot, and what the variant expects (``goal``, ``turns``)."""

    result: Any
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


def judge(criterion: Criterion, facts: RunFacts) -> Judgement:
    """``criterion``'s check on the run ``facts``."""
    return CHECK_FUNCTIONS[criterion.check](criterion, facts)


def _finishes(criterion: Criterion, facts: RunFacts) -> Judgement:
    run = facts.result
    if run.status == "SUCCESS":
        return Judgement(True)
    if run.status == "TIMEOUT":
        return Judgement(
            False, f"did not end within the time limit ({facts.time_limit:g} s)", facts.moment(), run.failed_path
        )
    return Judgement(False, f"the tree ended {run.status}: {run.reason}", facts.moment(), run.failed_path)


def _no_collision(criterion: Criterion, facts: RunFacts) -> Judgement:
    hit = facts.first("collision")
    if not facts.result.collisions:
        return Judgement(True)
    n = facts.result.collisions
    where = f" first at t = {hit['t']:.1f} s near ({hit['x']:.2f}, {hit['y']:.2f})" if hit else ""
    moment = {"t": hit["t"], "x": hit["x"], "y": hit["y"]} if hit else facts.moment()
    return Judgement(
        False,
        f"touched a wall {n} time{'s' * (n != 1)},{where}",
        moment,
        facts.node_before(moment["t"]) if moment else None,
    )


def _max_time(criterion: Criterion, facts: RunFacts) -> Judgement:
    run, limit = facts.result, criterion.max_time
    assert limit is not None
    if run.status != "TIMEOUT" and run.sim_time <= limit + 1e-9:
        return Judgement(True)
    took = "did not end" if run.status == "TIMEOUT" else f"took {run.sim_time:.1f} s"
    return Judgement(False, f"{took}, wanted at most {limit:g} s", facts.moment(), run.failed_path)


def _goal(criterion: Criterion, facts: RunFacts) -> Judgement:
    pose = facts.pose_at(None) if facts.result.final_pose else None
    disc = criterion.goal if isinstance(criterion.goal, GoalDisc) else facts.goal
    if pose is None:
        return Judgement(False, "no robot at the end of the run", facts.moment())
    if disc is None:
        if not facts.maze.goal:
            return Judgement(False, "this world has no goal to reach (the assignment's mistake)")
        if facts.maze.in_goal(pose.x, pose.y):
            return Judgement(True)
        return Judgement(False, f"ended at ({pose.x:.2f}, {pose.y:.2f}), outside the maze's goal", facts.moment())
    off = math.dist((pose.x, pose.y), disc.centre)
    if off <= disc.radius:
        return Judgement(True)
    return Judgement(
        False,
        f"ended {100 * off:.1f} cm from the goal ({disc.centre[0]:g}, {disc.centre[1]:g}), "
        f"wanted within {100 * disc.radius:g} cm",
        facts.moment(),
        facts.node_before(math.inf),
    )


def _gap(criterion: Criterion, facts: RunFacts) -> Judgement:
    spec = criterion.gap or criterion.dead_end
    assert spec is not None
    blame = None
    if spec.after is not None:
        ended = next(
            (
                e
                for e in facts.result.events
                if e["kind"] == "behaviour_end" and (e["name"] == spec.after or fnmatchcase(e["path"], spec.after))
            ),
            None,
        )
        if ended is None:
            return Judgement(False, f"no {spec.after} ended, so the gap after it cannot be measured", facts.moment())
        t: float | None = ended["t"]
        blame = ended["path"]
    elif spec.at == "delete":
        event = facts.first("delete_entity")
        if event is None:
            return Judgement(
                False, "the robot was never deleted, so its stop before the delete cannot be measured", facts.moment()
            )
        t = event["t"]
        blame = facts.node_before(t, event)
    else:
        t = None
        blame = facts.node_before(math.inf)
    pose = facts.pose_at(t)
    if pose is None:
        return Judgement(False, "no robot to measure", None)
    side = None
    if criterion.dead_end is not None:
        side = criterion.dead_end.side or DEAD_END_SIDE * facts.cell
    problem = stop_problem(facts.maze, facts.model, pose, spec.distance, spec.tolerance, side)
    if problem is not None:
        return Judgement(False, problem, facts.moment(t), blame)
    return Judgement(True)


def _order(criterion: Criterion, facts: RunFacts) -> Judgement:
    kinds = criterion.order or []
    events = facts.result.events
    previous: tuple[str, float] | None = None
    for kind in kinds:
        times = [e["t"] for e in events if e["kind"] == kind]
        if not times:
            return Judgement(False, f"no {_said(kind)} happened", facts.moment())
        if previous is not None and times[0] <= previous[1]:
            return Judgement(
                False,
                f"the {_said(kind)} (t = {times[0]:.1f} s) came before the {_said(previous[0])} had completed",
                facts.moment(times[0]),
                facts.node_before(times[0]),
            )
        previous = (kind, times[0])
    return Judgement(True)


def _said(kind: str) -> str:
    return kind.replace("_entity", "").replace("_", " ")


def _respawn(criterion: Criterion, facts: RunFacts) -> Judgement:
    spec = criterion.respawn
    assert spec is not None
    if isinstance(spec.pose, str):
        if spec.pose not in facts.maze.spawns:
            return Judgement(False, f"this world has no spawn '{spec.pose}' (the assignment's mistake)")
        want = facts.maze.spawns[spec.pose]
    else:
        want = spec.pose
    spawns = [e for e in facts.result.events if e["kind"] == "spawn_entity"]
    if not spawns:
        return Judgement(False, "the robot was never spawned again", facts.moment())
    got = spawns[-1]["pose"]
    off = math.dist((got["x"], got["y"]), (want.x, want.y))
    turn = abs(math.remainder(got["yaw"] - want.yaw, math.tau))
    if off <= spec.tolerance and turn <= spec.yaw_tolerance:
        return Judgement(True)
    return Judgement(
        False,
        f"spawned at ({got['x']:.3f}, {got['y']:.3f}, yaw {math.degrees(got['yaw']):.0f} deg), wanted "
        f"({want.x:g}, {want.y:g}, yaw {math.degrees(want.yaw):.0f} deg)",
        {"t": spawns[-1]["t"], "x": got["x"], "y": got["y"]},
        facts.node_before(spawns[-1]["t"]),
    )


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


def _turns(criterion: Criterion, facts: RunFacts) -> Judgement:
    wanted = facts.turns if criterion.turns is True else criterion.turns
    if wanted is None:
        return Judgement(False, "this world says no turns to compare with (the assignment's mistake)")
    taken = turns_taken(facts)
    made = "".join(kind for kind, _ in taken)
    if made == wanted:
        return Judgement(True)
    i = next((i for i, (a, b) in enumerate(zip(made, wanted, strict=False)) if a != b), min(len(made), len(wanted)))
    when = taken[i][1] if i < len(taken) else None
    what = {"L": "left", "R": "right"}
    if i < len(made) and i < len(wanted):
        detail = f"turn {i + 1} went {what[made[i]]}, wanted {what[wanted[i]]}"
    elif len(made) < len(wanted):
        detail = f"stopped turning after {len(made)} turn{'s' * (len(made) != 1)}"
    else:
        detail = f"made {len(made) - len(wanted)} turn(s) too many"
    return Judgement(
        False,
        f"turned {made or 'never'}, wanted {wanted}: {detail}",
        facts.moment(when),
        facts.node_before(when) if when else None,
    )


def _leaves_maze(criterion: Criterion, facts: RunFacts) -> Judgement:
    pose = facts.pose_at(None)
    if pose is None:
        return Judgement(False, "no robot at the end of the run")
    if facts.maze.outside(pose.x, pose.y):
        return Judgement(True)
    return Judgement(
        False, f"ended inside the maze at ({pose.x:.2f}, {pose.y:.2f})", facts.moment(), facts.node_before(math.inf)
    )


def _min_clearance(criterion: Criterion, facts: RunFacts) -> Judgement:
    wanted, got = criterion.min_clearance, facts.result.min_clearance
    assert wanted is not None
    if got is not None and got >= wanted - 1e-9:
        return Judgement(True)
    seen = "touched a wall" if not got else f"came {100 * got:.1f} cm from a wall"
    return Judgement(False, f"{seen}, wanted at least {100 * wanted:g} cm", facts.moment())


def _no_reverse(criterion: Criterion, facts: RunFacts) -> Judgement:
    spawns = [e["t"] for e in facts.result.events if e["kind"] == "spawn_entity"]
    back = 0.0
    previous = None
    for sample in facts.result.trajectory:
        if previous is not None and not any(previous[0] < s <= sample[0] for s in spawns):
            t, x, y, yaw = previous
            step = (sample[1] - x) * math.cos(yaw) + (sample[2] - y) * math.sin(yaw)
            back = back - step if step < 0 else 0.0
            if back > REVERSE_SLACK:
                return Judgement(
                    False,
                    f"drove backwards ({100 * back:.1f} cm) at t = {sample[0]:.1f} s",
                    facts.moment(sample[0]),
                    facts.node_before(sample[0]),
                )
        previous = sample
    return Judgement(True)


CHECK_FUNCTIONS: dict[str, Callable[[Criterion, RunFacts], Judgement]] = {
    "finishes": _finishes,
    "no_collision": _no_collision,
    "max_time": _max_time,
    "goal": _goal,
    "gap": _gap,
    "dead_end": _gap,
    "order": _order,
    "respawn": _respawn,
    "turns": _turns,
    "leaves_maze": _leaves_maze,
    "min_clearance": _min_clearance,
    "no_reverse": _no_reverse,
}
