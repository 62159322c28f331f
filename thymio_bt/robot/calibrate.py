"""``thymio-bt calibrate``: measure a robot's profile on any backend, as a file ``--robot`` takes.

The robot stands in a straight corridor facing a wall (:func:`arena`: a simulator builds it, a real
robot is placed by its operator at the printed pose) and does three things:

1. **speed**: 2 s straight at 150 motor units: the distance it really covers (the backend's true
   pose: a simulator's ground truth, else odometry) gives metres per unit;
2. **proximity**: a slow approach (2 cm/s) to 8 mm from the wall, recording the front-centre
   sensor's raw reading against its distance to the wall (the pose and the arena's geometry),
   binned every 5 mm into a calibration table (median per bin, strictly decreasing, ending at 0);
3. **wheel base**: back off 10 cm, spin 3 s at ±100 units per wheel: the turn rate it really makes
   and the measured wheel speed give the wheel separation.

Each measure skips its first half second (start-up, the robot's own delays). On a real robot without
ground truth the pose is odometry, which counts wheel turns in the same units: the speed and wheel
base then only check themselves, while the table is as good as the robot was placed.

``stopped`` is asked after every tick: once it says so (a Ctrl-C), the robot is told to stop and
:class:`Stopped` is raised, naming the measure it cut short; nothing is measured from half a run.

From the shell::

    thymio-bt calibrate --backend playground --robot enki -o enki_measured.yaml
    thymio-bt run missions/maze_part1_2.yaml --backend playground --robot enki_measured.yaml

Example (the corridor, and a table from approach samples, farthest first: a reading at or below
the noise floor means nothing in range, and the table reads 0 just beyond the last reading above it)::

    >>> len(arena().walls), arena().spawn("start")
    (4, Pose(x=0.15, y=0.1, yaw=0.0))
    >>> samples = [(0.30, 6), (0.04, 3), (0.030, 3600), (0.030, 3500), (0.020, 4100), (0.011, 4300), (0.010, 4200)]
    >>> floor = noise_floor(samples)
    >>> floor, table_rows(samples, floor)
    (12.0, [(0.01, 4250.0), (0.02, 4100.0), (0.03, 3550.0), (0.0305, 0.0)])
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import pairwise

from thymio_bt.errors import ThymioBtError
from thymio_bt.geometry import Pose, wrap_angle
from thymio_bt.maze import Maze
from thymio_bt.robot.interface import Backend
from thymio_bt.robot.model import RobotModel
from thymio_bt.robot.placement import ray_distance
from thymio_bt.robot.profile import Profile, TableRows
from thymio_bt.sensor_tables import CalibrationTable

TICK = 0.1
#: the corridor: 0.2 m wide, its end wall's face at x = END (m), the robot 0.45 m from it
END, WIDTH = 0.6, 0.2
START = Pose(0.15, WIDTH / 2, 0.0)
SPEED_UNITS, SPIN_UNITS = 150, 100
APPROACH_SPEED, CLOSEST, BIN = 0.02, 0.008, 0.005
#: no Thymio sees a wall this far (m; Enki's range is 0.14): readings from there on are the noise floor
FAR = 0.25
#: readings above the noise floor in a row that mark the range's edge
IN_A_ROW = 3
#: the table's last row, reading 0, is this far beyond the farthest reading in range (m)
EDGE = 0.0005


def arena() -> Maze:
    """The corridor calibrate runs in (walls 1 cm thick; the end wall's face at x = 0.6 - 0.005)."""
    walls = [
        {"from": [0.0, 0.0], "to": [END, 0.0]},
        {"from": [0.0, WIDTH], "to": [END, WIDTH]},
        {"from": [END, 0.0], "to": [END, WIDTH]},
        {"from": [0.0, 0.0], "to": [0.0, WIDTH]},
    ]
    return Maze.model_validate(
        {
            "name": "calibration corridor",
            "walls": [{**w, "thickness": 0.01} for w in walls],
            "spawns": {"start": {"x": START.x, "y": START.y, "yaw": START.yaw}},
        }
    )


class Stopped(ThymioBtError):
    """The calibration was stopped (``stopped()`` said so) during the measure named ``step``.

    >>> str(Stopped("2/3 proximity"))
    'stopped during 2/3 proximity'
    """

    def __init__(self, step: str) -> None:
        super().__init__(f"stopped during {step}")
        self.step = step


@dataclass
class Calibration:
    """What calibrate measured; :meth:`profile` makes the file."""

    base: RobotModel
    metres_per_unit: float
    wheel_separation: float
    samples: list[tuple[float, int]] = field(default_factory=list)  # (distance, raw), farthest first
    rows: list[tuple[float, float]] = field(default_factory=list)  # the table
    #: readings at or below this mean nothing in range (:func:`noise_floor`)
    floor: float = 0.0

    def profile(self, name: str) -> Profile:
        """The profile file's content, named ``name``, with the scales against the base model for the record."""
        return Profile(
            base=self.base.name,
            name=name,
            metres_per_unit=round(self.metres_per_unit, 9),
            wheel_separation=round(self.wheel_separation, 5),
            calibration=TableRows(
                distances=[round(d, 5) for d, _ in self.rows], readings=[r for _, r in self.rows], floor=self.floor
            ),
            measured={
                "speed_scale": round(self.metres_per_unit / self.base.metres_per_unit, 4),
                "wheel_separation_scale": round(self.wheel_separation / self.base.wheel_separation, 4),
                "proximity_samples": len(self.samples),
                "method": "thymio-bt calibrate: 2 s at 150 units, approach at 2 cm/s, 3 s spin at 100 units",
            },
        )

    def summary(self) -> list[str]:
        """Lines comparing the measures with the base model's."""
        base = self.base
        lines = [
            f"speed: {self.metres_per_unit * 500:.4f} m/s at 500 units ({base.name}: "
            f"{base.metres_per_unit * 500:.4f}, {100 * (self.metres_per_unit / base.metres_per_unit - 1):+.1f} %)",
            f"wheel base: {self.wheel_separation * 100:.2f} cm ({base.name}: {base.wheel_separation * 100:.2f})",
            "front-centre reading (measured / " + base.name + "):",
        ]
        table = self.table()
        for cm in (1, 2, 3, 4, 6, 8, 10, 12):
            measured, expected = table.to_raw(cm / 100), base.calibration.to_raw(cm / 100)
            off = f"{100 * (measured / expected - 1):+.1f} %" if expected else ""
            lines.append(f"  {cm:2d} cm: {measured:6.0f} / {expected:6.0f} {off}")
        return lines

    def table(self) -> CalibrationTable:
        """The measured rows as a calibration table."""
        return CalibrationTable.of_rows(self.rows, source="calibrate", floor=self.floor)


def noise_floor(samples: list[tuple[float, int]], base: float = 0.0) -> float:
    """The reading at or below which a sensor sees nothing: twice the largest reading taken with the
    wall beyond :data:`FAR` (out of any Thymio's range), and never below ``base`` (the base model's).

    >>> noise_floor([(0.30, 3), (0.28, 8), (0.05, 3366)]), noise_floor([(0.30, 0)], base=20.0)
    (16.0, 20.0)
    """
    far = [raw for distance, raw in samples if distance >= FAR]
    return max(float(base), 2.0 * max(far, default=0))


def table_rows(samples: list[tuple[float, int]], floor: float = 0.0) -> list[tuple[float, float]]:
    """A strictly decreasing table from (distance, raw) approach samples, farthest first: the median
    of each 5 mm bin of the readings above ``floor`` (the noise floor) from the range's edge on,
    rows that would not decrease dropped, then a 0 just beyond the edge.

    The edge is the first sample of the first :data:`IN_A_ROW` readings in a row above the floor: a
    stray reading farther out does not move it, a single reading dropping to noise nearer is left
    out, and no bin mixes readings in range with noise (a row of noise would make every noisy
    "nothing" read as an obstacle at the range's end)."""
    above = [raw > floor for _, raw in samples]
    start = next((i for i in range(len(samples)) if all(above[i : i + IN_A_ROW])), len(samples))
    near = [
        (d, raw) for (d, raw), seen in zip(samples[start:], above[start:], strict=True) if seen and math.isfinite(d)
    ]
    if start == 0 or len(near) < 2:
        raise ValueError(
            "the approach never saw the wall go out of range, or never saw it: "
            f"{len(samples)} readings, {len(near)} in range (is the robot facing the wall?)"
        )
    edge = near[0][0]
    bins: dict[int, list[int]] = {}
    for distance, raw in near:
        bins.setdefault(round(distance / BIN), []).append(raw)
    rows: list[tuple[float, float]] = []
    for index in sorted(bins):
        reading = float(statistics.median(bins[index]))
        if not rows or reading < rows[-1][1]:
            rows.append((index * BIN, reading))
    rows.append((round(max(edge, rows[-1][0]) + EDGE, 5), 0.0))
    return rows


def calibrate(
    backend: Backend,
    model: RobotModel,
    maze: Maze,
    say: Callable[[str], None] = print,
    stopped: Callable[[], bool] = lambda: False,
) -> Calibration:
    """Run the three measures on ``backend`` (a robot of base ``model`` at :data:`START` in ``maze``);
    :class:`Stopped` once ``stopped()`` is true (asked every tick), the robot told to stop."""
    sensor = model.sensor("front_center")
    period = TICK
    step = ""

    def tick() -> None:
        backend.advance(period)
        if stopped():
            backend.drive(0.0, 0.0)  # a real robot's targets are sent now; closing it stops it again
            raise Stopped(step)

    def measure(name: str, text: str) -> None:
        nonlocal step
        step = name
        say(f"{name}: {text}")

    def truth() -> Pose:
        pose = backend.true_pose()
        if pose is None:
            raise RuntimeError("the robot is gone")
        return pose

    def run_for(seconds: float, linear: float, angular: float) -> list[tuple[float, Pose]]:
        out = []
        for _ in range(round(seconds / period)):
            backend.drive(linear, angular)  # again every tick: a robot whose motors vary per command averages
            tick()
            out.append((backend.time(), truth()))
        backend.drive(0.0, 0.0)
        for _ in range(5):  # let it come to rest
            tick()
        return out

    # 1. speed, straight at SPEED_UNITS
    measure("1/3 speed", "2 s straight")
    speed_cmd = model.wheel_speed_of(SPEED_UNITS)
    track = run_for(2.0, speed_cmd, 0.0)[5:]
    (t0, p0), (t1, p1) = track[0], track[-1]
    speed = math.hypot(p1.x - p0.x, p1.y - p0.y) / (t1 - t0)
    metres_per_unit = model.metres_per_unit * speed / speed_cmd

    # 2. proximity, a slow approach
    measure("2/3 proximity", f"approaching the wall at {APPROACH_SPEED * 100:g} cm/s")
    if not backend.raw_readings:
        raise ValueError(
            f"the backend {type(backend).__name__} gives no raw readings (a simulator with "
            f"sensor_model raw or cone, the aseba or playground backends do)"
        )
    samples: list[tuple[float, int]] = []
    for _ in range(round(2 * END / APPROACH_SPEED / period)):
        backend.drive(APPROACH_SPEED, 0.0)
        tick()
        pose, raw = truth(), backend.proximity_raw()
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        x, y = pose.x + sensor.x * c - sensor.y * s, pose.y + sensor.x * s + sensor.y * c
        distance = ray_distance(maze, x, y, pose.yaw + sensor.yaw)
        if raw is not None:
            samples.append((distance, int(raw["front_center"])))
        if distance <= CLOSEST:
            break
    backend.drive(0.0, 0.0)

    # 3. wheel base, a spin after backing off
    measure("3/3 wheel base", "backing off 10 cm, then 3 s turning")
    run_for(2.0, -0.05, 0.0)
    spin_wheel = model.wheel_speed_of(SPIN_UNITS)
    track = run_for(3.0, 0.0, 2 * spin_wheel / model.wheel_separation)[5:]
    turned = sum(wrap_angle(b.yaw - a.yaw) for (_, a), (_, b) in pairwise(track))
    rate = turned / (track[-1][0] - track[0][0])
    wheel_separation = 2 * SPIN_UNITS * metres_per_unit / rate
    result = Calibration(model, metres_per_unit, wheel_separation, samples)
    result.floor = noise_floor(samples, model.calibration.floor)
    result.rows = table_rows(samples, result.floor)
    return result
