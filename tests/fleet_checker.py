"""Independent checker for large multi-robot plans (hundreds of robots, test oracle).

The rules are those of ``mrmp_checker.check_plan`` (see there), checked at fleet scale and
sharing no code with the planner or with that checker:

- obstacles: each robot's whole path is one Shapely ``LineString`` (linear motion between
  rows is exactly what the plan promises); an STR tree of the obstacles (scene dict, the
  objects at their start poses) answers which obstacles lie closer than the required
  clearance to it (GEOS ``dwithin``); the border is checked on the rows' bounding box;
- robots: for every pair of consecutive rows, candidate pairs come from a k-d tree of the
  rows' midpoints (``scipy.spatial.cKDTree``: two robots can only come within ``2r`` in a
  step when their midpoints are within ``2r`` plus both half-step lengths), and each
  candidate's closest approach over the step is computed in closed form.

Required clearance of robot i: ``min(r + margin, clearance(start_i), min goal clearance)``
(exact point distances); required distance of robots i, j: ``min(2r, |start_i - start_j|,
min distance between two goals)``; ``TOL`` = 1e-7 m.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import shapely
from mrmp_checker import obstacle_parts
from scipy.spatial import cKDTree

TOL = 1e-7


class _Disk:
    """A circle kept exact: centre and radius (Shapely would approximate it)."""

    def __init__(self, x: float, y: float, r: float) -> None:
        self.x, self.y, self.r = x, y, r


def _clearance_of_points(p: np.ndarray, polys: list, tree: shapely.STRtree | None,
                         disks: list[_Disk], W: float, H: float) -> np.ndarray:
    out = np.minimum.reduce([p[:, 0], W - p[:, 0], p[:, 1], H - p[:, 1]])
    pts = shapely.points(p)
    if tree is not None:
        idx = tree.nearest(pts)
        d = shapely.distance(pts, np.asarray(polys, dtype=object)[idx])
        inside = shapely.contains(np.asarray(polys, dtype=object)[idx], pts)
        out = np.minimum(out, np.where(inside, -1.0, d))
    for c in disks:
        out = np.minimum(out, np.hypot(p[:, 0] - c.x, p[:, 1] - c.y) - c.r)
    return out


def check_fleet_plan(scene_dict: dict[str, Any], starts: np.ndarray, goals: np.ndarray,
                     plan: Any, radius: float, margin: float = 0.0,
                     max_spacing: float = 0.02) -> list[str]:
    """Violations of ``plan`` (an ``MRMPPlan``), empty when it is valid."""
    errs: list[str] = []
    P = np.asarray(plan.paths, dtype=float)
    S = np.asarray(starts, dtype=float)
    G = np.asarray(goals, dtype=float)
    N, T = P.shape[0], P.shape[1]
    W, H = (float(v) for v in scene_dict["workspace"])
    if P.ndim != 3 or P.shape[2] != 2 or len(S) != N or not np.all(np.isfinite(P)):
        return [f"paths have shape {P.shape} or non-finite rows"]
    if not np.allclose(P[:, 0], S, atol=1e-12, rtol=0):
        errs.append("paths do not start at the starts")
    step = np.hypot(*np.diff(P, axis=1).transpose(2, 0, 1)) if T > 1 else np.zeros((N, 0))
    if step.size and step.max() > max_spacing + 1e-9:
        errs.append(f"a step of {step.max():.4f} m exceeds max_spacing {max_spacing}")
    goal_of = np.asarray(plan.goal_of)
    if plan.success:
        held = goal_of[goal_of >= 0]
        if sorted(held.tolist()) != list(range(len(G))):
            errs.append("not every goal is held by exactly one robot")
        i = np.nonzero(goal_of >= 0)[0]
        if np.any(np.hypot(*(P[i, -1] - G[goal_of[i]]).T) > 1e-9):
            errs.append("a robot does not end on its goal")
    # obstacles and border
    circles, polys = obstacle_parts(scene_dict)
    disks = [_Disk(*c) for c in circles]
    tree = shapely.STRtree(polys) if polys else None
    c_start = _clearance_of_points(S, polys, tree, disks, W, H)
    c_goal = (_clearance_of_points(G, polys, tree, disks, W, H) if len(G)
              else np.array([np.inf]))
    need = np.minimum(np.minimum(radius + margin, c_start), c_goal.min()) - TOL
    lo = P.min(axis=1)
    hi = P.max(axis=1)
    border = np.minimum.reduce([lo[:, 0], W - hi[:, 0], lo[:, 1], H - hi[:, 1]])
    for i in np.nonzero(border < need)[0][:3]:
        errs.append(f"robot {i} comes within {border[i]:.4f} m of the border")
    lines = shapely.linestrings(P) if T > 1 else shapely.points(P[:, 0])
    if tree is not None:
        hit = tree.query(lines, predicate="dwithin", distance=need)
        if hit.shape[1]:
            i, k = (int(v) for v in hit[:, 0])
            d = float(shapely.distance(lines[i], polys[k]))
            errs.append(f"robot {i} comes within {d:.4f} m of obstacle polygon {k} "
                        f"(needs {need[i]:.4f})")
    for c in disks:
        d = shapely.distance(lines, shapely.Point(c.x, c.y)) - c.r
        bad = np.nonzero(d < need)[0]
        if len(bad):
            errs.append(f"robot {bad[0]} comes within {d[bad[0]]:.4f} m of a disk obstacle")
            break
    # robot pairs, step by step
    dG = cKDTree(G).query(G, k=2)[0][:, 1].min() if len(G) > 1 else np.inf
    two_r = 2.0 * radius
    for t in range(T - 1):
        A = P[:, t]
        B = P[:, t + 1]
        half = 0.5 * np.hypot(*(B - A).T).max()
        pairs = cKDTree(0.5 * (A + B)).query_pairs(two_r + 2 * half + 1e-9, output_type="ndarray")
        if len(pairs) == 0:
            continue
        i, j = pairs[:, 0], pairs[:, 1]
        d0 = A[i] - A[j]
        d1 = B[i] - B[j]
        v = d1 - d0
        vv = np.einsum("ij,ij->i", v, v)
        s = np.where(vv > 0, np.clip(-np.einsum("ij,ij->i", d0, v) / np.where(vv > 0, vv, 1),
                                     0, 1), 0.0)
        dmin = np.hypot(*(d0 + s[:, None] * v).T)
        dS = np.hypot(*(S[i] - S[j]).T)
        need_r = np.minimum(np.minimum(two_r, dS), dG) - TOL
        bad = np.nonzero(dmin < need_r)[0]
        if len(bad):
            k = bad[0]
            errs.append(f"robots {i[k]} and {j[k]} come {dmin[k]:.4f} m apart between rows "
                        f"{t} and {t + 1} (needs {need_r[k]:.4f})")
            break
    return errs
