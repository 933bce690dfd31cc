"""A coarse graph of a lattice for the fleet assignment: blocks of lattice nodes.

The lattice's index grid is cut into square blocks of :data:`BLOCK` x :data:`BLOCK`
indices (15 cm on the 3 cm lattice); a block with free nodes is a coarse node at the
centroid of its nodes, and two 8-adjacent blocks are joined when some lattice edge joins
their nodes, at the distance between their centroids. A robot-goal pair's *coarse
distance* is the length of the way start -> its block's centroid -> (blocks) -> the goal's
block's centroid -> goal, and never less than their straight line (the straight line when
both lie in one block).

What it is for: an assignment of a fleet whose longest way and summed ways are those of the
coarse distances costs searches over a twenty-fifth of the nodes the exact lattice
distances need (:mod:`lamp.mrmp.assignment`). What it guarantees: nothing about the lattice
distances themselves (a block whose nodes are joined only through other blocks looks
joined; a coarse distance can be shorter or longer than the lattice's), so the caller
checks every chosen pair on the lattice.
"""

from __future__ import annotations

import heapq
import math
from typing import Any, NamedTuple

import numba as nb
import numpy as np

__all__ = ["BLOCK", "CoarseGraph", "coarse_below", "get_coarse"]

#: Side of a block, in lattice steps.
BLOCK = 5


class CoarseGraph(NamedTuple):
    """``block[v]``: the block of lattice node v; ``rep (B, 2)``: each block's centroid;
    ``nbr (B, 8)``: adjacent blocks (-1 none), ``wlen (B, 8)``: their distances."""

    block: np.ndarray
    rep: np.ndarray
    nbr: np.ndarray
    wlen: np.ndarray


@nb.njit(cache=True)
def _build(va: np.ndarray, vb: np.ndarray, coords: np.ndarray, lnbr: np.ndarray, nat: int,
           nbt: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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
            q = nbr[p, s]
            if q >= 0:
                wlen[p, s] = math.hypot(rep[p, 0] - rep[q, 0], rep[p, 1] - rep[q, 1])
    return block, rep, nbr, wlen


def get_coarse(lat: Any) -> CoarseGraph:
    """The coarse graph of lattice ``lat`` (built once, kept on the lattice)."""
    cg = getattr(lat, "_coarse", None)
    if cg is None:
        nbt, nat = lat.ids.shape
        cg = CoarseGraph(*_build(lat.va, lat.vb, lat.coords, lat.nbr, nat, nbt, BLOCK))
        lat._coarse = cg
    return cg


@nb.njit(cache=True)
def coarse_below(pm: np.ndarray, pi: np.ndarray, bound: float, sblk: np.ndarray,
                 gblk: np.ndarray, S: np.ndarray, G: np.ndarray, rep: np.ndarray,
                 nbr: np.ndarray, wlen: np.ndarray) -> np.ndarray:
    """For pairs (goal ``pm[k]``, robot ``pi[k]``), grouped by goal: the coarse distance
    when it is below ``bound``, else inf (``sblk``/``gblk``: the blocks of the starts and
    goals, -1 none; one Dijkstra over the blocks per goal, stopped at ``bound``)."""
    B = rep.shape[0]
    dist = np.full(B, np.inf)
    touched = np.empty(B, np.int64)
    nt = 0
    out = np.full(pm.shape[0], np.inf)
    k = 0
    heap = [(0.0, 0)]
    while k < pm.shape[0]:
        m = pm[k]
        for t in range(nt):
            dist[touched[t]] = np.inf
        nt = 0
        g = gblk[m]
        if g >= 0:
            heap.clear()
            d0 = math.hypot(G[m, 0] - rep[g, 0], G[m, 1] - rep[g, 1])
            dist[g] = d0
            touched[nt] = g
            nt += 1
            heapq.heappush(heap, (d0, g))
            while len(heap) > 0:
                d, p = heapq.heappop(heap)
                if d > dist[p]:
                    continue
                if d >= bound:
                    break
                for s in range(8):
                    q = nbr[p, s]
                    if q < 0:
                        continue
                    nd = d + wlen[p, s]
                    if nd < dist[q]:
                        if dist[q] == np.inf:
                            touched[nt] = q
                            nt += 1
                        dist[q] = nd
                        heapq.heappush(heap, (nd, q))
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
