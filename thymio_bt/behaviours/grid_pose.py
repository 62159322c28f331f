"""Where a mapping behaviour is in a maze of square cells: the map on the blackboard, the robot's
pose on its grid, and what a wall square ahead says of that pose.

:class:`OnGrid` is the base of every mapping behaviour (:mod:`thymio_bt.behaviours.mapping`,
:mod:`thymio_bt.behaviours.move_cells`); :class:`Sensing` adds the correction from a wall ahead,
measured with the robot's own sensor poses (docs/sources.md, "Robot geometry and sensors").

Example::

    >>> [side for side in HEADING], LEFT_OF["E"], RIGHT_OF["E"]
    (['E', 'N', 'W', 'S'], 'N', 'S')
    >>> SensingParams().trusted_from, MazeMapParams(cell=0.2).cell
    (0.025, 0.2)
"""

from __future__ import annotations

import math
from typing import ClassVar, Literal

from py_trees.common import Status
from pydantic import BaseModel, Field

from thymio_bt.behaviours.base import BehaviourParams, RobotBehaviour, current_pose
from thymio_bt.enums import FailureCode
from thymio_bt.geometry import wrap_angle
from thymio_bt.inputs.fields import BlackboardKey, Length
from thymio_bt.maze.cellmap import Cell, CellMap, centre_cells
from thymio_bt.robot.model import RobotModel

Target = Literal["goal", "centre", "start"]
Side = Literal["N", "E", "S", "W"]
#: the heading of each side of a cell, and the sides to the left and right of each
HEADING = {"E": 0.0, "N": math.pi / 2, "W": math.pi, "S": -math.pi / 2}
LEFT_OF = {"E": "N", "N": "W", "W": "S", "S": "E"}
RIGHT_OF = {"E": "S", "S": "W", "W": "N", "N": "E"}
#: a wall ahead whose ±20° readings say the robot is turned more than this is not believed square
MAX_TILT = math.radians(8.0)
#: how much the map's pose may drift per metre driven without a wall ahead to fix it (a turn a few
#: degrees off, then a straight run through open cells: 7 cm per metre was seen on Enki's Thymio)
DRIFT_PER_METRE = 0.1
#: the drift a wall-ahead fix accepts at most, as a fraction of the cell (a wall a cell away is not this one)
MAX_DRIFT = 0.25


class MazeMapParams(BehaviourParams):
    """The maze's grid and where its map is kept."""

    cell: Length = Field(0.18, gt=0.1, le=1.0, description="the grid pitch (post centre to post centre)")
    wall: Length = Field(0.012, gt=0, le=0.05, description="wall thickness")
    cols: int | None = Field(None, ge=1, le=64, description="cells along x (default: from the maze's size)")
    rows: int | None = Field(None, ge=1, le=64, description="cells along y (default: from the maze's size)")
    key: BlackboardKey = Field("maze_map", description="blackboard key of the map")


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


class OnGrid(RobotBehaviour):
    """Shared by the mapping behaviours: the map on the blackboard, the robot's pose on its grid."""

    # declared as the base's type: subclasses' parameters add required fields (MoveCells' distance)
    Params: ClassVar[type[BaseModel]] = MazeMapParams

    def prepare(self) -> None:
        """The map's blackboard key and the grid."""
        self.board = self.blackboard("map", write=(self.params.key,))
        self.grid = self._grid()
        self._map: CellMap | None = None
        self._goal: set[Cell] | None = None

    @property
    def model(self) -> RobotModel:
        """The robot's own geometry (asked when needed: a tree is also built without a robot, to draw it)."""
        return self.robot.model

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
        """FAILURE (INVALID_INPUT) when the grid is unknown, else the usual checks and :meth:`step`."""
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
        """The cell the axle is in, as the map believes it."""
        x, y, _ = self.pose()
        return math.floor(x / self.params.cell), math.floor(y / self.params.cell)

    def facing(self) -> str:
        """The side of its cell the robot faces most nearly (N, E, S or W)."""
        yaw = self.pose()[2]
        return min(HEADING, key=lambda side: abs(wrap_angle(HEADING[side] - yaw)))

    def centre_of(self, cell: Cell) -> tuple[float, float]:
        """Where the centre of ``cell`` is on the grid (metres from its origin)."""
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
                    if any(area.contains(ox + cx, oy + cy) for area in self.ctx.goal)
                }
            cells.goal = self._goal
            return self._goal
        if target == "start":
            return {cells.start} if cells.start is not None else set()
        cells.goal = centre_cells(cells.cols, cells.rows)
        return cells.goal


class Sensing(OnGrid):
    """Shared by the behaviours that correct the map's pose from a wall square ahead."""

    Params: ClassVar[type[BaseModel]] = SensingParams

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
            if abs(tilt) < MAX_TILT:
                heading = HEADING[side] + tilt
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
        ±20° readings) into the map's pose; a shift along the heading over ``gate`` (plus the drift
        the map may have gathered along it since its last such fix) is not believed."""
        heading = HEADING[side]
        c, s = math.cos(heading), math.sin(heading)
        x, y, yaw = self.pose()
        face = centre[0] * c + centre[1] * s + (self.params.cell - self.params.wall) / 2
        measured_yaw, measured_along = self.wall_fix(*readings, side, face)
        along = 0.0 if measured_along is None else measured_along - (x * c + y * s)
        turn = 0.0 if measured_yaw is None else wrap_angle(measured_yaw - yaw)
        drift = self.cell_map().drift
        axis = "x" if side in ("E", "W") else "y"
        if abs(along) <= gate + drift[axis] and (along or turn):
            self.nudge(heading, gain * along, 0.0, turn_gain * turn)
            if measured_along is not None:
                drift[axis] *= 1.0 - gain

    def drifted(self, distance: float) -> None:
        """The robot drove ``distance`` (m) on the map's pose: each coordinate may be that much
        (:data:`DRIFT_PER_METRE`) further off, up to :data:`MAX_DRIFT` of a cell."""
        drift, most = self.cell_map().drift, MAX_DRIFT * self.params.cell
        for axis in drift:
            drift[axis] = min(most, drift[axis] + DRIFT_PER_METRE * distance)
