"""The real Thymio II's proximity readings (``prox.horizontal``) against distance, both ways.

A real Thymio reports integers: 0 when nothing is seen, rising as an obstacle nears (about 3400 at
3 cm, as the course report measured). Behaviours work in metres, so the simulator's ``raw`` sensor
model and the real-robot backend both go distance → reading → distance through one table, and a
mission written for the metric simulator runs unchanged against raw readings.

The table
    Webots' Thymio II model, ``lookupTable`` of ``projects/robots/mobsya/thymio/protos/
    Thymio2DistanceSensor.proto`` (cyberbotics/webots @ 08f0a117; summarised in docs/sources.md,
    "Enki and the real robot"). It has 29 rows at 1/3 cm steps; its 1 cm rows
    (4279, 4139, 3515, 2965, 2570, 2248, 1941, 1597, 1195 at 1..9 cm) are the table usually quoted.
    The full table is used rather than those 9 rows because it is the source itself, and the
    3.3 mm rows bend the curve where it changes fastest (2-3 cm: 3857 at 2.5 cm against 3827 from the
    1 cm rows). It agrees with the independent ROS driver fit within about 150 between 3 and 8 cm,
    and with the course report's ≈3400 at 3 cm within 4 %.

Choices
    - The 0 m row (4235) is left out: it is lower than the 3.3 mm row (4308), so the curve would not
      be invertible. Closer than 3.33 mm reads 4308, and 4308 or more converts back to 3.33 mm.
    - Webots interpolates linearly between 1195 at 9 cm and 0 at 9.333 cm; so does this table, so
      any reading above 0 converts to a finite distance and 0 to ``math.inf``.
    - Range: the course's simulated rays reach 0.0975 m, the table only 0.09333 m. Through the raw
      model an obstacle between 9.33 and 9.75 cm is not seen (reads 0, converts to inf). The table is
      not stretched to 0.0975 m, since that would change the calibration.
    - A real robot's first non-zero reading is already about 800-1200 (a firmware offset, see
      docs/sources.md), and its range depends on the surface: the table stands for a light wall.

Thymio Suite's simulator
    Its robots (Enki, in Aseba Playground) follow another curve, ``F(x) = m(c - x0²)/(x² - 2·x0·x + c)``
    with m = 4505, x0 = 0.03 cm, c = 73 (``enki/robots/thymio2/Thymio2.cpp``, docs/sources.md): 600-900
    higher than Webots at 4-9 cm, and 1226 at 14 cm before dropping to 0. :data:`ENKI_THYMIO2` is that
    curve at 1 cm steps, for trying the real-robot backend on a simulated Thymio.

Noise
    Webots' third column gives a Gaussian sd of 1 % of the reading (``0.01`` on every row), which is
    :class:`RawProximityModel`'s default. Enki (the Thymio Suite simulator) adds an absolute sd of
    2.87 instead (``IRSensor`` ``noiseSd``); both can be set.

Example::

    >>> round(metres_to_raw(0.03))
    3515
    >>> round(raw_to_metres(2570), 4)
    0.05
    >>> raw_to_metres(0)
    inf
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from itertools import pairwise
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # numpy is only needed by whoever makes the generator
    import numpy as np


@dataclass(frozen=True, slots=True)
class CalibrationTable:
    """A monotone response curve: readings (strictly decreasing, ending at 0) at distances (increasing, m)."""

    distances: tuple[float, ...]
    readings: tuple[float, ...]
    source: str = ""
    #: readings at or below this are noise, not an obstacle: they mean nothing seen (inf)
    floor: float = 0.0
    _ascending: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        d, r = self.distances, self.readings
        if len(d) != len(r) or len(d) < 2:
            raise ValueError("a calibration table needs at least two (distance, reading) rows")
        # NaN passes every ordering check below (each comparison with it is false), and an infinite
        # row makes the interpolation NaN: neither is a measurement
        for what, values in (("distance", d), ("reading", r), ("floor", (self.floor,))):
            bad = next((i for i, value in enumerate(values) if not math.isfinite(value)), None)
            if bad is not None:
                row = f" {bad + 1}" if what != "floor" else ""
                raise ValueError(f"{what}{row} is {values[bad]}: a calibration table holds finite numbers")
        if any(b <= a for a, b in pairwise(d)) or any(b >= a for a, b in pairwise(r)):
            raise ValueError("distances must increase and readings decrease strictly")
        if r[-1] != 0 or d[0] < 0:
            raise ValueError("the last reading must be 0 (nothing seen) and distances non-negative")
        object.__setattr__(self, "_ascending", r[::-1])

    @classmethod
    def of_rows(cls, rows: Sequence[tuple[float, float]], source: str = "", floor: float = 0.0) -> CalibrationTable:
        """A table from (distance, reading) rows, nearest first.

        >>> CalibrationTable.of_rows([(0.01, 4000), (0.05, 0)]).to_raw(0.02)
        3000.0
        >>> CalibrationTable.of_rows([(0.01, 4000), (math.nan, 0)])
        Traceback (most recent call last):
        ...
        ValueError: distance 2 is nan: a calibration table holds finite numbers
        """
        return cls(tuple(d for d, _ in rows), tuple(float(r) for _, r in rows), source, floor)

    @property
    def min_distance(self) -> float:
        """Closer than this, the reading saturates at :attr:`max_reading`."""
        return self.distances[0]

    @property
    def max_distance(self) -> float:
        """From this distance on, nothing is seen (reading 0): the sensor's range."""
        return self.distances[-1]

    @property
    def max_reading(self) -> float:
        """The saturated reading, at :attr:`min_distance` and closer."""
        return self.readings[0]

    def to_raw(self, distance: float) -> float:
        """The noise-free reading at ``distance`` metres (0 at or beyond the range, inf included)."""
        d, r = self.distances, self.readings
        if distance <= d[0]:
            return float(r[0])
        if distance >= d[-1]:
            return 0.0
        i = bisect_right(d, distance)
        t = (distance - d[i - 1]) / (d[i] - d[i - 1])
        return r[i - 1] + t * (r[i] - r[i - 1])

    def to_metres(self, reading: float) -> float:
        """The distance a reading means: inf for 0 (nothing seen), :attr:`min_distance` at saturation."""
        d, r = self.distances, self.readings
        if reading <= self.floor:
            return math.inf
        if reading >= r[0]:
            return float(d[0])
        i = len(r) - bisect_right(self._ascending, reading)  # first row reading ``reading`` or less
        t = (reading - r[i - 1]) / (r[i] - r[i - 1])
        return d[i - 1] + t * (d[i] - d[i - 1])


# a data table: distances in m, then the readings there, nearest first
# fmt: off
_WEBOTS_ROWS = tuple(zip(
    (
        0.00333, 0.00666, 0.01, 0.01333, 0.01666, 0.02, 0.02333, 0.02666, 0.03, 0.03333, 0.03666, 0.04,
        0.04333, 0.04666, 0.05, 0.05333, 0.05666, 0.06, 0.06333, 0.06666, 0.07, 0.07333, 0.07666, 0.08,
        0.08333, 0.08666, 0.09, 0.09333
    ),
    (
        4308, 4298, 4279, 4253, 4201, 4139, 3981, 3733, 3515, 3326, 3141, 2965, 2860, 2696, 2570, 2475,
        2344, 2248, 2182, 2044, 1941, 1835, 1689, 1597, 1473, 1345, 1195, 0
    ),
    strict=True,
))
# fmt: on

#: The default table: Webots' Thymio II proximity lookup table without its 0 m row (see above).
WEBOTS_THYMIO2 = CalibrationTable.of_rows(
    _WEBOTS_ROWS,
    source="cyberbotics/webots projects/robots/mobsya/thymio/protos/Thymio2DistanceSensor.proto @ 08f0a117",
)


# a data table: distances in m, then the readings there, nearest first
# fmt: off
_ENKI_ROWS = tuple(zip(
    (
        0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.1, 0.11, 0.12, 0.13, 0.139999, 0.14
    ),
    (
        4505, 4448, 4278, 4019, 3705, 3366, 3027, 2705, 2409, 2143, 1908, 1701, 1521, 1363, 1226, 0
    ),
    strict=True,
))
# fmt: on

#: Enki's (Thymio Suite's simulator) response at 1 cm steps; the Playground reads 0 from 14 cm on.
ENKI_THYMIO2 = CalibrationTable.of_rows(
    _ENKI_ROWS,
    source="enki-community/enki enki/robots/thymio2/Thymio2.cpp @ bb486bfb (IRSensor m=4505, x0=0.03, c=73)",
    floor=20.0,  # empty sensors read 0-8 (noise sd 2.87): 20 is 7 sd
)


def metres_to_raw(distance: float, table: CalibrationTable = WEBOTS_THYMIO2) -> float:
    """The noise-free ``prox.horizontal`` reading for an obstacle ``distance`` metres away."""
    return table.to_raw(distance)


def raw_to_metres(reading: float, table: CalibrationTable = WEBOTS_THYMIO2) -> float:
    """The distance in metres a ``prox.horizontal`` reading means (``math.inf`` for 0)."""
    return table.to_metres(reading)


def raw_scan_to_metres(readings: Mapping[str, float], table: CalibrationTable = WEBOTS_THYMIO2) -> dict[str, float]:
    """A scan of readings by sensor name as the metric scan behaviours use."""
    return {name: table.to_metres(value) for name, value in readings.items()}


@dataclass(slots=True)
class RawProximityModel:
    """What a real sensor reports for a true distance: the table's reading plus Gaussian noise,
    rounded to an integer and clipped at 0. Nothing in range reads exactly 0, without noise.

    The noise sd is ``hypot(absolute_sd, relative_sd * reading)``: Webots' 1 % by default, Enki's
    2.87 with ``absolute_sd=2.87, relative_sd=0``. A normal draw is made for every sensor on every
    reading, seen or not, so a seed gives the same stream whatever the robot sees.

    Example::

        >>> import numpy as np
        >>> model = RawProximityModel(np.random.default_rng(0))
        >>> raw = model.measure_scan({"front_center": 0.05, "rear_left": math.inf})
        >>> raw                                  # 2570 at 5 cm, plus noise; nothing in range reads 0
        {'front_center': 2573, 'rear_left': 0}
        >>> raw_scan_to_metres(raw)              # back in metres
        {'front_center': 0.049920476190476196, 'rear_left': inf}
    """

    rng: np.random.Generator
    table: CalibrationTable = WEBOTS_THYMIO2
    relative_sd: float = 0.01
    absolute_sd: float = 0.0

    def measure(self, distance: float) -> int:
        """One noisy integer reading for an obstacle ``distance`` metres away (inf: nothing)."""
        return self._reading(self.table.to_raw(distance), float(self.rng.standard_normal()))

    def measure_scan(self, scan: Mapping[str, float]) -> dict[str, int]:
        """Noisy readings for a scan in metres (by sensor name, inf when nothing is in range)."""
        draws = self.rng.standard_normal(len(scan))
        return {
            name: self._reading(self.table.to_raw(distance), float(z))
            for (name, distance), z in zip(scan.items(), draws, strict=True)
        }

    def through_raw(self, scan: Mapping[str, float]) -> dict[str, float]:
        """A metric scan as a real robot would see it: measured as readings, converted back to metres."""
        return raw_scan_to_metres(self.measure_scan(scan), self.table)

    def _reading(self, ideal: float, z: float) -> int:
        if ideal <= 0.0:
            return 0
        sd = math.hypot(self.absolute_sd, self.relative_sd * ideal)
        return max(0, round(ideal + sd * z))
