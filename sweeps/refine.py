"""Quadtree refinement on a 2-D slice: compute the fine grid only near a class's boundary.

The finest grid is the spec's grid (``k * 2**levels + 1`` points per axis). Level 0 computes
every ``2**levels``-th point; each square cell of the current level whose four corners disagree
about the chosen class (certified or not) is split in four, which needs its five midpoints
(edges and centre); cells whose corners agree are left alone. After ``levels`` rounds the
refined cells have side one: the boundary is resolved at the finest resolution.

A boundary that enters and leaves a coarse cell between its corners is not seen (the usual
limit of corner sampling); the coarse spacing bounds the size of what can be missed.

Everything here is a pure function of the statuses computed so far, so a resumed run takes
exactly the same decisions and computes exactly the same points.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

Cell = tuple[int, int, int]  # (i0, j0, side) in grid indices


def coarse_points(shape: tuple[int, int], levels: int) -> npt.NDArray[np.intp]:
    """Indices ``(n, 2)`` of the level-0 grid."""
    step = 2**levels
    ii, jj = np.meshgrid(np.arange(0, shape[0], step), np.arange(0, shape[1], step), indexing="ij")
    return np.stack([ii.ravel(), jj.ravel()], axis=1)


def coarse_cells(shape: tuple[int, int], levels: int) -> list[Cell]:
    step = 2**levels
    return [(i, j, step) for i in range(0, shape[0] - 1, step) for j in range(0, shape[1] - 1, step)]


def disagree(cell: Cell, certified: npt.NDArray[np.bool_]) -> bool:
    i, j, s = cell
    corners = (certified[i, j], certified[i + s, j], certified[i, j + s], certified[i + s, j + s])
    return any(corners) and not all(corners)


def split(cells: list[Cell], certified: npt.NDArray[np.bool_]) -> tuple[list[Cell], npt.NDArray[np.intp]]:
    """The children of every disagreeing cell, and the (unique, sorted) points they need."""
    children: list[Cell] = []
    points: set[tuple[int, int]] = set()
    for cell in cells:
        if not disagree(cell, certified):
            continue
        i, j, s = cell
        h = s // 2
        children.extend([(i, j, h), (i + h, j, h), (i, j + h, h), (i + h, j + h, h)])
        points.update({(i + h, j), (i, j + h), (i + h, j + h), (i + 2 * h, j + h), (i + h, j + 2 * h)})
    arr = np.array(sorted(points), dtype=np.intp).reshape(-1, 2)
    return children, arr
