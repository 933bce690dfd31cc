"""Independent checker for multi-robot plans (test oracle).

Shares no collision code with the planner: obstacles are rebuilt here from the scene's
dict form with Shapely (circles kept as centre + radius so that their distances are
exact), robot-robot distances between stored rows are computed in closed form with numpy.

Rules checked (see ``lamp.mrmp.gspi`` for why the tolerances exist):
- shapes: paths (N, T, 2), goal_of (N,); rows finite;
- step: consecutive rows of each robot at most ``max_spacing`` apart;
- starts: ``paths[:, 0] == starts``;
- on success: each goal held by exactly one robot (``goal_of``), that robot ends on it;
- obstacles: along every straight piece between rows, the clearance of robot i (distance
  from its centre to obstacles and the workspace border) is at least
  ``min(r + margin, clearance(start_i), min over goals of clearance(goal))`` (any robot
  may visit any goal, so the goal tolerance applies to every robot);
- robots: between rows t and t+1 (linear motion of both), the distance of robots i, j is
  at least ``min(2r, |start_i - start_j|, min distance between two goals)``.
  With goals and starts >= r from obstacles and >= 2r apart this is the plain rule
  clearance >= r + margin, robot distance >= 2r.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import shapely

TOL = 1e-7


def _rect_corners(cx: float, cy: float, sx: float, sy: float, a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    loc = np.array([[-sx, -sy], [sx, -sy], [sx, sy], [-sx, sy]]) * 0.5
    return np.stack([cx + c * loc[:, 0] - s * loc[:, 1], cy + s * loc[:, 0] + c * loc[:, 1]], 1)


def obstacle_parts(
    scene_dict: dict[str, Any],
    object_poses: np.ndarray | None = None,
    extra_obstacles: Sequence[dict[str, Any]] = (),
) -> tuple[np.ndarray, list[shapely.Geometry]]:
    """(circles (C, 3), polygons) in the world from a scene dict, objects at poses."""
    circles: list[tuple[float, float, float]] = []
    polys: list[shapely.Geometry] = []
    obs = list(scene_dict.get("obstacles") or []) + list(extra_obstacles)
    for o in obs:
        if o["type"] == "circle":
            circles.append((o["center"][0], o["center"][1], o["radius"]))
        elif o["type"] == "rectangle":
            polys.append(shapely.Polygon(_rect_corners(*o["center"], *o["size"], o.get("angle", 0.0))))
        else:
            polys.append(shapely.Polygon(o["points"]))
    for k, o in enumerate(scene_dict["objects"]):
        x, y, a = (o["start"] if object_poses is None else object_poses[k])
        if o["type"] == "circle":
            circles.append((x, y, o["radius"]))
        elif o["type"] == "rectangle":
            polys.append(shapely.Polygon(_rect_corners(x, y, *o["size"], a)))
        else:
            p = np.asarray(o["points"], float)
            c, s = np.cos(a), np.sin(a)
            polys.append(shapely.Polygon(np.stack([x + c * p[:, 0] - s * p[:, 1],
                                                   y + s * p[:, 0] + c * p[:, 1]], 1)))
    return np.array(circles, float).reshape(-1, 3), polys


def point_clearance(points: np.ndarray, circles: np.ndarray, polys: list, W: float, H: float) -> np.ndarray:
    """Exact signed-ish clearance of points (negative for polygons is clipped to 0 -> use
    ``shapely.contains``)."""
    p = np.asarray(points, float).reshape(-1, 2)
    out = np.minimum.reduce([p[:, 0], W - p[:, 0], p[:, 1], H - p[:, 1]])
    if len(circles):
        d = np.hypot(p[:, None, 0] - circles[None, :, 0], p[:, None, 1] - circles[None, :, 1])
        out = np.minimum(out, (d - circles[None, :, 2]).min(axis=1))
    if polys:
        pts = shapely.points(p)
        for g in polys:
            d = shapely.distance(pts, g)
            d = np.where(shapely.contains(g, pts), -1.0, d)
            out = np.minimum(out, d)
    return out


def segment_clearance(a: np.ndarray, b: np.ndarray, circles: np.ndarray, polys: list,
                      W: float, H: float) -> np.ndarray:
    """Exact clearance of straight segments a-b ((S, 2) each), 0 or below when touching."""
    a = np.asarray(a, float).reshape(-1, 2)
    b = np.asarray(b, float).reshape(-1, 2)
    out = np.minimum.reduce([a[:, 0], W - a[:, 0], a[:, 1], H - a[:, 1],
                             b[:, 0], W - b[:, 0], b[:, 1], H - b[:, 1]])
    if len(circles):
        # point-segment distance of each circle centre, closed form
        ab = b - a
        L2 = (ab ** 2).sum(1)
        for cx, cy, rad in circles:
            ap = np.stack([cx - a[:, 0], cy - a[:, 1]], 1)
            t = np.where(L2 > 0, (ap * ab).sum(1) / np.where(L2 > 0, L2, 1), 0.0).clip(0, 1)
            q = a + t[:, None] * ab
            out = np.minimum(out, np.hypot(q[:, 0] - cx, q[:, 1] - cy) - rad)
    if polys:
        same = np.all(a == b, axis=1)
        geoms = np.empty(len(a), dtype=object)
        geoms[same] = shapely.points(a[same])
        if (~same).any():
            geoms[~same] = shapely.linestrings(np.stack([a[~same], b[~same]], 1))
        tree = shapely.STRtree(polys)
        cap = float(out.max()) + 1.0
        gi, pj = tree.query(geoms, predicate="dwithin", distance=cap)
        if len(gi):
            d = shapely.distance(geoms[gi], np.asarray(polys, dtype=object)[pj])
            np.minimum.at(out, gi, d)
    return out


def min_pair_distance(P0: np.ndarray, P1: np.ndarray) -> np.ndarray:
    """(N, N) minimum distance between robots moving linearly from rows P0 to P1."""
    D0 = P0[:, None, :] - P0[None, :, :]
    D1 = P1[:, None, :] - P1[None, :, :]
    E = D1 - D0
    e2 = (E ** 2).sum(-1)
    t = np.where(e2 > 0, -(D0 * E).sum(-1) / np.where(e2 > 0, e2, 1.0), 0.0).clip(0, 1)
    Mn = D0 + t[..., None] * E
    return np.hypot(Mn[..., 0], Mn[..., 1])


def check_plan(
    scene: Any,
    starts: np.ndarray,
    goals: np.ndarray,
    plan: Any,
    object_poses: np.ndarray | None = None,
    extra_obstacles: Sequence[dict[str, Any]] = (),
    margin: float = 0.0,
    max_spacing: float = 0.02,
    require_success: bool | None = None,
) -> None:
    """Raise AssertionError naming the first violated rule (see module doc)."""
    d = scene.to_dict()
    W, H = d["workspace"]
    r = d["robots"]["radius"]
    S = np.asarray(starts, float).reshape(-1, 2)
    G = np.asarray(goals, float).reshape(-1, 2)
    N, M = len(S), len(G)
    P = np.asarray(plan.paths, float)
    goal_of = np.asarray(plan.goal_of)
    assert P.ndim == 3 and P.shape[0] == N and P.shape[2] == 2 and P.shape[1] >= 1, P.shape
    assert goal_of.shape == (N,), goal_of.shape
    assert np.all(np.isfinite(P)), "non-finite path values"
    if require_success is not None:
        assert bool(plan.success) == require_success, (plan.success, plan.reason)
    assert isinstance(plan.reason, str)
    if not plan.success:
        assert plan.reason, "a failure must give a reason"
    assert np.allclose(P[:, 0], S, atol=1e-9, rtol=0), "paths do not begin at the starts"
    steps = np.hypot(*(P[:, 1:] - P[:, :-1]).transpose(2, 0, 1))
    if steps.size:
        assert steps.max() <= max_spacing + 1e-9, f"step {steps.max():.5f} > {max_spacing}"
    if plan.success:
        assert np.all((goal_of >= -1) & (goal_of < M)), goal_of
        held = goal_of[goal_of >= 0]
        assert len(held) == M and len(np.unique(held)) == M, f"goal_of {goal_of} for M={M}"
        ends = P[goal_of >= 0, -1]
        err = np.hypot(*(ends - G[held]).T)
        assert err.max(initial=0.0) <= 1e-6, f"goal missed by {err.max(initial=0.0):.2e} m"
        # T minimal in the sense of no trailing repeats
        if P.shape[1] > 1:
            assert np.any(P[:, -1] != P[:, -2]), "trailing repeated rows"
    circles, polys = obstacle_parts(d, object_poses, extra_obstacles)
    thr = r + margin
    # any robot may visit any goal (goals swap), so the goal tolerance applies to all
    c_s = point_clearance(S, circles, polys, W, H)
    c_g = float(point_clearance(G, circles, polys, W, H).min()) if M else np.inf
    req = np.minimum(thr, np.minimum(c_s, c_g))
    if P.shape[1] > 1:
        a = P[:, :-1].reshape(-1, 2)
        b = P[:, 1:].reshape(-1, 2)
        clr = segment_clearance(a, b, circles, polys, W, H).reshape(N, -1)
        worst = clr - req[:, None]
        i, t = np.unravel_index(np.argmin(worst), worst.shape)
        assert worst[i, t] >= -TOL, (
            f"robot {i} between rows {t} and {t + 1} has clearance {clr[i, t]:.5f} "
            f"< required {req[i]:.5f} ({P[i, t]} -> {P[i, t + 1]})")
    else:
        clr = point_clearance(P[:, 0], circles, polys, W, H)
        assert np.all(clr >= req - TOL)
    # robot-robot
    dS = np.hypot(*(S[:, None] - S[None, :]).transpose(2, 0, 1))
    reqp = np.minimum(2 * r, dS)
    if M > 1:
        dG = np.hypot(*(G[:, None] - G[None, :]).transpose(2, 0, 1))
        np.fill_diagonal(dG, np.inf)
        reqp = np.minimum(reqp, dG.min())
    np.fill_diagonal(reqp, -np.inf)
    T = P.shape[1]
    if T == 1:
        dmin = np.hypot(*(P[:, None, 0] - P[None, :, 0]).transpose(2, 0, 1))
        np.fill_diagonal(dmin, np.inf)
        assert np.all(dmin >= reqp - TOL)
    for t in range(T - 1):
        dmin = min_pair_distance(P[:, t], P[:, t + 1])
        np.fill_diagonal(dmin, np.inf)
        bad = dmin < reqp - TOL
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise AssertionError(
                f"robots {i} and {j} come {dmin[i, j]:.5f} m apart between rows {t} and "
                f"{t + 1} (required {reqp[i, j]:.5f})")
