"""The clearance of every robot grid node to a map's static obstacles, in tiles filled on
first use: what a :class:`~lamp.geometry.robot_space.RobotSpace` window starts from.

A space over a window of the grid starts from the clearance of its nodes to the border
and the static obstacles (capped at ``cap``), then lays the objects over it. Computing
that base for every window anew costs as much as the window holds: on a large map a
fleet's tasks ask for hundreds of distinct windows. :class:`StaticField` computes each
tile of ``TILE`` x ``TILE`` nodes once, the first time a window needs it, and a window's
base is then a copy of the tiles' parts.

Guarantee (``tests/test_static_field.py``): :meth:`StaticField.window` returns, bit for
bit, what computing the window alone returns (``clearance_kernels.fill_field`` gives a
window the whole grid's values for its nodes, and the border term is a function of a
node's index). Memory grows with the tiles the windows touch, up to ``budget`` bytes
(``STATIC_FIELD_BYTES`` by default): beyond it the tile used least recently is handed
back (``distance_tiles.drop_tile``) and filled again, the same, when a window needs it;
a window never drops a tile it reads itself, so one wider than the budget still fits.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import numpy as np

from lamp.geometry.clearance_kernels import fill_field
from lamp.geometry.distance_tiles import drop_tile, lazy_zeros, oldest_tile
from lamp.geometry.geometry_set import GeometrySet
from lamp.geometry.primitives import Obstacle

__all__ = ["STATIC_FIELD_BYTES", "StaticField", "TILE", "clear_static_fields", "static_field",
           "window_base"]

#: Nodes per tile side.
TILE = 128
#: Bytes of filled tiles a static field keeps (module doc): 384 tiles of 128 kB.
STATIC_FIELD_BYTES = 48 * 2**20
#: Static fields kept (one per map, workspace, resolution and cap): the most recent.
_KEPT = 2

_FIELDS: OrderedDict[Any, StaticField] = OrderedDict()


def window_base(workspace: tuple[float, float], obstacles: tuple[Obstacle, ...],
                geometry: GeometrySet, h: float, cap: float,
                nodes: tuple[int, int, int, int]) -> np.ndarray:
    """A new (rows, columns) array: the clearance of the window ``nodes`` = (i0, j0, i1,
    j1) (inclusive) to the border and ``obstacles`` (their ``geometry``), capped at
    ``cap``; ``field[j, i]`` is node ``(i0 + i, j0 + j)`` at ``((i0 + i) * h, (j0 + j) *
    h)``."""
    W, H = workspace
    i0, j0, i1, j1 = nodes
    xs = np.arange(i0, i1 + 1) * h
    ys = np.arange(j0, j1 + 1) * h
    bx = np.minimum(xs, W - xs)
    by = np.minimum(ys, H - ys)
    field = np.minimum(np.minimum(bx[None, :], by[:, None]), cap).astype(np.float64)
    fill_field(field, h, cap, geometry.circles, geometry.verts, geometry.ptr, i0, j0)
    return field


class StaticField:
    """Clearances of the grid nodes of ``workspace`` (spacing ``h``, ``n_nodes`` = (NX,
    NY)) to its border and ``obstacles``, capped at ``cap``, tiled, at most ``budget``
    bytes of tiles kept (module doc)."""

    def __init__(self, workspace: tuple[float, float], obstacles: tuple[Obstacle, ...],
                 h: float, cap: float, n_nodes: tuple[int, int],
                 budget: int = STATIC_FIELD_BYTES) -> None:
        self.workspace, self.obstacles, self.h, self.cap = workspace, obstacles, h, cap
        self.geometry = GeometrySet(obstacles)
        self.n_nodes = n_nodes
        self.filled = np.zeros((-(-n_nodes[1] // TILE), -(-n_nodes[0] // TILE)), dtype=bool)
        self._store = lazy_zeros((self.filled.size, TILE, TILE), np.float64)
        self.kept = max(1, int(budget) // (TILE * TILE * 8))  # tiles
        self._used = np.zeros(self.filled.shape, dtype=np.int64)  # last window to read each
        self._windows = 0

    @property
    def nbytes(self) -> int:
        """Bytes of the tiles filled so far."""
        return int(self.filled.sum()) * TILE * TILE * 8

    def window(self, nodes: tuple[int, int, int, int]) -> np.ndarray:
        """A new writable array: the window ``nodes`` = (i0, j0, i1, j1) (inclusive, inside
        the grid), as :func:`window_base` computes it."""
        i0, j0, i1, j1 = nodes
        out = np.empty((j1 - j0 + 1, i1 - i0 + 1))
        ntx = self.filled.shape[1]
        self._windows += 1
        self._used[j0 // TILE:j1 // TILE + 1, i0 // TILE:i1 // TILE + 1] = self._windows
        for tr in range(j0 // TILE, j1 // TILE + 1):
            for tc in range(i0 // TILE, i1 // TILE + 1):
                if not self.filled[tr, tc]:
                    self._make_room()
                    self._fill(tr, tc)
                a0, a1 = max(j0, tr * TILE), min(j1, tr * TILE + TILE - 1)
                b0, b1 = max(i0, tc * TILE), min(i1, tc * TILE + TILE - 1)
                out[a0 - j0:a1 - j0 + 1, b0 - i0:b1 - i0 + 1] = self._store[
                    tr * ntx + tc, a0 - tr * TILE:a1 - tr * TILE + 1,
                    b0 - tc * TILE:b1 - tc * TILE + 1]
        return out

    def _make_room(self) -> None:
        """Hand back the tile read least recently (the first in row order among ties)
        while ``kept`` are filled, never one the current window reads."""
        while int(self.filled.sum()) >= self.kept:
            flat = oldest_tile(self.filled, self._used, self._windows)
            if flat is None:
                return  # every filled tile is the current window's
            self.filled.flat[flat] = False
            drop_tile(self._store, flat)

    def _fill(self, tr: int, tc: int) -> None:
        nx, ny = self.n_nodes
        i0, j0 = tc * TILE, tr * TILE
        i1, j1 = min(nx, i0 + TILE) - 1, min(ny, j0 + TILE) - 1
        part = window_base(self.workspace, self.obstacles, self.geometry, self.h, self.cap,
                           (i0, j0, i1, j1))
        self._store[tr * self.filled.shape[1] + tc, :part.shape[0], :part.shape[1]] = part
        self.filled[tr, tc] = True


def static_field(workspace: tuple[float, float], obstacles: tuple[Obstacle, ...],
                 token: int, h: float, cap: float, n_nodes: tuple[int, int]) -> StaticField:
    """The :class:`StaticField` of ``obstacles`` (``token``: their
    ``clearance_layers.static_token``), kept for the ``_KEPT`` most recent maps."""
    key = (workspace, token, h, cap)
    hit = _FIELDS.get(key)
    if hit is None:
        hit = _FIELDS[key] = StaticField(workspace, obstacles, h, cap, n_nodes)
        while len(_FIELDS) > _KEPT:
            _FIELDS.popitem(last=False)
    _FIELDS.move_to_end(key)
    return hit


def clear_static_fields() -> None:
    """Drop the kept static fields."""
    _FIELDS.clear()

