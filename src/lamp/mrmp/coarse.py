"""A coarse graph of a lattice for the fleet assignment: blocks of lattice nodes.

The lattice's index grid is cut into square blocks of :data:`BLOCK` x :data:`BLOCK`
indices (15 cm on the 3 cm lattice); a block with free nodes is a coarse node, and two
8-adjacent blocks are linked when some lattice edge joins their nodes, a block side long
(its diagonal for a corner link). A robot-goal pair's *coarse distance* is the way start ->
its block's centroid -> (block links) -> the goal's block's centroid -> goal, and never
less than their straight line (the straight line when both lie in one block).

What it is for: an assignment of a fleet whose longest way and summed ways are those of the
coarse distances costs searches over a twenty-fifth of the nodes the exact lattice
distances need (:mod:`lamp.mrmp.assignment`). What it guarantees: nothing about the lattice
distances themselves (a block whose nodes are joined only through other blocks looks
joined; a coarse distance can be shorter or longer than the lattice's), so the caller
checks every chosen pair on the lattice.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba as nb
import numpy as np

__all__ = ["BLOCK", "CoarseGraph", "coarse_below", "get_coarse"]

#: Side of a block, in lattice steps.
BLOCK = 5


class CoarseGraph(NamedTuple):
    """``block[v]``: the block of lattice node v; ``rep (B, 2)``: each block's centroid;
    ``nbr (B, 8)``: adjacent blocks (-1 none), ``wlen (B, 8)``: the links' lengths (a
    block side ``unit`` across, its diagonal corner to corner)."""

    block: np.ndarray
    rep: np.ndarray
    nbr: np.ndarray
    wlen: np.ndarray
    unit: float


@nb.njit(cache=True)
def _build(va: np.ndarray, vb: np.ndarray, coords: np.ndarray, lnbr: np.ndarray, nat: int,
           nbt: int, k: int, unit: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    naB = (nat + k - 1) // k
    nbB = (nbt + k - 1) // k
    V = va.shape[0]
    cell = np.empty(V, np.int64)
    bid = np.full(naB * nbB, -1, np.int64)
    B = 0
    for v in range(V):
        c = (vb[v] // k) * naB + va[v] // k
        cell[v] = c
        if bid[c] < 0:
            bid[c] = B
            B += 1
    block = np.empty(V, np.int64)
    rep = np.zeros((B, 2))
    cnt = np.zeros(B)
    for v in range(V):
        p = bid[cell[v]]
        block[v] = p
        rep[p, 0] += coords[v, 0]
        rep[p, 1] += coords[v, 1]
        cnt[p] += 1.0
    for p in range(B):
        rep[p, 0] /= cnt[p]
        rep[p, 1] /= cnt[p]
    nbr = np.full((B, 8), -1, np.int64)
    for v in range(V):
        p = block[v]
        for e in range(8):
            w = lnbr[v, e]
            if w < 0:
                continue
            q = block[w]
            if q == p:
                continue
            dx = cell[w] % naB - cell[v] % naB
            dy = cell[w] // naB - cell[v] // naB
            d = (dy + 1) * 3 + dx + 1  # 0..8 without 4 (same block)
            slot = d if d < 4 else d - 1
            nbr[p, slot] = q
    wlen = np.full((B, 8), np.inf)
    for p in range(B):
        for s in range(8):
            if nbr[p, s] >= 0:
                wlen[p, s] = unit * (math.sqrt(2.0) if s in (0, 2, 5, 7) else 1.0)
    return block, rep, nbr, wlen


def get_coarse(lat: Any) -> CoarseGraph:
    """The coarse graph of lattice ``lat`` (built once, kept on the lattice)."""
    cg = getattr(lat, "_coarse", None)
    if cg is None:
        nbt, nat = lat.ids.shape
        unit = BLOCK * lat.step
        cg = CoarseGraph(*_build(lat.va, lat.vb, lat.coords, lat.nbr, nat, nbt, BLOCK, unit),
                         unit)
        lat._coarse = cg
    return cg


@nb.njit(cache=True)
def coarse_below(pm: np.ndarray, pi: np.ndarray, bound: float, sblk: np.ndarray,
                 gblk: np.ndarray, S: np.ndarray, G: np.ndarray, rep: np.ndarray,
                 nbr: np.ndarray, wlen: np.ndarray, unit: float) -> np.ndarray:
    """For pairs (goal ``pm[k]``, robot ``pi[k]``), grouped by goal: the coarse distance
    when it is below ``bound``, else inf (``sblk``/``gblk``: the blocks of the starts and
    goals, -1 none; one search over the blocks per goal, stopped at ``bound``: Dial's
    buckets of width ``unit``, no block link being shorter)."""
    B = rep.shape[0]
    dist = np.full(B, np.inf)
    done = np.zeros(B, np.uint8)
    touched = np.empty(B, np.int64)
    bk = np.empty((4, 8 * B + 16), np.int64)
    cnt = np.zeros(4, np.int64)
    out = np.full(pm.shape[0], np.inf)
    nt = 0
    k = 0
    while k < pm.shape[0]:
        m = pm[k]
        for t in range(nt):
            dist[touched[t]] = np.inf
            done[touched[t]] = 0
        nt = 0
        g = gblk[m]
        if g >= 0:
            cnt[:] = 0
            d0 = math.hypot(G[m, 0] - rep[g, 0], G[m, 1] - rep[g, 1])
            dist[g] = d0
            touched[0] = g
            nt = 1
            b = int(d0 / unit)
            bk[b & 3, 0] = g
            cnt[b & 3] = 1
            left = 1
            while left > 0 and b * unit < bound:
                s = b & 3
                if cnt[s] == 0:
                    b += 1
                    continue
                cnt[s] -= 1
                left -= 1
                p = bk[s, cnt[s]]
                if done[p]:
                    continue
                done[p] = 1
                for e in range(8):
                    q = nbr[p, e]
                    if q < 0 or done[q]:
                        continue
                    nd = dist[p] + wlen[p, e]
                    if nd < dist[q]:
                        if dist[q] == np.inf:
                            touched[nt] = q
                            nt += 1
                        dist[q] = nd
                        r = max(int(nd / unit), b) & 3
                        bk[r, cnt[r]] = q
                        cnt[r] += 1
                        left += 1
        while k < pm.shape[0] and pm[k] == m:
            i = pi[k]
            e = math.hypot(G[m, 0] - S[i, 0], G[m, 1] - S[i, 1])
            b = sblk[i]
            c = np.inf
            if b >= 0 and g >= 0:
                c = e if b == g else max(e, dist[b] + math.hypot(S[i, 0] - rep[b, 0],
                                                                 S[i, 1] - rep[b, 1]))
            out[k] = c if c < bound else np.inf
            k += 1
    return out
