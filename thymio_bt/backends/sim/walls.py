"""Which static walls can lie near a point: a grid of cells, each listing the walls whose bounding
box comes near it.

The clearance tracker asks for the walls within a few centimetres of the robot's axle. pymunk's
``Space.point_query`` answers with a Python callback and result objects per shape, which cost more
than the distances themselves; the grid gives the few candidates at the price of one dict lookup,
and the caller (:mod:`~thymio_bt.backends.sim.clearance`) measures each. Grids are cached by
geometry: every run of a mission (a sweep's hundreds) shares its maze's grid.

Example::

    >>> grid = wall_grid(((0.0, 0.0, 0.6, 0.01),), cell=0.05, margin=0.15)   # the walls' bounding boxes
    >>> grid.near(0.3, 0.1, 0.1), grid.near(0.3, 0.5, 0.1)   # every wall within 0.1, perhaps more
    ((0,), ())
"""

from __future__ import annotations

import math
from functools import lru_cache

Box = tuple[float, float, float, float]


class WallGrid:
    """Wall indices by grid cell: each cell lists the walls whose bounding box comes within
    ``margin`` of it (one cell more on every side, so a point rounded into a neighbouring cell is
    still served)."""

    def __init__(self, boxes: tuple[Box, ...], cell: float, margin: float) -> None:
        self.cell, self.margin = cell, margin
        self.all = tuple(range(len(boxes)))
        cells: dict[tuple[int, int], list[int]] = {}
        for index, (x0, y0, x1, y1) in enumerate(boxes):
            for i in range(math.floor((x0 - margin) / cell) - 1, math.floor((x1 + margin) / cell) + 2):
                for j in range(math.floor((y0 - margin) / cell) - 1, math.floor((y1 + margin) / cell) + 2):
                    cells.setdefault((i, j), []).append(index)
        self.cells = {key: tuple(found) for key, found in cells.items()}

    def near(self, x: float, y: float, radius: float) -> tuple[int, ...]:
        """The indices of every wall whose box comes within ``radius`` of (x, y), perhaps a few more."""
        if radius > self.margin:
            return self.all
        return self.cells.get((math.floor(x / self.cell), math.floor(y / self.cell)), ())


@lru_cache(maxsize=16)
def wall_grid(boxes: tuple[Box, ...], cell: float, margin: float) -> WallGrid:
    """The grid of these bounding boxes (x0, y0, x1, y1), built once per geometry."""
    return WallGrid(boxes, cell, margin)
