"""Mapping and planning in mazes of square cells: what a micromouse does, as behaviours.

The robot keeps a :class:`~thymio_bt.behaviours.cellmap.CellMap` on the blackboard: the walls
seen so far, the cells visited, and where the maze's grid lies in the odometry frame.

- ``MapWalls`` looks at the side of its cell it faces (a few stationary readings; more when they
  disagree) and marks a wall or an opening. Facing a wall it also re-measures the robot's heading
  and its distance along it, which cancels the drift odometry builds up.
- ``PlanMove`` flood-fills the map towards a target region (walls not seen yet assumed open, or
  only known openings for the fast run) and writes the move: ``move_centre`` (back to the cell
  centre along the heading), ``move_turn`` (to face the next cell) and ``move_distance`` (cell centre to cell centre).
- ``MoveCells`` drives ``move_distance`` along the grid line, holding the corridor's centre with
  the side sensors (their readings correct the map's idea of where the robot is across the corridor).
- ``WallMapped`` and ``AtTarget`` are the conditions a tree needs around them.

A Thymio spinning at a cell centre clears the walls of an 18 cm contest cell by only 4 mm, so
every move ends where the map says the cell centre is, and the map keeps that true to a millimetre.

Example (YAML)::

    - repeat:
        until: {AtTarget: {target: centre}}
        do:
          sequence:
            - MapWalls
            - PlanMove: {target: centre}
            - MoveDistance: {distance: bb:move_centre}
            - TurnAngle: {angle: bb:move_turn}
            - MapWalls
            - selector: [WallMapped, {MoveCells: {distance: bb:move_distance}}]
"""

from __future__ import annotations

import math
from collections import deque
from typing import Literal

from py_trees.common import Access, Status
from pydantic import Field

from thymio_bt.behaviours.base import (
    BehaviourParams,
    ConditionBehaviour,
    Context,
    FailureCode,
    RobotBehaviour,
    current_pose,
)
from thymio_bt.behaviours.cellmap import STEPS, Cell, CellMap, centre_cells
from thymio_bt.behaviours.motion import approach_speed
from thymio_bt.inputs.fields import Length, Speed
from thymio_bt.robot.interface import wrap_angle
from thymio_bt.robot.model import COURSE, RobotModel

Target = Literal["goal", "centre", "start"]
Side = Literal["N", "E", "S", "W"]
_HEADING = {"E": 0.0, "N": math.pi / 2, "W": math.pi, "S": -math.pi / 2}
_LEFT = {"E": "N", "N": "W", "W": "S", "S": "E"}
_RIGHT = {"E": "S", "S": "W", "W": "N", "N": "E"}
#: a front-wall measurement that disagrees with the map's pose by more than this is not believed
_MAX_SHIFT = 0.03
_MAX_TILT = math.radians(8.0)


class MazeMapParams(BehaviourParams):
    """The maze's grid and where its map is kept."""

    cell: Length = Field(0.18, gt=0.1, le=1.0, description="the grid pitch (post centre to post centre)")
    wall: Length = Field(0.012, gt=0, le=0.05, description="wall thickness")
    cols: int | None = Field(None, ge=1, le=64, description="cells along x (default: from the maze's size)")
    rows: int | None = Field(None, ge=1, le=64, description="cells along y (default: from the maze's size)")
    key: str = Field("maze_map", description="blackboard key of the map")


class SensingParams(MazeMapParams):
    """How far the proximity sensors are believed for a position fix."""

    trusted_from: Length = Field(
        0.025,
        ge=0,
        le=0.05,
        description="front readings closer than this are not "
        "used to correct the pose (a real Thymio's calibration is off by mm there)",
    )
    trusted_to: Length = Field(
        0.08,
        ge=0.02,
        le=0.2,
        description="nor readings further than this (noisy near "
        "the end of the range, and a cone sensor sees more than the wall ahead there)",
    )


class _OnGrid(RobotBehaviour):
    """Shared by the mapping behaviours: the map on the blackboard, the robot's pose on its grid."""

    Params = MazeMapParams

    def __init__(self, name: str, params: MazeMapParams, ctx: Context, **kwargs: object) -> None:
        super().__init__(name, params, ctx, **kwargs)  # type: ignore[arg-type]
        self.board = self.attach_blackboard_client(name=f"{name}_map")
        self.board.register_key(params.key, access=Access.WRITE)
        self.model: RobotModel = getattr(self.robot, "model", COURSE)
        self.grid = self._grid()
        self._map: CellMap | None = None
        self._goal: set[Cell] | None = None

    def _grid(self) -> tuple[int, int, float, float] | str:
        """cols, rows and the grid's origin (the bottom-left post's centre), or why they are unknown."""
        p, bounds = self.params, self.ctx.bounds
        if bounds is None:
            if p.cols is None or p.rows is None:
                return "the maze's size is unknown here: give cols and rows"
            return p.cols, p.rows, 0.0, 0.0
        xmin, ymin, xmax, ymax = bounds
        cols = p.cols or max(1, round((xmax - xmin) / p.cell))
        rows = p.rows or max(1, round((ymax - ymin) / p.cell))
        # the outline's walls straddle the outer grid lines: centre the grid in the bounds
        return cols, rows, xmin + (xmax - xmin - cols * p.cell) / 2, ymin + (ymax - ymin - rows * p.cell) / 2

    def update(self) -> Status:
        if isinstance(self.grid, str):
            return self.fail(FailureCode.INVALID_INPUT, self.grid)
        return super().update()

    def cell_map(self) -> CellMap:
        """The map, made on first use with the cell the robot is in as its start (and then kept:
        one map object per run, looked up on the blackboard once per behaviour)."""
        if self._map is not None:
            return self._map
        if not self.board.exists(self.params.key):
            assert not isinstance(self.grid, str)
            found = CellMap(self.grid[0], self.grid[1], cell=self.params.cell, origin=(self.grid[2], self.grid[3]))
            self.board.set(self.params.key, found)
            found.start = self.cell()
        found = self.board.get(self.params.key)
        assert isinstance(found, CellMap)
        self._map = found
        return found

    # ------------------------------------------------------------------ poses
    def odometry(self) -> tuple[float, float, float]:
        """The axle's odometry pose, relative to the grid's origin."""
        assert not isinstance(self.grid, str)
        x, y, yaw = self.model.axle_of(current_pose(self.robot))
        return x - self.grid[2], y - self.grid[3], yaw

    def pose(self) -> tuple[float, float, float]:
        """The axle's pose on the grid, as the map believes it."""
        return self.cell_map().frame.to_maze(*self.odometry())

    def cell(self) -> Cell:
        x, y, _ = self.pose()
        return math.floor(x / self.params.cell), math.floor(y / self.params.cell)

    def facing(self) -> str:
        yaw = self.pose()[2]
        return min(_HEADING, key=lambda side: abs(wrap_angle(_HEADING[side] - yaw)))

    def centre_of(self, cell: Cell) -> tuple[float, float]:
        return (cell[0] + 0.5) * self.params.cell, (cell[1] + 0.5) * self.params.cell

    def nudge(self, heading: float, along: float, left: float, turn: float) -> None:
        """Move the map's pose of the robot by ``along`` ``heading`` and ``left`` across it, and turn it."""
        cells = self.cell_map()
        odometry = self.odometry()
        x, y, yaw = cells.frame.to_maze(*odometry)
        c, s = math.cos(heading), math.sin(heading)
        cells.frame.correct(odometry, (x + along * c - left * s, y + along * s + left * c, yaw + turn))

    def targets(self, target: str) -> set[Cell]:
        """The cells of ``target``: the maze's goal region (the cells whose centre lies in it), the
        contest's centre block, or the cell the map was started in."""
        cells = self.cell_map()
        if target == "goal":
            if self._goal is None:
                assert not isinstance(self.grid, str)
                ox, oy = self.grid[2], self.grid[3]
                centres = {(i, j): self.centre_of((i, j)) for i in range(cells.cols) for j in range(cells.rows)}
                self._goal = {
                    cell
                    for cell, (cx, cy) in centres.items()
                    if any(x0 <= ox + cx <= x1 and y0 <= oy + cy <= y1 for x0, y0, x1, y1 in self.ctx.goal)
                }
            cells.goal = self._goal
            return self._goal
        if target == "start":
            return {cells.start} if cells.start is not None else set()
        cells.goal = centre_cells(cells.cols, cells.rows)
        return cells.goal


class _Sensing(_OnGrid):
    """Shared by the behaviours that correct the map's pose from a wall square ahead."""

    Params = SensingParams

    def wall_fix(
        self, front: float, left: float, right: float, side: str, face: float
    ) -> tuple[float | None, float | None]:
        """What a wall square ahead, its face at ``face`` along the heading of ``side``, says of the
        robot: (heading, axle coordinate along that heading), each None when the readings do not
        tell (out of range, or nearer than ``trusted_from``)."""
        lo, hi = self.params.trusted_from, self.params.trusted_to
        if not lo <= front <= hi:
            return None, None
        tilt = 0.0
        heading = None
        if lo <= min(left, right) and max(left, right) <= hi:
            hits = []
            for name, reading in (("front_center_left", left), ("front_center_right", right)):
                sensor = self.model.sensor(name)
                hits.append((sensor.x + reading * math.cos(sensor.yaw), sensor.y + reading * math.sin(sensor.yaw)))
            (lx, ly), (rx, ry) = hits
            tilt = math.atan2(lx - rx, ly - ry)  # > 0: turned left of the wall's normal
            if abs(tilt) < _MAX_TILT:
                heading = _HEADING[side] + tilt
            else:
                tilt = 0.0
        # the front sensor's distance to the wall, from the axle, measured square to the wall
        reach = (self.model.sensor("front_center").x - self.model.axle_x + front) * math.cos(tilt)
        return heading, face - reach

    def fix_from_wall(
        self,
        readings: tuple[float, float, float],
        centre: tuple[float, float],
        side: str,
        gain: float,
        turn_gain: float,
        gate: float,
    ) -> None:
        """Take ``gain`` of what the wall on ``side`` of the cell centred at ``centre`` says (front,
        ±20° readings) into the map's pose; a shift along the heading over ``gate`` is not believed."""
        heading = _HEADING[side]
        c, s = math.cos(heading), math.sin(heading)
        x, y, yaw = self.pose()
        face = centre[0] * c + centre[1] * s + (self.params.cell - self.params.wall) / 2
        measured_yaw, measured_along = self.wall_fix(*readings, side, face)
        along = 0.0 if measured_along is None else measured_along - (x * c + y * s)
        turn = 0.0 if measured_yaw is None else wrap_angle(measured_yaw - yaw)
        if abs(along) <= gate and (along or turn):
            self.nudge(heading, gain * along, 0.0, turn_gain * turn)


class MapWallsParams(SensingParams):
    """How the wall ahead is read."""

    readings: int = Field(
        3, ge=1, le=20, description="stationary readings per look; three times as many at most when they disagree"
    )


class MapWalls(_Sensing):
    """Look at the side of the robot's cell it faces: a wall when the front sensor sees one within
    half a cell, an opening when it sees none; mark the cell visited. It stands still for
    ``readings`` ticks and reads on while they disagree (a wall at the edge of the sensor's range, a
    noisy reading); a side the map already knows takes one reading that agrees. Facing a wall it
    re-measures the heading (from where the two ±20° sensors hit
    it) and the distance to it (front sensor): the map's pose follows the robot, not odometry.

    Example (YAML)::

        - MapWalls: {cell: 18cm}
    """

    yaml_name = "MapWalls"
    Params = MapWallsParams
    moves = True

    def start(self) -> None:
        self.samples: list[tuple[float, float, float]] = []

    def step(self) -> Status:
        p = self.params
        self.robot.drive(0.0, 0.0)
        scan = self.robot.proximity()
        assert scan is not None
        self.samples.append((scan["front_center"], scan["front_center_left"], scan["front_center_right"]))
        near = [s[0] < p.cell / 2 for s in self.samples]
        cells, here, side = self.cell_map(), self.cell(), self.facing()
        known = cells.wall(here, side)
        confirmed = known is not None and near == [known]  # one reading agrees with the map: done
        if not confirmed and (
            len(self.samples) < p.readings or (0 < sum(near) < len(near) and len(near) < 3 * p.readings)
        ):
            self.feedback_message = f"reading ({len(self.samples)})"
            return Status.RUNNING
        wall = known if confirmed else 2 * sum(near) > len(near)
        cells.mark(here, side, wall)
        cells.visited.add(here)
        if wall:
            self._relocate(here, side)
        self.extra = {"cell": list(here), "side": side, "wall": wall, "visited": len(cells.visited)}
        self.feedback_message = f"{side} of {here}: {'wall' if wall else 'open'}"
        return Status.SUCCESS

    def _relocate(self, here: Cell, side: str) -> None:
        """Correct the map's pose from the wall ahead, by the mean of the readings that saw it."""
        valid = [s for s in self.samples if all(math.isfinite(v) for v in s)]
        if valid:
            mean = tuple(sum(s[k] for s in valid) / len(valid) for k in range(3))
            self.fix_from_wall(mean, self.centre_of(here), side, 1.0, 1.0, _MAX_SHIFT)  # type: ignore[arg-type]


class PlanMoveParams(MazeMapParams):
    """Where to go, and on which map."""

    target: Target = Field(
        "goal", description="the maze's goal region, the centre (the contest's goal block) or the start cell"
    )
    known_only: bool = Field(
        False,
        description="plan over known openings only and run straight through "
        "as many cells as the path goes straight (the fast run); else walls not "
        "seen yet are assumed open and the robot stops at every cell to look (exploration)",
    )


class PlanMove(_OnGrid):
    """Flood-fill the map towards ``target`` and write the next move on the blackboard:
    ``move_centre`` (along the heading, back to the cell centre), ``move_turn`` (to face the next
    cell, relative, left positive) and ``move_distance`` (from this cell's centre to the next one's,
    or to the last cell of a straight run). In the target already: a zero move. FAILURE (NO_PATH) when the map
    leaves no way there.

    Example (YAML)::

        - PlanMove: {target: centre}
        - TurnAngle: {angle: bb:move_turn}
    """

    yaml_name = "PlanMove"
    Params = PlanMoveParams

    def __init__(self, name: str, params: PlanMoveParams, ctx: Context, **kwargs: object) -> None:
        super().__init__(name, params, ctx, **kwargs)
        for key in ("move_centre", "move_turn", "move_distance"):
            self.board.register_key(key, access=Access.WRITE)

    def step(self) -> Status:
        p = self.params
        cells, here = self.cell_map(), self.cell()
        targets = self.targets(p.target)
        if not targets:
            return self.fail(FailureCode.INVALID_INPUT, f"the maze declares no goal region (target: {p.target})")
        x, y, yaw = self.pose()
        cx, cy = self.centre_of(here)
        centre = (cx - x) * math.cos(yaw) + (cy - y) * math.sin(yaw)
        if here in targets:
            return self._write(centre, 0.0, 0.0)
        distance = cells.distances(targets, p.known_only)
        if here not in distance:
            return self.fail(FailureCode.NO_PATH, f"no way from cell {list(here)} to the {p.target} on the map")
        side = cells.next_side(here, self.facing(), distance, p.known_only)
        run = cells.straight_run(here, side, distance) if p.known_only else 1
        di, dj = STEPS[side]
        self.extra = {"cell": list(here), "to": [here[0] + run * di, here[1] + run * dj], "steps_left": distance[here]}
        return self._write(centre, wrap_angle(_HEADING[side] - yaw), run * p.cell)

    def _write(self, centre: float, turn: float, ahead: float) -> Status:
        self.board.set("move_centre", centre)
        self.board.set("move_turn", turn)
        self.board.set("move_distance", ahead)
        return Status.SUCCESS


class MoveCellsParams(SensingParams):
    """Drive along the grid line the robot faces."""

    distance: Length = Field(
        description="how far from the centre of the robot's cell (from the blackboard: move_distance)", ge=-10, le=10
    )
    speed: Speed = Field(0.1, gt=0, le=0.2, description="cruise speed")
    tolerance: Length = Field(0.0005, gt=0, le=0.01, description="done when within this of the goal")


#: steering towards the grid line: rad of heading per metre off it, and the largest heading offset
_LINE_GAIN, _LINE_MAX = 8.0, 0.15
#: how much of a side-sensor fix the map's pose takes per tick (two walls, one wall)
_FIX_BOTH, _FIX_ONE = 0.3, 0.15
#: two-wall readings the map averages before it trusts its side sensors' bias (and one wall alone)
_BIAS_SAMPLES = 10
#: a front-sensor fix further than twice this from the map's pose is not believed (a post, an opening)
_FIX_GATE = 0.012
#: nor a side-sensor fix further than this, nor one from a wall in view for less than _STEADY ticks
_SIDE_GATE, _STEADY = 0.004, 3
#: ... unless this many in a row agree to within _SIDE_GATE
_PERSIST = 5
#: two-wall readings whose mean bias differs from the learnt one by more than this are not used
_WIDTH_GATE = 0.003
#: side walls are read only while nothing is this close ahead of the axle (a cone sensor's inner
#: edge sees a wall ahead long before its centre ray would)
_CLEAR_AHEAD = 0.16
#: how much of a heading measured from a wall ahead (the ±20° sensors) the map takes per tick: two
#: readings with 1 mm of noise each, 5 cm apart, give the angle to a degree only
_FIX_TILT = 0.1
#: the heading correction per metre of a side-sensor fix (the map was off across: it was heading off)
_FIX_TURN = 2.0


class MoveCells(_Sensing):
    """Drive to ``distance`` from the centre of the robot's cell along the grid line of the heading
    it faces (a whole number of cells ends on a cell centre), steering onto the
    line by the map's pose. While the ±38° sensors see side walls (and nothing is ahead) their
    readings say where the robot is across the corridor and correct the map's pose, so the robot
    ends on the cell centre, where turning in place is safe, and not where odometry says it is.

    Example (YAML)::

        - MoveCells: {distance: bb:move_distance, speed: 20cm/s}
    """

    yaml_name = "MoveCells"
    Params = MoveCellsParams
    moves = True

    def start(self) -> None:
        self.side = self.facing()
        self.heading = _HEADING[self.side]
        x, y = self.centre_of(self.cell())
        self.goal = (
            x + self.params.distance * math.cos(self.heading),
            y + self.params.distance * math.sin(self.heading),
        )
        self.line = self._left(x, y)  # the grid line through the robot's cell
        self.steady = {"front_left": 0, "front_right": 0}  # ticks each side wall has been in view
        self.votes: dict[tuple[Cell, str], list[int]] = {}  # (cell, side) -> [wall, open] readings
        self.outliers: deque[float] = deque(maxlen=_PERSIST)  # the latest side fixes beyond the gate

    def _left(self, x: float, y: float) -> float:
        """The coordinate of (x, y) to the left of the heading (y facing E, -x facing N, ...)."""
        return -math.sin(self.heading) * x + math.cos(self.heading) * y

    def step(self) -> Status:
        p = self.params
        scan = self.robot.proximity()
        assert scan is not None
        self._map_sides(scan)
        self._fix_across(scan)
        self._fix_along(scan)
        x, y, yaw = self.pose()
        remaining = (self.goal[0] - x) * math.cos(self.heading) + (self.goal[1] - y) * math.sin(self.heading)
        if abs(remaining) <= p.tolerance:
            self.robot.drive(0.0, 0.0)
            return Status.SUCCESS
        off = self._left(x, y) - self.line  # > 0: left of the line
        direction = math.copysign(1.0, remaining)
        wanted = self.heading - direction * max(-_LINE_MAX, min(_LINE_MAX, _LINE_GAIN * off))
        error = wrap_angle(wanted - yaw)
        speed = approach_speed(abs(remaining), p.speed, 5.0, 0.005, self.ctx.tick_period)
        self.robot.drive(direction * speed, max(-0.5, min(0.5, 3.0 * error)))
        self.extra = {"remaining": round(remaining, 6)}
        self.say("{:.3f} m to go", remaining)
        return Status.RUNNING

    def _map_sides(self, scan: dict[str, float]) -> None:
        """Map the side walls of the cells the robot drives through from the ±38° sensors: where a
        ray would meet the side wall of a cell (in the middle of its length, well within range), a
        reading there is a wall and none is an opening. Two agreeing readings and no contrary one
        mark an unknown side; so turns are planned towards sides known to be open."""
        cells = self.cell_map()
        x, y, yaw = self.pose()
        c = self.params.cell
        half = (c - self.params.wall) / 2
        along = (math.cos(self.heading), math.sin(self.heading))
        normal = (-along[1], along[0])  # to the left of the heading
        front = scan["front_center"] + self.model.sensor("front_center").x - self.model.axle_x
        for name, sign in (("front_left", 1.0), ("front_right", -1.0)):
            sensor = self.model.sensor(name)
            ax, ay = sensor.x - self.model.axle_x, sensor.y
            px, py = x + ax * math.cos(yaw) - ay * math.sin(yaw), y + ax * math.sin(yaw) + ay * math.cos(yaw)
            dx, dy = math.cos(yaw + sensor.yaw), math.sin(yaw + sensor.yaw)
            across = dx * normal[0] + dy * normal[1]
            if across * sign <= 0.0:
                continue
            lateral = px * normal[0] + py * normal[1] - self.line
            expected = (sign * half - lateral) / across  # the ray's length to the side wall's face
            qx, qy = px + expected * dx, py + expected * dy  # where it would meet it
            ahead = (qx - x) * along[0] + (qy - y) * along[1]
            position = (qx * along[0] + qy * along[1]) / c
            if expected > 0.8 * self.model.range_max or front < ahead + _FIX_GATE or not 0.3 <= position % 1.0 <= 0.7:
                continue
            reading = scan[name]
            if reading < expected + 0.03:
                seen = 0  # a wall
            elif reading > expected + 0.06:
                seen = 1  # nothing there (inf, or a wall beyond)
            else:
                continue
            ox, oy = qx - sign * half * normal[0], qy - sign * half * normal[1]  # back onto the centre line
            cell = (math.floor(ox / c), math.floor(oy / c))
            side = (_LEFT if sign > 0 else _RIGHT)[self.side]
            votes = self.votes.setdefault((cell, side), [0, 0])
            votes[seen] += 1
            if cells.inside(cell) and cells.wall(cell, side) is None and votes[seen] >= 2 and not votes[1 - seen]:
                cells.mark(cell, side, seen == 0)

    def _fix_across(self, scan: dict[str, float]) -> None:
        """Where the side walls say the robot is across the corridor, taken into the map's pose (and
        its heading: an offset that keeps growing as the robot drives is a heading error).

        With both walls in view the offset is half the difference of their distances, whatever the
        sensors' bias (a cone sensor reads an oblique wall long); their mean teaches the map that
        bias, so that one wall alone can be used afterwards."""
        half = (self.params.cell - self.params.wall) / 2
        front = scan["front_center"] + self.model.sensor("front_center").x - self.model.axle_x
        reach: dict[str, float] = {}
        tilt = wrap_angle(self.pose()[2] - self.heading)  # the robot's angle to the corridor
        cos, sin = math.cos(tilt), math.sin(tilt)
        for name in ("front_left", "front_right"):
            sensor, reading = self.model.sensor(name), scan[name]
            # the ray meets a side wall this far ahead of the axle; a wall ahead nearer than that hides it
            meets = sensor.x - self.model.axle_x + (half - abs(sensor.y)) / math.tan(abs(sensor.yaw))
            if math.isfinite(reading) and front > max(meets + _FIX_GATE, _CLEAR_AHEAD):
                # the hit point, from the axle, turned into the corridor's frame: its distance across
                hx = sensor.x - self.model.axle_x + reading * math.cos(sensor.yaw)
                hy = sensor.y + reading * math.sin(sensor.yaw)
                reach[name] = abs(hx * sin + hy * cos)
        for name in ("front_left", "front_right"):  # a wall's end seen by a cone is not a wall yet
            self.steady[name] = self.steady[name] + 1 if name in reach else 0
            if self.steady[name] < _STEADY:
                reach.pop(name, None)
        cells = self.cell_map()
        if len(reach) == 2:
            offset = (reach["front_right"] - reach["front_left"]) / 2  # > 0: the robot is left of the centre
            bias = (reach["front_right"] + reach["front_left"]) / 2 - half
            cells.side_bias.add(bias)
            if cells.side_bias.count >= _BIAS_SAMPLES and abs(bias - cells.side_bias.median) > _WIDTH_GATE:
                return  # the corridor reads too wide or narrow: a wall's end, a post
            gain, gate = _FIX_BOTH, _SIDE_GATE
        elif reach and cells.side_bias.count >= _BIAS_SAMPLES:
            name, value = next(iter(reach.items()))
            offset = (half - (value - cells.side_bias.median)) * (1.0 if name == "front_left" else -1.0)
            gain, gate = _FIX_ONE, _SIDE_GATE
        else:
            return
        x, y, _ = self.pose()
        error = offset - (self._left(x, y) - self.line)
        if abs(error) > gate:
            # beyond the gate: a post or a wall's end, unless the readings keep saying the same thing
            # (then the map is what is wrong, and the fix is taken)
            self.outliers.append(error)
            if len(self.outliers) < _PERSIST or max(self.outliers) - min(self.outliers) > _SIDE_GATE:
                return
        self.outliers.clear()
        self.nudge(self.heading, 0.0, gain * error, _FIX_TURN * gain * error)

    def _fix_along(self, scan: dict[str, float]) -> None:
        """Where the wall at the end of the move says the robot is along it (and how it is turned to
        it), taken into the map's pose."""
        self.fix_from_wall(
            (scan["front_center"], scan["front_center_left"], scan["front_center_right"]),
            self.goal,
            self.side,
            _FIX_BOTH,
            _FIX_TILT,
            2 * _FIX_GATE,
        )


class WallMappedParams(MazeMapParams):
    """Is a wall mapped ahead?"""


class WallMapped(ConditionBehaviour, _OnGrid):
    """SUCCESS when the map has a wall on the side of its cell the robot faces.

    Example (YAML)::

        - selector: [WallMapped, {MoveCells: {distance: bb:move_distance}}]
    """

    yaml_name = "WallMapped"
    Params = WallMappedParams

    def step(self) -> Status:
        return Status.SUCCESS if self.cell_map().wall(self.cell(), self.facing()) else Status.FAILURE


class AtTargetParams(MazeMapParams):
    """Is the robot in the target region?"""

    target: Target = Field(
        "goal", description="the maze's goal region, the centre (the contest's goal block) or the start cell"
    )


class AtTarget(ConditionBehaviour, _OnGrid):
    """SUCCESS when the robot's cell (on the map's grid) is in the ``target`` region.

    Example (YAML)::

        - repeat: {until: {AtTarget: {target: centre}}, do: ...}
    """

    yaml_name = "AtTarget"
    Params = AtTargetParams

    def step(self) -> Status:
        return Status.SUCCESS if self.cell() in self.targets(self.params.target) else Status.FAILURE
