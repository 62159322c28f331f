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
    >>> from thymio_bt.robot.interface import Pose
    >>> from thymio_bt.run.result import RunStatus
    >>> run = SimpleNamespace(status=RunStatus.SUCCESS, reason=None, failed_path=None, sim_time=1.0,
    ...     final_pose=Pose(0.469, 0.1, 0.0), collisions=0, min_clearance=0.04, events=[],
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
from dataclasses import dataclass

from thymio_bt.grade.assignment import Criterion, GoalDisc
from thymio_bt.grade.facts import RunFacts, cruise_speed, turns_taken
from thymio_bt.run.result import RunStatus
from thymio_bt.run.verdict import stop_problem

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


def judge(criterion: Criterion, facts: RunFacts) -> Judgement:
    """``criterion``'s check on the run ``facts``."""
    return CHECK_FUNCTIONS[criterion.check](criterion, facts)


def _finishes(criterion: Criterion, facts: RunFacts) -> Judgement:
    run = facts.result
    if run.status == RunStatus.SUCCESS:
        return Judgement(True)
    if run.status == RunStatus.TIMEOUT:
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
    if run.status != RunStatus.TIMEOUT and run.sim_time <= limit + 1e-9:
        return Judgement(True)
    took = "did not end" if run.status == RunStatus.TIMEOUT else f"took {run.sim_time:.1f} s"
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
    event = None
    if criterion.gap is not None and spec.after is not None:
        ended = facts.ended(spec.after)
        if ended is None:
            return Judgement(False, f"no {spec.after} ended, so the gap after it cannot be measured", facts.moment())
        t: float | None = ended["t"]
        blame = ended["path"]
    elif spec.at == "delete" and facts.first("delete_entity") is not None:
        event = facts.first("delete_entity")
        assert event is not None
        t = event["t"]
        blame = facts.node_that_drove(t, event)
    elif spec.at == "delete":  # a run that never deleted the robot: its stop is where it first stopped
        t = facts.first_stop()
        blame = facts.node_that_drove(t)
    else:
        t = None
        blame = facts.node_that_drove(None)
    pose = facts.pose_at(t)
    if pose is None:
        return Judgement(False, "no robot to measure", None)
    side = None
    if criterion.dead_end is not None:
        early = _before_its_phase(criterion, facts)
        if early is not None:
            return Judgement(False, early, facts.moment(t), blame)
        side = criterion.dead_end.side or DEAD_END_SIDE * facts.cell
    problem = stop_problem(facts.maze, facts.model, pose, spec.distance, spec.tolerance, side)
    if problem is not None:
        return Judgement(False, problem, facts.moment(t), blame)
    return Judgement(True)


def _before_its_phase(criterion: Criterion, facts: RunFacts) -> str | None:
    """Why a dead-end stop does not count yet: the node it must come after never ended, or the
    route has not taken the variant's turns (a stop at part 1's wall is no dead end of part 2)."""
    spec = criterion.dead_end
    assert spec is not None
    if spec.after is not None:
        return (
            None if facts.ended(spec.after) else f"the run ended before any {spec.after} ended, so not at the dead end"
        )
    wanted = facts.turns
    if not wanted:
        return None
    made = len(turns_taken(facts))
    if made >= len(wanted):
        return None
    turns = "turn" if len(wanted) == 1 else "turns"
    return f"ended before the dead end: took {made or 'none'} of the {len(wanted)} {turns} on the way there"


def count(n: int, noun: str) -> str:
    """``n`` things in words: 'no turn', '1 turn', '3 turns'.

    >>> count(0, "turn"), count(1, "turn"), count(3, "left turn")
    ('no turn', '1 turn', '3 left turns')
    """
    return f"no {noun}" if n == 0 else f"{n} {noun}{'s' * (n != 1)}"


def _order(criterion: Criterion, facts: RunFacts) -> Judgement:
    kinds = criterion.order or []
    events = facts.result.events
    previous: tuple[str, float] | None = None
    for kind in kinds:
        times = [e["t"] for e in events if e["kind"] == kind]
        if not times:
            run = facts.result
            if run.status != RunStatus.SUCCESS and run.reason:  # the tree ended first: that is the cause
                return Judgement(
                    False,
                    f"the tree {_ended(run.status)} before any {_said(kind)}: {run.reason}",
                    facts.moment(),
                    run.failed_path,
                )
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


def _ended(status: RunStatus) -> str:
    """'failed' or 'timed out'."""
    return "timed out" if status == RunStatus.TIMEOUT else "failed"


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
    # not wrap_angle: math.remainder is exact where wrap_angle rounds (kept: the same bits as before)
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
    return Judgement(False, turns_said(made, wanted), facts.moment(when), facts.node_before(when) if when else None)


def turns_said(made: str, wanted: str) -> str:
    """What went wrong with the turns, as a person says it.

    >>> turns_said("", "LLLL")
    'took no turn, wanted 4 left turns'
    >>> turns_said("LL", "LLLL")
    'took 2 left turns, then no more: wanted 4 left turns'
    >>> turns_said("LLRL", "LLLL")
    'turn 3 went right instead of left (took left, left, right, left; wanted 4 left turns)'
    >>> turns_said("LLLLL", "LLLL")
    'took 5 left turns, one too many: wanted 4 left turns'
    """
    i = next((i for i, (a, b) in enumerate(zip(made, wanted, strict=False)) if a != b), None)
    if i is not None:
        return (
            f"turn {i + 1} went {_WAY[made[i]]} instead of {_WAY[wanted[i]]} "
            f"(took {', '.join(_WAY[k] for k in made)}; wanted {_turns_in_words(wanted)})"
        )
    if not made:
        return f"took no turn, wanted {_turns_in_words(wanted)}"
    if len(made) < len(wanted):
        return f"took {_turns_in_words(made)}, then no more: wanted {_turns_in_words(wanted)}"
    extra = len(made) - len(wanted)
    return f"took {_turns_in_words(made)}, {'one' if extra == 1 else extra} too many: wanted {_turns_in_words(wanted)}"


_WAY = {"L": "left", "R": "right"}


def _turns_in_words(turns: str) -> str:
    """'4 left turns', '1 right turn', '3 turns (left, right, left)', 'no turn'."""
    if len(set(turns)) == 1:
        return count(len(turns), f"{_WAY[turns[0]]} turn")
    if not turns:
        return "no turn"
    return f"{len(turns)} turns ({', '.join(_WAY[k] for k in turns)})"


def _speed(criterion: Criterion, facts: RunFacts) -> Judgement:
    spec = criterion.speed
    assert spec is not None
    start = 0.0 if spec.after is None else facts.marker(spec.after)
    end = math.inf if spec.before is None else facts.marker(spec.before)
    if start is None:
        return Judgement(False, f"no {_said(spec.after or '')} happened, so the speed after it cannot be measured")
    phase = _phase_said(spec.after, spec.before)
    cruise = cruise_speed(facts, start, math.inf if end is None else end)
    if cruise is None:
        return Judgement(False, f"never drove {phase}", facts.moment(start), facts.node_before(math.inf))
    speed, t = cruise
    if abs(speed - spec.speed) <= spec.tolerance + 1e-9:
        return Judgement(True)
    return Judgement(
        False,
        f"drove at {100 * speed:.1f} cm/s {phase}, wanted {100 * spec.speed:g} +- {100 * spec.tolerance:g} cm/s",
        facts.moment(t),
        facts.node_running(t),
    )


def _phase_said(after: str | None, before: str | None) -> str:
    """'before the delete', 'after the spawn and before the delete', 'over the run'."""
    parts = [f"after the {_said(after)}" if after else "", f"before the {_said(before)}" if before else ""]
    return " and ".join(p for p in parts if p) or "over the run"


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
    "speed": _speed,
}
