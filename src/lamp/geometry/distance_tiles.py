"""The obstacle distance grid of :class:`~lamp.geometry.object_space.ObjectSpace`, in tiles.

The grid has cells of side ``resolution`` covering the workspace; a cell is *occupied*
when its centre lies within half a cell diagonal ``h`` of an obstacle, and a free cell
stores ``D - 2h``, ``D`` the distance from its centre to the nearest occupied centre
(see :mod:`lamp.geometry.object_space` for why that is a clearance lower bound).

The grid is held as square tiles of ``TILE`` x ``TILE`` cells and a table of which tile
holds which block (-1: not filled; a compiled reader answers -inf there, which callers
read as "not free", so a missing tile can never make a colliding pose free).

* **Small maps** (at most ``FULL_GRID_CELLS`` cells): one distance transform over the
  whole grid, cut into tiles at once; the values are exactly the whole-grid values.
* **Large maps**: tiles are filled on demand (:meth:`DistanceTiles.ensure`), each by a
  distance transform over the tile plus a halo of ``cap`` metres. An occupied centre
  within ``cap`` of a cell lies in that halo, so a cell stores ``min(D, cap) - 2h``:
  exact where ``D <= cap`` and capped beyond (still a lower bound), stored as float32
  rounded down (so still a lower bound, within 1e-7 relative of the float64 value).
  Memory and time grow with the part of the map the queries touch, not with the map.
* **A shared base** (large maps): a grid may be laid over a ``base`` grid of the map's
  static obstacles (:func:`shared_tiles`: one per obstacle tuple, workspace, resolution
  and cap, shared by every grid over it while one lives). A tile whose halo none of the
  grid's own obstacles reaches holds what the base's tile holds (the same occupancy,
  so the same values), and the grid points to the base's tile instead of a copy: a
  grid holds only the tiles its own obstacles change. The table tells: ``t >= 0`` the
  grid's tile ``t``, ``-1`` not filled, ``t <= -2`` the base's tile ``-2 - t``.
* **A base keeps at most ``SHARED_KEPT_BYTES``** of tiles: filling one more hands back
  the tile asked for longest ago (by an :meth:`DistanceTiles.ensure` of any grid over it;
  a box a grid already knew filled is not asked for again), and every grid over it that
  pointed there reads it as not filled again, so its next ``ensure`` fills it again, the
  same. A tile some part of the ``ensure`` under way asked
  for is never handed back (that call's reads follow it), so a call that needs more
  tiles than the budget still gets them all. Memory follows what the searches touch
  lately, not the map.
"""

from __future__ import annotations

import math
import mmap
import weakref
from collections.abc import Sequence
from functools import lru_cache

import numpy as np
import shapely
from numpy.typing import ArrayLike
from scipy import ndimage

from lamp.geometry.primitives import Obstacle
from lamp.geometry.shapes import obstacle_geometry

__all__ = ["DistanceTiles", "TILE", "FULL_GRID_CELLS", "DEFAULT_GRID_CAP", "SHARED_KEPT_BYTES",
           "drop_tile", "lazy_zeros", "obstacle_box", "obstacle_cells", "oldest_tile",
           "shared_tiles"]

#: Cells per tile side.
TILE = 128
#: Grids of at most this many cells are computed whole and exact (4 m maps: 1e6 cells).
FULL_GRID_CELLS = 2**22
#: Distances are exact up to this (m) in tiles filled on demand (spaces raise it to their
#: footprint's ``min_grid_cap`` where needed).
DEFAULT_GRID_CAP = 0.15
#: Tiles filled on demand are stored in blocks of this many.
_GROW = 64
#: Bytes of tiles a shared base keeps (module doc): 1,536 tiles of float32.
SHARED_KEPT_BYTES = 96 * 2**20


def grid_shape(workspace: tuple[float, float], resolution: float) -> tuple[int, int]:
    """(rows, columns) of the obstacle grid: cells of side ``resolution`` covering the
    workspace (at least one each way). One definition, so that every obstacle's cells and
    the grid they are written into agree."""
    nx = max(1, math.ceil(workspace[0] / resolution - 1e-9))
    ny = max(1, math.ceil(workspace[1] / resolution - 1e-9))
    return ny, nx


@lru_cache(maxsize=4096)
def obstacle_box(
    obstacle: Obstacle, workspace: tuple[float, float], resolution: float
) -> tuple[shapely.Geometry, int, int, int, int] | None:
    """The cells one obstacle may occupy: (its outline grown by half a cell diagonal,
    row0, col0, row1, col1), or None when that box misses the grid. Cheap: no cell is
    tested (:func:`obstacle_cells` does that, for the tiles that need it)."""
    ny, nx = grid_shape(workspace, resolution)
    h = resolution / math.sqrt(2.0)
    geom = obstacle_geometry(obstacle).buffer(h, quad_segs=8)
    x0, y0, x1, y1 = geom.bounds
    c0 = max(0, math.floor(x0 / resolution - 0.5))
    c1 = min(nx - 1, math.ceil(x1 / resolution - 0.5))
    r0 = max(0, math.floor(y0 / resolution - 0.5))
    r1 = min(ny - 1, math.ceil(y1 / resolution - 0.5))
    if c1 < c0 or r1 < r0:
        return None
    return geom, r0, c0, r1, c1


@lru_cache(maxsize=4096)
def obstacle_cells(
    obstacle: Obstacle, workspace: tuple[float, float], resolution: float
) -> tuple[int, int, np.ndarray] | None:
    """Occupied cells of one obstacle: (row0, col0, bool mask) or None when none.

    A cell is occupied when its centre is within half a cell diagonal of the obstacle.
    Cached per obstacle: scenes share static obstacles across many ObjectSpaces.
    """
    box = obstacle_box(obstacle, workspace, resolution)
    if box is None:
        return None
    geom, r0, c0, r1, c1 = box
    xs = (np.arange(c0, c1 + 1) + 0.5) * resolution
    ys = (np.arange(r0, r1 + 1) + 0.5) * resolution
    gx, gy = np.meshgrid(xs, ys)
    mask = shapely.contains_xy(geom, gx, gy) | shapely.intersects_xy(geom.boundary, gx, gy)
    if not mask.any():
        return None
    return r0, c0, mask


def _round_down(values: np.ndarray) -> np.ndarray:
    """float32 values, each at most the float64 value it stands for."""
    v32 = values.astype(np.float32)
    up = v32.astype(np.float64) > values
    v32[up] = np.nextafter(v32[up], np.float32(-np.inf))
    return v32


class DistanceTiles:
    """The obstacle distance grid of ``obstacles`` in ``workspace`` (see module doc).

    ``args`` is what the compiled readers take: ``(tiles, base tiles, table, rows,
    columns)``. ``capped`` tells whether tiles are filled on demand with distances capped
    at ``cap``. With ``base`` (a capped grid of the same workspace, resolution and cap)
    the distances are those of its obstacles and ``obstacles`` together, and tiles that
    ``obstacles`` leave alone are the base's (module doc). ``slotted``: every tile has its
    place in one store allocated at once (untouched pages take no memory), so the store
    is never moved: what a base needs, as grids over it hold its store.
    """

    def __init__(self, workspace: tuple[float, float], obstacles: Sequence[Obstacle],
                 resolution: float, cap: float = DEFAULT_GRID_CAP,
                 full_grid_cells: int = FULL_GRID_CELLS, base: DistanceTiles | None = None,
                 slotted: bool = False) -> None:
        if not (cap > 0 and math.isfinite(cap)):
            raise ValueError(f"cap must be finite and > 0, got {cap!r}")
        self.workspace = (float(workspace[0]), float(workspace[1]))
        self.resolution = float(resolution)
        self.shape = grid_shape(self.workspace, self.resolution)
        ny, nx = self.shape
        self.two_h = 2.0 * self.resolution / math.sqrt(2.0)
        self.cap = float(cap)
        self._halo = int(math.ceil(self.cap / self.resolution))
        self.table = np.full((-(-ny // TILE), -(-nx // TILE)), -1, dtype=np.int32)
        self.capped = ny * nx > full_grid_cells
        if base is not None and not (base.capped and base.shape == self.shape and self.capped
                                     and (base.resolution, base.cap) == (resolution, cap)):
            raise ValueError("base must be a capped grid of this grid's workspace, "
                             "resolution and cap")
        self.slotted = bool(slotted) and self.capped
        dtype = np.float32 if self.capped else np.float64
        self._store = (lazy_zeros((self.table.size, TILE, TILE), dtype) if self.slotted
                       else np.zeros((0, TILE, TILE), dtype=dtype))
        self._n = 0
        #: tile boxes (tx0, ty0, tx1, ty1) known to be filled
        self._ready: set[tuple[int, int, int, int]] = set()
        # each obstacle's cells are tested when a tile within its box is first filled
        boxes = [(ob, obstacle_box(ob, self.workspace, self.resolution)) for ob in obstacles]
        own = np.array([b[1:] for _, b in boxes if b is not None], dtype=np.int64).reshape(-1, 4)
        self._base, self._own_boxes = base, own
        #: with a budget (``keep``): the tiles kept, each tile's last ``ensure`` (``_tick``)
        self.kept: int | None = None
        self._used = np.zeros(self.table.shape, dtype=np.int64)
        self._tick = 0
        self._over: weakref.WeakSet[DistanceTiles] = weakref.WeakSet()  # grids over it
        if base is not None:
            base._over.add(self)
        self._obstacles = ([] if base is None else base._obstacles) + [
            ob for ob, b in boxes if b is not None]
        self._boxes = own if base is None else np.concatenate([base._boxes, own])
        if not self.capped:
            self._fill_whole()
        self._refresh()

    def keep(self, budget: int) -> None:
        """Keep at most ``budget`` bytes of tiles from now on (a slotted grid: module doc)."""
        if not self.slotted:
            raise ValueError("only a slotted grid keeps a budget")
        self.kept = max(1, int(budget) // (TILE * TILE * self._store.itemsize))

    def _begin(self, flat: np.ndarray) -> None:
        """An ``ensure`` starts that reads the tiles ``flat`` (table indices): those it
        reads of a grid keeping a budget (its base's, its own) are marked as used by the
        call now under way."""
        t = self.table.ravel()[flat]
        for grid, mine in ((self._base, t <= -2), (self, t >= 0)):
            if grid is not None and grid.kept is not None:
                grid._tick += 1
                grid._used.ravel()[flat[mine]] = grid._tick

    def _make_room(self) -> None:
        """Hand back the tile used least recently (module doc) while ``kept`` are filled,
        never one the ``ensure`` under way reads; the grids over this one that pointed
        there forget it."""
        while self._n >= self.kept:
            flat = oldest_tile(self.table >= 0, self._used, self._tick)
            if flat is None:
                return
            self.table.flat[flat] = -1
            self._n -= 1
            drop_tile(self._store, flat)
            for grid in list(self._over):
                if grid.table.flat[flat] == -2 - flat:
                    grid.table.flat[flat] = -1
                    grid._ready.clear()
            self._ready.clear()

    def _refresh(self) -> None:
        """``args`` for the tiles filled so far."""
        store = self._store if self.slotted else self._store[: self._n]
        base = self._store[:0] if self._base is None else self._base._store
        self.args = (store, base, self.table, *self.shape)

    # ---------------------------------------------------------------- filling
    def _occupancy(self, r0: int, c0: int, r1: int, c1: int) -> np.ndarray:
        """Occupied cells of rows r0..r1 and columns c0..c1 (inclusive)."""
        occ = np.zeros((r1 - r0 + 1, c1 - c0 + 1), dtype=bool)
        b = self._boxes
        hit = np.nonzero(_meets(b, r0, c0, r1, c1))[0]
        for k in hit.tolist():
            cells = obstacle_cells(self._obstacles[k], self.workspace, self.resolution)
            if cells is None:
                continue
            rr, cc, mask = cells
            a0, a1 = max(rr, r0), min(rr + mask.shape[0] - 1, r1)
            b0, b1 = max(cc, c0), min(cc + mask.shape[1] - 1, c1)
            occ[a0 - r0 : a1 - r0 + 1, b0 - c0 : b1 - c0 + 1] |= mask[
                a0 - rr : a1 - rr + 1, b0 - cc : b1 - cc + 1]
        return occ

    def _reserve(self, n: int) -> None:
        if n > len(self._store) and not self.slotted:
            size = n if not self.capped else _GROW * -(-n // _GROW)
            grown = np.zeros((size, TILE, TILE), dtype=self._store.dtype)
            grown[: self._n] = self._store[: self._n]
            self._store = grown

    def _fill_whole(self) -> None:
        ny, nx = self.shape
        occ = self._occupancy(0, 0, ny - 1, nx - 1)
        if not occ.any():
            sd = np.full((ny, nx), np.inf)
        else:
            sd = ndimage.distance_transform_edt(~occ, sampling=self.resolution) - self.two_h
        nty, ntx = self.table.shape
        self._reserve(nty * ntx)
        for tr in range(nty):
            for tc in range(ntx):
                blk = sd[tr * TILE : (tr + 1) * TILE, tc * TILE : (tc + 1) * TILE]
                self._store[self._n, : blk.shape[0], : blk.shape[1]] = blk
                self.table[tr, tc] = self._n
                self._n += 1

    def _fill_tile(self, tr: int, tc: int) -> None:
        ny, nx = self.shape
        r0, c0 = tr * TILE, tc * TILE
        r1, c1 = min(ny, r0 + TILE) - 1, min(nx, c0 + TILE) - 1
        g = self._halo
        R0, C0 = max(0, r0 - g), max(0, c0 - g)
        R1, C1 = min(ny - 1, r1 + g), min(nx - 1, c1 + g)
        base = self._base
        if base is not None and not _meets(self._own_boxes, R0, C0, R1, C1).any():
            if base.table[tr, tc] == -1:  # the same occupancy: the base's tile
                base._fill_tile(tr, tc)
            base._used[tr, tc] = base._tick
            self.table[tr, tc] = -2 - base.table[tr, tc]
            return
        if self.kept is not None:
            self._make_room()
        occ = self._occupancy(R0, C0, R1, C1)
        slot = tr * self.table.shape[1] + tc if self.slotted else self._n
        self._reserve(self._n + 1)
        out = self._store[slot]
        if occ.any():
            d = ndimage.distance_transform_edt(~occ, sampling=self.resolution)
            blk = np.minimum(d[r0 - R0 : r1 - R0 + 1, c0 - C0 : c1 - C0 + 1], self.cap)
            out[: blk.shape[0], : blk.shape[1]] = _round_down(blk - self.two_h)
        else:
            out[:] = _round_down(np.array([self.cap - self.two_h]))[0]
        self.table[tr, tc] = slot
        self._used[tr, tc] = self._tick
        self._n += 1

    def ensure_point(self, x: float, y: float, radius: float) -> None:
        """:meth:`ensure` for one point (the search's per-node call: no arrays)."""
        if not self.capped:
            return
        span = TILE * self.resolution
        nty, ntx = self.table.shape
        tx0, tx1 = max(0, int((x - radius) // span)), min(ntx - 1, int((x + radius) // span))
        ty0, ty1 = max(0, int((y - radius) // span)), min(nty - 1, int((y + radius) // span))
        key = (tx0, ty0, tx1, ty1)
        if key in self._ready:
            return
        table = self.table
        box = [(tr, tc) for tr in range(ty0, ty1 + 1) for tc in range(tx0, tx1 + 1)]
        self._begin(np.array([tr * ntx + tc for tr, tc in box], dtype=np.int64))
        todo = [(tr, tc) for tr, tc in box if table[tr, tc] == -1]
        for tr, tc in todo:
            self._fill_tile(tr, tc)
        if todo:
            self._refresh()
        self._ready.add(key)

    def ensure(self, points: ArrayLike, radius: float) -> None:
        """Fill every tile holding a cell within ``radius`` (m) of the (..., 2) world
        ``points``, so that compiled reads there see values, not -inf."""
        if not self.capped:
            return
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        if not len(p):
            return
        ny, nx = self.shape
        span = TILE * self.resolution
        nty, ntx = self.table.shape
        lo = np.maximum(np.floor((p - radius) / span).astype(np.int64), 0)
        hi = np.minimum(np.floor((p + radius) / span).astype(np.int64), [ntx - 1, nty - 1])
        ext = np.maximum(hi - lo, -1).max(axis=0)
        ids = []
        for ox in range(int(ext[0]) + 1):
            for oy in range(int(ext[1]) + 1):
                tx, ty = lo[:, 0] + ox, lo[:, 1] + oy
                ok = (tx <= hi[:, 0]) & (ty <= hi[:, 1])
                ids.append(ty[ok] * ntx + tx[ok])
        flat = np.unique(np.concatenate(ids)) if ids else np.zeros(0, np.int64)
        self._begin(flat)
        missing = flat[self.table.ravel()[flat] == -1]
        need = [(int(f // ntx), int(f % ntx)) for f in missing]
        if not need:
            return
        for tr, tc in need:
            self._fill_tile(tr, tc)
        self._refresh()

    @property
    def nbytes(self) -> int:
        """Bytes of the tiles this grid filled (not its base's) and the table."""
        return int(self._n * TILE * TILE * self._store.itemsize + self.table.nbytes)

    def values(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Stored values of cells (rows, cols) (indices inside the grid); -inf where the
        tile is not filled."""
        tiles, base, table = self.args[:3]
        t = table[rows // TILE, cols // TILE]
        out = np.full(np.shape(rows), -np.inf)
        r, c = rows % TILE, cols % TILE
        own, shared = t >= 0, t <= -2
        out[own] = tiles[t[own], r[own], c[own]]
        out[shared] = base[-2 - t[shared], r[shared], c[shared]]
        return out


def lazy_zeros(shape: tuple[int, ...], dtype: type) -> np.ndarray:
    """Zeros whose pages the system provides as they are first written: a private
    anonymous mapping of its own, in small pages (numpy asks for huge pages on large
    arrays, which would make one written tile hold 2 MB); :func:`drop_tile` hands pages
    back."""
    size = int(np.prod(shape)) * np.dtype(dtype).itemsize
    private = getattr(mmap, "MAP_PRIVATE", None)  # (a shared mapping keeps dropped pages)
    mapping = (mmap.mmap(-1, max(1, size)) if private is None else
               mmap.mmap(-1, max(1, size), flags=private | mmap.MAP_ANONYMOUS))
    return np.frombuffer(mapping, dtype=dtype, count=int(np.prod(shape))).reshape(shape)


def oldest_tile(filled: np.ndarray, used: np.ndarray, now: int) -> int | None:
    """The flat index of the ``filled`` tile whose ``used`` stamp is oldest (the first in
    row order among ties), or None when every filled one was used at ``now`` or later
    (by the call under way: it must not be handed back)."""
    stamps = np.where(filled, used, np.iinfo(np.int64).max).ravel()
    flat = int(np.argmin(stamps))
    return None if stamps[flat] >= now else flat


def drop_tile(store: np.ndarray, index: int) -> None:
    """Hand the pages of ``store[index]`` back to the system (``store`` from
    :func:`lazy_zeros`, whose tiles are whole pages): they read as zeros again and take no
    memory until written."""
    owner = store.base
    while isinstance(owner, np.ndarray | memoryview):
        owner = owner.obj if isinstance(owner, memoryview) else owner.base
    size = store[0].nbytes
    if isinstance(owner, mmap.mmap) and size % mmap.PAGESIZE == 0:
        owner.madvise(mmap.MADV_DONTNEED, index * size, size)
    else:  # (not page-aligned tiles: written over, not handed back)
        store[index] = 0


def _meets(boxes: np.ndarray, r0: int, c0: int, r1: int, c1: int) -> np.ndarray:
    """Which (row0, col0, row1, col1) ``boxes`` meet rows r0..r1 and columns c0..c1."""
    return (boxes[:, 0] <= r1) & (boxes[:, 2] >= r0) & (boxes[:, 1] <= c1) & (boxes[:, 3] >= c0)


#: The live shared bases (:func:`shared_tiles`), freed with the last grid over them.
_SHARED: weakref.WeakValueDictionary = weakref.WeakValueDictionary()


def shared_tiles(workspace: tuple[float, float], obstacles: tuple[Obstacle, ...],
                 resolution: float, cap: float) -> DistanceTiles:
    """The slotted, capped grid of ``obstacles`` (a map's static obstacles) that grids over
    the same tuple object, workspace, resolution and cap share as their ``base``: one
    while any of them lives."""
    key = (id(obstacles), tuple(float(v) for v in workspace), float(resolution), float(cap))
    hit = _SHARED.get(key)
    if hit is not None and hit.static is obstacles:
        return hit
    base = DistanceTiles(workspace, obstacles, resolution, cap, full_grid_cells=0, slotted=True)
    base.keep(SHARED_KEPT_BYTES)
    base.static = obstacles  # held: no other tuple takes its id while the base lives
    _SHARED[key] = base
    return base
