"""Gspi's special vertices: each start and goal linked to the lattice by checked straight
moves (:func:`link_special_vertices`), and the search graph they make."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.distance_field import FEW, Lattice, clear_segments
from lamp.mrmp.gspi_kernels import Graph
from lamp.mrmp.near_pairs import near_pairs

__all__ = ["Links", "link_special_vertices"]


@dataclass(frozen=True)
class Links:
    """The special vertices of one attempt, linked to the lattice and to each other."""

    graph: Graph
    #: (N, M): start i reaches goal m by a direct checked straight move.
    direct: np.ndarray
    #: Per goal m: (lattice nodes linked to it, link lengths).
    goal_links: list[tuple[np.ndarray, np.ndarray]]
    #: Candidate slots per robot and step: 8 neighbours, wait and the extra edges.
    max_candidates: int
    #: The longest edge of the graph (a lattice diagonal or a link).
    max_move: float


def link_special_vertices(space: RobotSpace, lat: Lattice, S: np.ndarray, G: np.ndarray,
                           c_start: np.ndarray, c_goal: np.ndarray, R: float,
                           stats: dict[str, Any]) -> Links | np.ndarray:
    """Vertices V+i (start i) and V+N+m (goal m), linked by checked straight moves to the
    lattice nodes within ``R`` (goals both ways), and start -> goal directly when close;
    or, when some goal has no link at all (the starts then left unlinked), the (M,) mask
    of such goals. With more than ``FEW`` goals, when some goal has no lattice node
    within ``R`` at all and no start links to it directly, the mask of those goals only,
    found before any link is checked (on a map of 0.15 m cells the 5 cm lattice has no
    node within reach of the centres of some one-cell corridors, about 2.5 % of the
    free cells of ``random-64-64-20``, so a fleet of hundreds fails on it that way)."""
    N, M = len(S), len(G)
    V = lat.V
    gv0 = V + N
    thr = space.threshold
    if M > FEW:  # hundreds of goals: one cell-centre goal out of reach is likely
        lone = ~lat.any_node_near(G, R)
        if lone.any() and _direct_only(space, S, G, c_start, c_goal, R, lone).any():
            return lone  # this lattice cannot be used: nothing else linked
    coords = np.concatenate([lat.coords, S, G]).astype(np.float64)
    g_links = lat.links(G, R, np.minimum(thr, c_goal), c_goal)
    stats["goal_links"] = [len(x[0]) for x in g_links]
    lone = np.array([len(x[0]) == 0 for x in g_links], dtype=bool)
    if lone.any() and _direct_only(space, S, G, c_start, c_goal, R, lone).any():
        return lone  # no need to link the starts: this lattice cannot be used
    s_links = lat.links(S, R, np.minimum(thr, c_start), c_start)
    stats["start_links"] = [len(x[0]) for x in s_links]
    ns = np.array([len(x[0]) for x in s_links], dtype=np.int64)
    ng = np.array([len(x[0]) for x in g_links], dtype=np.int64)
    s_nodes = np.concatenate([np.zeros(0, np.int64)] + [x[0] for x in s_links])
    g_nodes = np.concatenate([np.zeros(0, np.int64)] + [x[0] for x in g_links])
    g_ids = np.repeat(gv0 + np.arange(M), ng)
    # (the order among the edges of one vertex is that of its links; a stable sort by
    # source below keeps it)
    src: list[np.ndarray] = [np.repeat(V + np.arange(N), ns), g_ids, g_nodes]
    dst: list[np.ndarray] = [s_nodes, g_nodes, g_ids]
    # direct start -> goal moves for robots already close to a goal
    si, gi, _ = near_pairs(S, G, R)
    direct = np.zeros((N, M), dtype=bool)
    if len(si):
        ok = clear_segments(space.geometry, space.workspace, S[si], G[gi],
                            np.minimum(thr, np.minimum(c_start[si], c_goal[gi])))
        si, gi = si[ok], gi[ok]
        direct[si, gi] = True
        src.append(V + si)
        dst.append(gv0 + gi)
    src_a = np.concatenate(src).astype(np.int64)
    dst_a = np.concatenate(dst).astype(np.int64)
    order = np.argsort(src_a, kind="stable")
    src_a, dst_a = src_a[order], dst_a[order]
    xptr = np.concatenate([[0], np.cumsum(np.bincount(src_a, minlength=V + N + M))])
    graph = Graph(coords, lat.nbr, lat.dlen, xptr, np.ascontiguousarray(dst_a))
    longest = float(np.hypot(*(coords[src_a] - coords[dst_a]).T).max()) if len(src_a) else 0.0
    return Links(graph, direct, g_links, 9 + int(np.max(np.diff(xptr))),
                  max(longest, float(lat.dlen.max())))


def _direct_only(space: RobotSpace, S: np.ndarray, G: np.ndarray, c_start: np.ndarray,
                 c_goal: np.ndarray, R: float, lone: np.ndarray) -> np.ndarray:
    """``lone`` (goals without lattice links) with the goals that some start within
    ``R`` links to by a checked straight move cleared, in place; returns it."""
    thr = space.threshold
    ms = np.flatnonzero(lone)
    near = [np.flatnonzero(np.hypot(*(S - G[m]).T) <= R) for m in ms.tolist()]
    si = np.concatenate([np.zeros(0, np.int64)] + near)
    if len(si) == 0:  # no start within reach of any: no segment to check
        return lone
    gi = np.repeat(ms, [len(n) for n in near])
    ok = clear_segments(space.geometry, space.workspace, S[si], G[gi],
                        np.minimum(thr, np.minimum(c_start[si], c_goal[gi])))
    lone[gi[ok]] = False
    return lone
