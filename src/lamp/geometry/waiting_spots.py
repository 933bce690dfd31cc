"""Waiting spots: the free grid node nearest a point, found by breadth-first search.

:func:`nearest_free_spot` is :meth:`lamp.geometry.robot_space.RobotSpace.nearest_free`
(documented there). It guarantees that the spot returned is exactly a grid node whose
clearance is at least the asked one, outside every disk (or mask node) to avoid, accepted
by ``accept``, within ``max_distance`` of the point, and the closest to the point in
Euclidean distance among the valid nodes the search meets; None when there is none.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.clearance_kernels import bfs_collect


class ClearanceGrid(Protocol):
    """What the search reads of a robot space (``RobotSpace`` is one): its clearance
    field on a grid of ``resolution`` m from node ``origin``, the clearance a robot
    needs (``threshold``), and the free nodes connected as a robot moves
    (``free_grid``)."""

    threshold: float
    resolution: float
    shape: tuple[int, int]
    origin: tuple[int, int]
    field: np.ndarray

    @property
    def free_grid(self) -> np.ndarray: ...


def _clear_disks(ok: np.ndarray, avoid: ArrayLike, h: float, oi: int, oj: int) -> None:
    """Mark, in place, the nodes of ``ok`` (origin node ``(oi, oj)``) inside any disk
    ``(x, y, radius)`` of ``avoid`` as not valid."""
    ny, nx = ok.shape
    disks = np.asarray(avoid, dtype=np.float64).reshape(-1, 3)
    for x, y, rad in disks:
        i0 = max(0, int(math.floor((x - rad) / h)) - oi)
        i1 = min(nx - 1, int(math.ceil((x + rad) / h)) - oi)
        j0 = max(0, int(math.floor((y - rad) / h)) - oj)
        j1 = min(ny - 1, int(math.ceil((y + rad) / h)) - oj)
        if i1 < i0 or j1 < j0:
            continue
        xs = np.arange(oi + i0, oi + i1 + 1) * h - x
        ys = np.arange(oj + j0, oj + j1 + 1) * h - y
        inside = xs[None, :] ** 2 + ys[:, None] ** 2 <= rad * rad
        ok[j0:j1 + 1, i0:i1 + 1] &= ~inside


def _judge(accept: Callable[[np.ndarray], np.ndarray], judged: np.ndarray, ci: np.ndarray,
           cj: np.ndarray, nx: int, oi: int, oj: int, h: float) -> np.ndarray:
    """Whether ``accept`` takes each collected node; asks only about nodes not judged
    before (``judged``: -1 unknown, 0 no, 1 yes, updated in place)."""
    flat = cj.astype(np.int64) * nx + ci
    todo = flat[judged[flat] < 0]
    if len(todo):
        pts = np.stack([(todo % nx + oi) * h, (todo // nx + oj) * h],
                       axis=1).astype(np.float64)
        res = np.asarray(accept(pts), dtype=bool).reshape(-1)
        if res.shape != (len(todo),):
            raise ValueError("accept must return one bool per point")
        judged[todo] = res
    return judged[flat] == 1


def _search(p: np.ndarray, ok: np.ndarray, reach: np.ndarray, si: int, sj: int, oi: int,
            oj: int, h: float, limit: int, accept: Callable[[np.ndarray], np.ndarray] | None,
            max_distance: float | None) -> np.ndarray | None:
    """BFS from node (si, sj) of the box, deepening until the nearest valid node is sure."""
    ny, nx = ok.shape
    depth_cap = min(16, limit)
    judged = np.full(ny * nx, -1, dtype=np.int8) if accept is not None else None
    while True:
        ci, cj, cd = bfs_collect(ok, reach, si, sj, depth_cap)
        good = np.ones(len(ci), dtype=bool)
        if judged is not None and len(ci):
            good = _judge(accept, judged, ci, cj, nx, oi, oj, h)  # type: ignore[arg-type]
        if good.any():
            d_first = int(cd[good].min())
            # BFS depth counts 8-connected hops (chessboard distance in the open); a
            # node at Euclidean distance e has depth >= e / h, so nodes closer than the
            # first find lie within depth ceil(first Euclidean distance / h)
            xy = np.stack([(ci + oi) * h - p[0], (cj + oj) * h - p[1]], axis=1)
            e = np.hypot(xy[:, 0], xy[:, 1])
            need = int(math.ceil(e[good][cd[good] == d_first].min() / h)) + 1
            if need <= depth_cap or depth_cap >= limit:
                sel = good & (cd <= need)
                k = int(np.argmin(np.where(sel, e, np.inf)))
                if max_distance is not None and e[k] > max_distance:
                    return None
                return np.array([(ci[k] + oi) * h, (cj[k] + oj) * h], dtype=np.float64)
            depth_cap = min(limit, max(need, 2 * depth_cap))
            continue
        if depth_cap >= limit:
            return None
        depth_cap = min(limit, 2 * depth_cap)


def nearest_free_spot(
    space: ClearanceGrid,
    point: ArrayLike,
    avoid: np.ndarray | Sequence[Sequence[float]] | None = None,
    min_clearance: float | None = None,
    through_free: bool = True,
    accept: Callable[[np.ndarray], np.ndarray] | None = None,
    max_distance: float | None = None,
) -> np.ndarray | None:
    """``space.nearest_free(point, ...)``: see ``RobotSpace.nearest_free``."""
    p = np.asarray(point, dtype=np.float64).reshape(2)
    if not np.all(np.isfinite(p)):
        raise ValueError(f"point must be finite, got {point!r}")
    thr = space.threshold if min_clearance is None else float(min_clearance)
    h = space.resolution
    ny, nx = space.shape
    oi, oj = space.origin
    si = int(np.clip(round(p[0] / h) - oi, 0, nx - 1))
    sj = int(np.clip(round(p[1] / h) - oj, 0, ny - 1))
    start_free = space.field[sj, si] >= space.threshold
    limit = max(nx, ny) if max_distance is None else int(math.ceil(max_distance / h)) + 1
    # the search never goes more than ``limit`` hops from the start node: work on that
    # box of the grid only (a large space's whole grid costs more than the search)
    bi0, bj0 = max(0, si - limit), max(0, sj - limit)
    bi1, bj1 = min(nx - 1, si + limit), min(ny - 1, sj + limit)
    box = (slice(bj0, bj1 + 1), slice(bi0, bi1 + 1))
    si, sj, oi, oj = si - bi0, sj - bj0, oi + bi0, oj + bj0
    ny, nx = bj1 - bj0 + 1, bi1 - bi0 + 1
    ok = space.field[box] >= thr
    if avoid is not None:
        if isinstance(avoid, np.ndarray) and avoid.dtype == bool:
            if avoid.shape != space.shape:
                raise ValueError(f"avoid mask must have shape {space.shape}, got {avoid.shape}")
            ok = ok & ~avoid[box]
        else:
            _clear_disks(ok, avoid, h, oi, oj)
    reach = space.free_grid[box] if through_free and start_free else np.ones((ny, nx), bool)
    if ok[sj, si]:
        # the start node is the grid node nearest ``point`` and comes first in BFS
        # order: when it is valid it is the answer (a robot already where it may wait
        # costs one ``accept`` call)
        here = np.array([[(si + oi) * h, (sj + oj) * h]], dtype=np.float64)
        if (max_distance is None or math.hypot(*(here[0] - p)) <= max_distance) and (
                accept is None
                or bool(np.asarray(accept(here), dtype=bool).reshape(-1)[0])):
            return here[0]
    return _search(p, ok, reach, si, sj, oi, oj, h, limit, accept, max_distance)
