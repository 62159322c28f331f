"""MoveCells: drive along a grid line of a maze of square cells, holding the corridor's centre.

The side sensors' readings say where the robot is across the corridor (and map the side walls of
the cells it passes); the wall at the end of the move says where it is along it. Both correct the
map's pose (:mod:`thymio_bt.behaviours.grid_pose`), so a move ends on the cell centre the map
believes in, not where odometry says the robot is.

Example::

    >>> params = MoveCellsParams(distance=0.36, speed=0.2)
    >>> params.distance, params.tolerance, params.cell
    (0.36, 0.0005, 0.18)
"""

from __future__ import annotations

import math
from collections import deque

from py_trees.common import Status
from pydantic import Field

from thymio_bt.behaviours.grid_pose import HEADING, LEFT_OF, RIGHT_OF, Sensing, SensingParams
from thymio_bt.behaviours.motion import approach_speed
from thymio_bt.geometry import wrap_angle
from thymio_bt.inputs.fields import Length, Speed
from thymio_bt.maze.cellmap import Cell
from thymio_bt.robot.interface import Scan


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


class MoveCells(Sensing):
    """Drive to ``distance`` from the centre of the robot's cell along the grid line of the heading
    it faces (a whole number of cells ends on a cell centre), steering onto the
    line by the map's pose. While the ±38° sensors see side walls (and nothing is ahead) their
    readings say where the robot is across the corridor and correct the map's pose, so the robot
    ends on the cell centre, where turning in place is safe, and not where odometry says it is.

    Example (YAML)::

        - MoveCells: {distance: bb:move_distance, speed: 20cm/s}
    """

    Params = MoveCellsParams
    moves = True

    @classmethod
    def drives_forward(cls, params: MoveCellsParams) -> float:
        """It drives ``distance`` along its grid line: its sensors correct its pose, they do not stop it."""
        return params.distance

    def start(self) -> None:
        """Take the goal on the grid line the robot faces, and forget what the last move saw."""
        self.side = self.facing()
        self.heading = HEADING[self.side]
        x, y = self.centre_of(self.cell())
        self.goal = (
            x + self.params.distance * math.cos(self.heading),
            y + self.params.distance * math.sin(self.heading),
        )
        self.line = self._left(x, y)  # the grid line through the robot's cell
        self.steady = {"front_left": 0, "front_right": 0}  # ticks each side wall has been in view
        self.votes: dict[tuple[Cell, str], list[int]] = {}  # (cell, side) -> [wall, open] readings
        self.outliers: deque[float] = deque(maxlen=_PERSIST)  # the latest side fixes beyond the gate
        self.last = self.odometry()[:2]  # where the axle was last tick, for the drift driven

    def _left(self, x: float, y: float) -> float:
        """The coordinate of (x, y) to the left of the heading (y facing E, -x facing N, ...)."""
        return -math.sin(self.heading) * x + math.cos(self.heading) * y

    def step(self) -> Status:
        """Map and fix from this tick's readings, then steer along the line towards the goal."""
        p = self.params
        scan = self.robot.proximity()
        assert scan is not None
        odometry = self.odometry()
        self.drifted(math.dist(odometry[:2], self.last))
        self.last = odometry[:2]
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

    def _map_sides(self, scan: Scan) -> None:
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
            side = (LEFT_OF if sign > 0 else RIGHT_OF)[self.side]
            votes = self.votes.setdefault((cell, side), [0, 0])
            votes[seen] += 1
            if cells.inside(cell) and cells.wall(cell, side) is None and votes[seen] >= 2 and not votes[1 - seen]:
                cells.mark(cell, side, seen == 0)

    def _fix_across(self, scan: Scan) -> None:
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

    def _fix_along(self, scan: Scan) -> None:
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
