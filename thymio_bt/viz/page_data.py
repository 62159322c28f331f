"""What a run's page embeds: a :class:`~thymio_bt.logs.recording.Recording` as compact JSON data.

A page must stay small (a 7000-tick micromouse run in a few MB) yet answer, at any tick, where the
robot was, what it read, the status of every node and what the blackboard held. So signals are
columns of numbers rounded as the page shows them (poses to 0.1 mm and 0.1 mrad), each node's status
is kept only where it changes (tick indices as gaps, with the letters of the log), and each
blackboard key only where its value changes. :func:`statuses_at` reads the statuses back, as the page's
JavaScript does.

Example (a log's statuses, their changes, and the statuses at tick index 2 read back):

>>> samples = [{"nodes": {"a": "R", "a/b": "R"}}, {"nodes": {"a": "R", "a/b": "S"}},
...            {"nodes": {"a": "S", "a/b": "S"}}, {"nodes": {"a": "S", "a/b": "S"}}]
>>> changes = status_changes(samples, ["a", "a/b"])
>>> changes
[[[0, 2], 'RS'], [[0, 1], 'RS']]
>>> statuses_at(changes, 2), statuses_at(changes, 0)
(['S', 'S'], ['R', 'R'])
"""

from __future__ import annotations

import math
from bisect import bisect_right
from itertools import accumulate
from typing import Any, Literal

from thymio_bt.logs.entries import TickRecord
from thymio_bt.logs.recording import Recording, robot_shape
from thymio_bt.robot.model import COURSE

#: decimals the page keeps: poses to 0.1 mm (the DOM contract's 4 decimals), signals to 0.1 mm/s
DECIMALS = 4
#: the speeds of a tick whose log has none (a rosbag2 log's tick without /odom: no robot then)
NO_SPEED = (None, None)
#: the run's end as the page keeps it: its verdict, and where the robot was when the run ended
END_FIELDS = ("status", "reason", "code", "failed_path", "sim_time", "collisions", "final_pose")
#: event fields the page shows; the rest (poses, whole proximity scans) the ticks already hold
EVENT_FIELDS = ("t", "kind", "name", "path", "status", "decision", "reason", "entity", "code")


def _r(value: Any) -> float | None:
    """A number as the page keeps it (None stays None)."""
    return None if value is None else round(float(value), DECIMALS)


def tree_paths(recording: Recording) -> list[list[Any]]:
    """The tree as ``[path, name, kind, parent index or -1]`` rows in pre-order: the header's tree,
    else (a log without one) the paths of the ticks' ``nodes``, parents made from the paths."""
    nodes = recording.header.get("tree") or []
    if nodes:
        index: dict[int | None, int] = {node["uid"]: i for i, node in enumerate(nodes)}
        return [[n["path"], n["name"], n["kind"], index.get(n["parent"], -1)] for n in nodes]
    paths: list[str] = []
    for sample in recording.samples:
        paths += [p for p in sample.get("nodes", {}) if p not in paths]
    ordered = sorted(paths, key=lambda p: p.split("/"))
    rows: list[list[Any]] = []
    for path in ordered:
        parent = path.rpartition("/")[0]
        rows.append([path, path.rpartition("/")[2], "", ordered.index(parent) if parent in ordered else -1])
    return rows


def status_changes(samples: list[TickRecord], paths: list[str]) -> list[list[Any]]:
    """For each path, ``[gaps, letters]``: the tick indices where its status changes (the first
    tick included), as gaps from the previous change, and its letter from then on (``-``: INVALID,
    also for a node a tick does not list)."""
    out: list[list[Any]] = []
    for path in paths:
        gaps: list[int] = []
        letters: list[str] = []
        last_index, last = 0, None
        for i, sample in enumerate(samples):
            letter = sample.get("nodes", {}).get(path, "-")
            if letter != last:
                gaps.append(i - last_index)
                letters.append(letter)
                last_index, last = i, letter
        out.append([gaps, "".join(letters)])
    return out


def statuses_at(changes: list[list[Any]], index: int) -> list[str]:
    """Each node's status letter at tick index ``index``, read from :func:`status_changes`."""
    out = []
    for gaps, letters in changes:
        at = bisect_right(list(accumulate(gaps)), index) - 1
        out.append(letters[at] if at >= 0 else "-")
    return out


def blackboard_changes(samples: list[TickRecord]) -> dict[str, list[list[Any]]]:
    """Each blackboard key's ``[tick index, value]`` at every tick where the log says it changed."""
    keys: dict[str, list[list[Any]]] = {}
    for i, sample in enumerate(samples):
        for key, value in (sample.get("bb") or {}).items():
            keys.setdefault(str(key), []).append([i, value])
    return dict(sorted(keys.items()))


def event_rows(events: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The run's events as the page keeps them: the fields of :data:`EVENT_FIELDS` only."""
    return [{k: e[k] for k in EVENT_FIELDS if k in e} for e in events]


def _maze(recording: Recording) -> dict[str, Any]:
    """The maze's shapes as flat corner lists, its goal areas and its bounds."""
    maze = recording.maze

    def flat(corners: list[tuple[float, float]]) -> list[float | None]:
        return [_r(v) for corner in corners for v in corner]

    return {
        "name": maze.name,
        "walls": [flat(wall.corners()) for wall in maze.walls],
        "obstacles": [flat(obstacle.corners()) for obstacle in maze.obstacles],
        "goal": [[_r(v) for v in (*area.start, *area.end)] for area in maze.goal],
        "bounds": [_r(v) for v in maze.bounds()],
    }


def robot_data(recording: Recording) -> dict[str, Any]:
    """The robot that ran as the page draws it: its name, outline and sensors (base_link frame) and
    range, from the log header (:func:`~thymio_bt.logs.recording.robot_shape`); a log without them
    (written before logs named their robot) or with them unreadable gets the course Thymio's, with
    ``assumed`` saying why.

    >>> from thymio_bt.maze import Maze
    >>> robot_data(Recording(maze=Maze()))["assumed"]
    'the log does not say which robot ran: drawn as the course Thymio'
    >>> robot_data(Recording(maze=Maze(), header={"robot": {"name": "x", "hull": "<svg>"}}))["name"]
    'course'
    """
    shape = recording.header.get("robot")
    try:
        if not isinstance(shape, dict):
            raise ValueError("not given")
        hull = [_number(v) for corner in shape["hull"] for v in _pair(corner)]
        sensors = [[str(row[0]), *(_number(v) for v in row[1:4])] for row in shape["sensors"] if len(row) == 4]
        reach = _number(shape["range"])
        if len(hull) < 6 or not sensors or reach <= 0:
            raise ValueError("too small")
        return {"name": str(shape["name"]), "hull": hull, "sensors": sensors, "range": reach}
    except (KeyError, TypeError, ValueError):
        said = "does not say which robot ran" if shape is None else "names its robot unreadably"
        course = robot_shape(COURSE)
        return {
            "name": course["name"],
            "hull": [_r(v) for corner in course["hull"] for v in corner],
            "sensors": [[n, _r(x), _r(y), _r(yaw)] for n, x, y, yaw in course["sensors"]],
            "range": course["range"],
            "assumed": f"the log {said}: drawn as the course Thymio",
        }


def _number(value: Any) -> float:
    """A finite number from a log, as the page keeps it; a ValueError or TypeError for anything else."""
    number = float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else math.nan
    if not math.isfinite(number):
        raise ValueError(value)
    return round(number, DECIMALS)


def _pair(corner: Any) -> tuple[Any, Any]:
    """An outline's corner ``[x, y]`` from a log (a TypeError for anything else)."""
    if not isinstance(corner, list) or len(corner) != 2:
        raise TypeError(corner)
    return corner[0], corner[1]


def page_data(recording: Recording, label: str = "") -> dict[str, Any]:
    """The data of one run's page (see the module docstring): JSON-ready, compact."""
    samples = recording.samples  # every field read with get: a log of another format may lack one
    tree = tree_paths(recording)
    robot = robot_data(recording)
    prox_names = [row[0] for row in robot["sensors"]]
    end = recording.end
    return {
        "label": label or recording.mission,
        "mission": recording.mission,
        "seed": recording.header.get("seed"),
        "tick_hz": recording.header.get("tick_hz"),
        "note": recording.header.get("note"),
        "end": {k: end.get(k) for k in END_FIELDS},
        "maze": _maze(recording),
        "robot": robot,
        "tree": tree,
        "t": [s["t"] for s in samples],
        "tick": [s.get("tick", i) for i, s in enumerate(samples)],
        **_pose_columns(samples),
        "cmd": _speed_columns(samples, "cmd"),
        "vel": _speed_columns(samples, "vel"),
        "prox": {"names": prox_names, "values": _prox_columns(samples, prox_names)},
        "status": status_changes(samples, [row[0] for row in tree]),
        "bb": blackboard_changes(samples),
        "events": event_rows(recording.events),
    }


def _pose_columns(samples: list[TickRecord]) -> dict[str, list[float | None]]:
    """The true pose as the columns ``x``, ``y`` and ``yaw`` (None where there was no robot)."""
    poses = [s.get("pose") for s in samples]
    return {axis: [None if p is None else _r(p[axis]) for p in poses] for axis in ("x", "y", "yaw")}


def _speed_columns(samples: list[TickRecord], key: Literal["cmd", "vel"]) -> list[list[float | None]]:
    """A speed (``cmd`` or ``vel``) as two columns, linear and angular (0 where a sample has none)."""
    return [[_r((s.get(key) or NO_SPEED)[k]) for s in samples] for k in (0, 1)]


def _prox_columns(samples: list[TickRecord], names: list[str]) -> list[list[float | None]]:
    """A column of each proximity sensor's range in ``names`` (None where it saw nothing or was not read)."""
    return [[_r((s.get("prox") or {}).get(name)) for s in samples] for name in names]
