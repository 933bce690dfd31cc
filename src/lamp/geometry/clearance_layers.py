"""The layers a :class:`~lamp.geometry.robot_space.RobotSpace` is built from: the grid and
its windows, the cached static base layer (clearance to the scene's fixed obstacles), and
the byte-bounded LRU caches that keep them.

Conventions as in :mod:`lamp.geometry.robot_space`: ``field[j, i]`` is the clearance of grid
node ``(i * h, j * h)``; a window holds the node rectangle ``(i0, j0, i1, j1)`` (inclusive).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from lamp.geometry.geometry_set import GeometrySet, as_obstacle
from lamp.geometry.primitives import Obstacle
from lamp.geometry.static_field import clear_static_fields, static_field

__all__ = ["Derived", "as_obstacles", "base_layer", "base_window", "clear_base_layers",
           "grid_nodes", "lru_get", "lru_put", "static_token", "window_nodes"]

#: Most base layers kept, and their byte bound.
_BASE_CACHE_SIZE = 16
_BASE_CACHE_BYTES = 64 * 2**20

_BASE_CACHE: OrderedDict[Any, tuple[np.ndarray, GeometrySet]] = OrderedDict()


def clear_base_layers() -> None:
    """Drop the cached static base layers and tiled static fields."""
    _BASE_CACHE.clear()
    clear_static_fields()


def lru_get(cache: OrderedDict, key: Any) -> Any:
    val = cache.get(key)
    if val is not None:
        cache.move_to_end(key)
    return val


def lru_put(cache: OrderedDict, key: Any, val: Any, size: int,
             max_bytes: float = math.inf, nbytes: Callable[[Any], int] | None = None) -> None:
    """Insert ``val``; evict least recently used entries beyond ``size`` entries or
    beyond ``max_bytes`` in all (as measured by ``nbytes``; the newest entry stays)."""
    cache[key] = val
    cache.move_to_end(key)
    while len(cache) > size:
        cache.popitem(last=False)
    if nbytes is not None:
        # the plain dict's view: an OrderedDict's own re-hashes every key as it iterates
        # (tuples of obstacles, some hundred dataclass hashes each)
        total = sum(nbytes(v) for v in dict.values(cache))
        while total > max_bytes and len(cache) > 1:
            _, old = cache.popitem(last=False)
            total -= nbytes(old)


def grid_nodes(workspace: tuple[float, float], h: float) -> tuple[int, int]:
    """(NX, NY): nodes of the whole workspace grid of spacing ``h``."""
    W, H = workspace
    return int(math.floor(W / h + 1e-9)) + 1, int(math.floor(H / h + 1e-9)) + 1


def window_nodes(workspace: tuple[float, float], h: float,
                 window: Sequence[float] | None) -> tuple[int, int, int, int]:
    """(i0, j0, i1, j1): the grid nodes (inclusive) of the smallest node rectangle that
    covers ``window`` = (x0, y0, x1, y1) metres, clipped to the workspace (None: all)."""
    NX, NY = grid_nodes(workspace, h)
    if window is None:
        return 0, 0, NX - 1, NY - 1
    x0, y0, x1, y1 = (float(v) for v in window)
    if not all(math.isfinite(v) for v in (x0, y0, x1, y1)) or x1 < x0 or y1 < y0:
        raise ValueError(f"window must be finite (x0, y0, x1, y1) with x0 <= x1, y0 <= y1, "
                         f"got {window!r}")
    i0 = min(NX - 1, max(0, int(math.floor(x0 / h + 1e-9))))
    j0 = min(NY - 1, max(0, int(math.floor(y0 / h + 1e-9))))
    i1 = max(i0, min(NX - 1, int(math.ceil(x1 / h - 1e-9))))
    j1 = max(j0, min(NY - 1, int(math.ceil(y1 / h - 1e-9))))
    return i0, j0, i1, j1


def base_layer(
    workspace: tuple[float, float], obstacles: tuple[Obstacle, ...], h: float, cap: float,
    nodes: tuple[int, int, int, int],
) -> tuple[np.ndarray, GeometrySet]:
    """The clearance of the window ``nodes`` to the border and the static ``obstacles``
    (read-only, cached) and their geometry."""
    token = static_token(obstacles)
    key = (workspace, token, h, cap, nodes)
    hit = lru_get(_BASE_CACHE, key)
    if hit is not None:
        return hit
    field, geo = _from_tiles(workspace, obstacles, token, h, cap, nodes)
    field.setflags(write=False)
    lru_put(_BASE_CACHE, key, (field, geo), _BASE_CACHE_SIZE, _BASE_CACHE_BYTES,
             lambda v: v[0].nbytes)
    return field, geo


def base_window(
    workspace: tuple[float, float], obstacles: tuple[Obstacle, ...], h: float, cap: float,
    nodes: tuple[int, int, int, int],
) -> tuple[np.ndarray, GeometrySet]:
    """:func:`base_layer`'s values as a new writable array (from the map's tiled static
    field, ``static_field``: the same values), and the obstacles' geometry."""
    token = static_token(obstacles)
    hit = lru_get(_BASE_CACHE, (workspace, token, h, cap, nodes))
    if hit is not None:
        return hit[0].copy(), hit[1]
    return _from_tiles(workspace, obstacles, token, h, cap, nodes)


def _from_tiles(workspace: tuple[float, float], obstacles: tuple[Obstacle, ...], token: int,
                h: float, cap: float, nodes: tuple[int, int, int, int]
                ) -> tuple[np.ndarray, GeometrySet]:
    """The window ``nodes`` copied from the map's tiled static field (``token``: the
    obstacles' :func:`static_token`), and the obstacles' geometry."""
    sf = static_field(workspace, obstacles, token, h, cap, grid_nodes(workspace, h))
    return sf.window(nodes), sf.geometry


_TOKENS: OrderedDict[int, tuple[tuple, int]] = OrderedDict()
_TOKEN_COUNT = [0]


def static_token(obstacles: tuple) -> int:
    """A small integer standing for the static obstacle tuple ``obstacles`` in cache keys
    (hashing hundreds of obstacles per lookup would dominate on large maps). The same
    tuple object always gets the same token; an equal but distinct tuple may get another
    one, which costs a cache miss, never a wrong hit (tokens are never reused)."""
    hit = _TOKENS.get(id(obstacles))
    if hit is not None and hit[0] is obstacles:
        _TOKENS.move_to_end(id(obstacles))
        return hit[1]
    _TOKEN_COUNT[0] += 1
    _TOKENS[id(obstacles)] = (obstacles, _TOKEN_COUNT[0])
    while len(_TOKENS) > 64:
        _TOKENS.popitem(last=False)
    return _TOKEN_COUNT[0]


def as_obstacles(items: Iterable[Any]) -> tuple[Obstacle, ...]:
    """``items`` as a tuple of Obstacles (the same tuple object when it already is one)."""
    if isinstance(items, tuple) and all(type(o) is Obstacle for o in items):
        return items
    return tuple(as_obstacle(o) for o in items)


class Derived(dict):
    """A space's derived structures; keeps the bytes of its arrays (counted on insertion)."""

    nbytes = 0

    def __setitem__(self, key: Any, value: Any) -> None:
        if key in self:
            self.nbytes -= _derived_nbytes(self[key])
        super().__setitem__(key, value)
        self.nbytes += _derived_nbytes(value)


def _derived_nbytes(value: Any) -> int:
    """Bytes of the arrays held by a derived structure (an array or an object's arrays)."""
    if isinstance(value, np.ndarray):
        return value.nbytes
    total = 0
    for v in getattr(value, "__dict__", {}).values():
        if isinstance(v, np.ndarray):
            total += v.nbytes
        elif isinstance(v, dict):
            total += sum(x.nbytes for x in v.values() if isinstance(x, np.ndarray))
    return total
