"""The motion primitives of the SE(2) lattice (:mod:`lamp.search.lattice`) and their checks.

``PRIMITIVES`` are the 26 lattice offsets ``(di, dj, dk)`` (8 translations times {-1, 0, +1}
heading bins, and the 2 pure rotations), ``REVERSE`` the index of each one's reverse.
:func:`check_lattice_args` refuses a lattice whose primitives leave the model's range (or
whose arguments are malformed) with a ValueError naming the argument;
:func:`primitive_costs` gives each primitive's cost and the farthest one's reach.
:func:`successor_kernel` lists a node's valid edges, checking and caching
(``UNKNOWN``/``BLOCKED``/``FREE``) only what is not known yet; each motion is checked once,
from its lower-id end, and kept once.

A node's state and its edges' states share one ``uint32`` word of the *store*: the node's
2 bits (bits 0-1), then 2 bits for each of the 13 primitives of ``HALF`` (one of each pair
of mutually reverse primitives). The edge ``u -> v`` by primitive ``p`` is the edge
``v -> u`` by ``REVERSE[p]``; its state is kept once, in the word of ``u`` when ``p`` is in
``HALF`` and in the word of ``v`` otherwise (:data:`SLOT`). The words lie in tiles of
``EDGE_TILE`` x ``EDGE_TILE`` cells (every heading of a cell together; :func:`edge_words`
sizes the zero-filled store). Node ids run y-fastest, so a search along the x axis visits
cells ``n_j`` ids apart: stored by node id, each cell it visits would touch a page of its
own; tiled, a page holds four 4 x 4 tiles and the pages touched follow the area searched
(tested: ``tests/test_lattice_edge_store.py``). A node and its 26 edges take 4 bytes.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numba
import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.object_kernels import motion_free_kernel, pose_free_kernel
from lamp.search.metric import TWO_PI

if TYPE_CHECKING:
    from lamp.geometry.object_space import ObjectSpace

#: Cached validity of nodes and edges: not checked yet, checked and blocked, checked and free.
UNKNOWN, BLOCKED, FREE = 0, 1, 2
#: the 26 primitives (di, dj, dk): 8 translations x {-1, 0, +1} heading bins, 2 rotations
PRIMITIVES: tuple[tuple[int, int, int], ...] = tuple(
    (di, dj, dk)
    for di in (-1, 0, 1)
    for dj in (-1, 0, 1)
    for dk in (-1, 0, 1)
    if (di, dj, dk) != (0, 0, 0)
)
#: The index of each primitive's reverse (``PRIMITIVES[REVERSE[p]]`` undoes ``PRIMITIVES[p]``).
REVERSE = tuple(PRIMITIVES.index((-di, -dj, -dk)) for di, dj, dk in PRIMITIVES)
#: One primitive of each mutually reverse pair: the edges a node's word holds.
HALF = tuple(p for p in range(len(PRIMITIVES)) if p < REVERSE[p])
#: Where primitive ``p``'s edge is kept: ``SLOT[p] = s >= 0``, bits ``2 + 2 s`` of the word of
#: the node it leaves (``p`` is ``HALF[s]``); ``s < 0``, bits ``2 + 2 (-1 - s)`` of the word of
#: the node it reaches (``REVERSE[p]`` is ``HALF[-1 - s]``).
SLOT = tuple(HALF.index(p) if p in HALF else -1 - HALF.index(REVERSE[p])
             for p in range(len(PRIMITIVES)))
#: The store's word: a node's state and its ``HALF`` of the edges' (module docstring).
STORE_DTYPE = np.uint32
#: Side (cells) of the square tiles the words are stored in (module docstring).
EDGE_TILE = 4
assert 2 + 2 * len(HALF) <= 32  # a node's state and its half of the edges fit one uint32


def edge_words(n_i: int, n_j: int, n_k: int) -> int:
    """Words of the store of an ``n_i x n_j`` cell lattice with ``n_k`` headings (whole
    tiles: up to ``EDGE_TILE - 1`` cells of padding on each axis)."""
    t = EDGE_TILE
    return -(-n_i // t) * -(-n_j // t) * t * t * n_k


def _word(ii: ArrayLike, jj: ArrayLike, k: ArrayLike, n_j: int, n_k: int) -> ArrayLike:
    """The word of the store holding node ``(ii, jj, k)``'s state (and half its edges'):
    of ints, an int; of int64 arrays, an array."""
    t = EDGE_TILE
    ti = ii // t
    tj = jj // t
    return ((((ti * ((n_j + t - 1) // t) + tj) * t + (ii - ti * t)) * t + (jj - tj * t))
            * n_k + k)


#: :func:`_word` compiled, for the kernels.
edge_word = numba.njit(cache=True, inline="always")(_word)


def node_words(u: np.ndarray, n_j: int, n_k: int) -> np.ndarray:
    """:func:`edge_word` of int64 node ids (vectorised)."""
    rest, k = np.divmod(np.asarray(u, dtype=np.int64), n_k)
    ii, jj = np.divmod(rest, n_j)
    return _word(ii, jj, k, n_j, n_k)


@numba.njit(cache=True, inline="always")
def word_state(store: np.ndarray, w: int, shift: int) -> int:
    """The 2-bit state at bit ``shift`` of word ``w`` (``shift`` 0: the node's)."""
    return (int(store[w]) >> shift) & 3


def check_lattice_args(
    space: ObjectSpace, anchor: ArrayLike, step: float, n_headings: int, w_rot: float | None,
    max_translation: float, max_rotation: float, succ_kept: int = 0,
) -> tuple[np.ndarray, float, float]:
    """``ObjectLattice``'s arguments checked: (anchor as a float array, rotation weight
    (default: the object's bounding radius), heading bin width). ValueError when one is
    malformed or a primitive leaves the model's range."""
    if not succ_kept >= 0:
        raise ValueError(f"succ_kept must be >= 0, got {succ_kept!r}")
    anchor = np.asarray(anchor, dtype=float)
    if anchor.shape != (3,) or not np.all(np.isfinite(anchor)):
        raise ValueError(f"anchor must be a finite (x, y, theta) pose, got {anchor!r}")
    if not (step > 0 and math.isfinite(step)):
        raise ValueError(f"step must be finite and > 0, got {step!r}")
    if not (isinstance(n_headings, (int, np.integer)) and n_headings >= 3):
        raise ValueError(f"n_headings must be an integer >= 3, got {n_headings!r}")
    if w_rot is None:
        w_rot = float(space.shape.bounding_radius)
    if not (w_rot >= 0 and math.isfinite(w_rot)):
        raise ValueError(f"w_rot must be finite and >= 0, got {w_rot!r}")
    dtheta = TWO_PI / n_headings
    if step * math.sqrt(2.0) > max_translation + 1e-12:
        raise ValueError(
            f"step {step} gives diagonal primitives beyond max_translation {max_translation}"
        )
    if dtheta > max_rotation + 1e-12:
        raise ValueError(
            f"n_headings {n_headings} gives rotations of {dtheta:.3f} rad beyond "
            f"max_rotation {max_rotation}"
        )
    return anchor, w_rot, dtheta


def primitive_costs(step: float, w_rot: float, dtheta: float
                    ) -> tuple[np.ndarray, np.ndarray, float]:
    """(primitives as a (26, 3) int array, their costs (translation length +
    ``w_rot * |dtheta|``), the farthest a primitive moves the object's origin (m))."""
    prim = np.array(PRIMITIVES, dtype=int)
    cost = step * np.hypot(prim[:, 0], prim[:, 1]) + w_rot * dtheta * np.abs(prim[:, 2])
    reach = float(step * np.max(np.hypot(prim[:, 0], prim[:, 1])))
    return prim, cost, reach


@numba.njit(cache=True)
def successor_kernel(
    u: int,
    n_i: int,
    n_j: int,
    n_k: int,
    i_min: int,
    j_min: int,
    ax: float,
    ay: float,
    at: float,
    step: float,
    dth: float,
    prim: np.ndarray,
    slot: np.ndarray,
    store: np.ndarray,
    out_ids: np.ndarray,
    out_prim: np.ndarray,
    margin: float,
    reach: float,
    sd: tuple,
    res: float,
    width: float,
    height: float,
    fp: tuple,
    reach2: float,
) -> tuple[int, int, int]:
    """Fill ``out_ids``/``out_prim`` with u's valid edges, checking (and caching in the
    ``store``, module docstring) what is unknown. Returns (count, pose checks, motion
    checks). Poses are computed exactly as ``ObjectLattice.poses`` does; each motion is
    checked from its lower-id end and stored once, where ``slot`` (:data:`SLOT`) says."""
    rest = u // n_k
    k = u - rest * n_k
    ii = rest // n_j
    jj = rest - ii * n_j
    wu = edge_word(ii, jj, k, n_j, n_k)
    two_pi = 2.0 * math.pi
    xu = ax + (ii + i_min) * step
    yu = ay + (jj + j_min) * step
    tu = (at + k * dth + math.pi) % two_pi - math.pi
    n_pose = 0
    n_motion = 0
    if word_state(store, wu, 0) == UNKNOWN:
        store[wu] |= np.uint32(BLOCKED + pose_free_kernel(xu, yu, tu, sd, res, width, height,
                                                          fp, reach2))
        n_pose += 1
    if word_state(store, wu, 0) == BLOCKED:
        return 0, n_pose, n_motion
    n = 0
    for p in range(prim.shape[0]):
        ni = ii + prim[p, 0]
        nj = jj + prim[p, 1]
        if ni < 0 or ni >= n_i or nj < 0 or nj >= n_j:
            continue
        nk = (k + prim[p, 2]) % n_k
        v = (ni * n_j + nj) * n_k + nk
        wv = edge_word(ni, nj, nk, n_j, n_k)
        xv = ax + (ni + i_min) * step
        yv = ay + (nj + j_min) * step
        tv = (at + nk * dth + math.pi) % two_pi - math.pi
        if word_state(store, wv, 0) == UNKNOWN:
            store[wv] |= np.uint32(BLOCKED + pose_free_kernel(xv, yv, tv, sd, res, width,
                                                              height, fp, reach2))
            n_pose += 1
        if word_state(store, wv, 0) == BLOCKED:
            continue
        s = slot[p]
        w = wu if s >= 0 else wv
        shift = 2 + 2 * (s if s >= 0 else -1 - s)
        if word_state(store, w, shift) == UNKNOWN:
            if u < v:
                free = motion_free_kernel(
                    xu, yu, tu, xv, yv, tv, margin, reach, sd, res, width, height, fp, reach2
                )
            else:
                free = motion_free_kernel(
                    xv, yv, tv, xu, yu, tu, margin, reach, sd, res, width, height, fp, reach2
                )
            n_motion += 1
            store[w] |= np.uint32((BLOCKED + free) << shift)
        if word_state(store, w, shift) == FREE:
            out_ids[n] = v
            out_prim[n] = p
            n += 1
    return n, n_pose, n_motion
