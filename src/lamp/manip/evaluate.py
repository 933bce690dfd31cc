"""Open-space evaluation of proposers in the simulator (a benchmark, not a test).

For held-out cases (objects and motions drawn with a seed the training data never used;
shape sizes and motions are continuous, so no case repeats a training sample), each
proposer is asked for ``k`` proposals per case; every proposal is executed in MuJoCo in an
empty workspace: the robots start ``APPROACH`` metres out along the contact normals, drive
in to the contacts (the approach), then follow the pushes. Reported per proposer and
budget: the share of pushes within 0.05 m / 0.1 rad and within 0.1 m / 0.2 rad of the
request, mean and median translation and rotation errors (also restricted to pushes of at
most 0.2 m), contact validity (no robot penetrating the object, robots at least 2r apart)
and the proposer's median ``propose`` time; once over all k proposals and once over the
first proposal of each case (the one a planner tries first).

Three case sets: circles and rectangles as in training, random convex polygons
(``polygons``), and large objects (``large``: bars 1.0-1.5 m long, L and T shapes
0.8-1.2 m across, beyond the model's 1 m window, which the learned model proposes for
scaled down, ``lamp.manip.scaling``).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from lamp.geometry.se2 import relative, transform_points, wrap_angle
from lamp.manip.contacts import closest_boundary, contacts_valid
from lamp.manip.dataset import WORKSPACE, densify, object_scene, sample_motion, sample_shape
from lamp.manip.proposals import Proposal, ProposalModel
from lamp.scene.model import Polygon, Rectangle, Shape

APPROACH = 0.1
"""How far out along the contact normal the robots start before the approach (m)."""
TOLERANCES = ((0.05, 0.1), (0.1, 0.2))
BAR_LENGTHS = (1.0, 1.5)
"""Length range of the large-object set's bars (m); widths are ``LARGE_THICKNESS``."""
LT_SPANS = (0.8, 1.2)
"""Range of the large-object set's L and T shapes' longer side (m)."""
LARGE_THICKNESS = (0.1, 0.25)
"""Range of the bars' widths and of the L and T shapes' arm widths (m)."""


def execute_proposal(shape: Shape, proposal: Proposal, motion: np.ndarray) -> dict[str, float]:
    """Approach + push one proposal in open space; errors w.r.t. the requested motion."""
    from lamp.sim import Simulator

    c0 = np.array([0.5 * WORKSPACE, 0.5 * WORKSPACE, 0.0])
    contacts = proposal.contacts
    _, out_dir = closest_boundary(shape, contacts)
    starts = contacts + APPROACH * out_dir
    approach = starts[:, None, :] + np.linspace(0.0, 1.0, 6)[None, :, None] * (
        contacts - starts)[:, None, :]
    path = np.concatenate([approach, proposal.pushes[:, 1:]], axis=1)
    sim = Simulator(object_scene(shape, len(contacts), transform_points(c0, starts)))
    out = sim.execute(densify(transform_points(c0, path)))
    achieved = relative(c0, out.object_poses[0])
    return {
        "err_t": float(np.hypot(*(achieved[:2] - motion[:2]))),
        "err_r": abs(float(wrap_angle(achieved[2] - motion[2]))),
        "valid": float(contacts_valid(shape, contacts)),
        "n_robots": float(len(contacts)),
    }


def random_polygon(rng: np.random.Generator) -> Polygon:
    """A convex polygon with 3-6 vertices within 0.15-0.30 m of its origin (out of the
    training distribution, which only has circles and rectangles)."""
    n = int(rng.integers(3, 7))
    ang = np.sort(rng.uniform(0.0, 2 * np.pi, n))
    ang = ang[0] + np.linspace(0.0, 2 * np.pi, n, endpoint=False) + rng.uniform(-0.25, 0.25, n)
    r = rng.uniform(0.15, 0.30)
    pts = np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)
    return Polygon(tuple((float(x), float(y)) for x, y in pts))


def l_shape(width: float, height: float, thickness: float) -> Polygon:
    """An L: a ``width`` x ``thickness`` foot and a ``thickness`` x ``height`` upright
    sharing the bottom-left corner; the origin at the centre of its bounding box."""
    w, h, t = float(width), float(height), float(thickness)
    pts = [(0.0, 0.0), (w, 0.0), (w, t), (t, t), (t, h), (0.0, h)]
    return Polygon(tuple((x - 0.5 * w, y - 0.5 * h) for x, y in pts))


def t_shape(width: float, height: float, thickness: float) -> Polygon:
    """A T: a ``width`` x ``thickness`` top bar on a centred stem, ``height`` tall in all;
    the origin at the centre of its bounding box."""
    w, h, t = float(width), float(height), float(thickness)
    pts = [(-0.5 * t, 0.0), (0.5 * t, 0.0), (0.5 * t, h - t), (0.5 * w, h - t), (0.5 * w, h),
           (-0.5 * w, h), (-0.5 * w, h - t), (-0.5 * t, h - t)]
    return Polygon(tuple((x, y - 0.5 * h) for x, y in pts))


def large_shape(rng: np.random.Generator) -> Shape:
    """A large object: half the time a bar (length in ``BAR_LENGTHS``, width in
    ``LARGE_THICKNESS``), else an L or a T whose longer side is in ``LT_SPANS`` (the other
    60-100% of it, arms ``LARGE_THICKNESS`` wide)."""
    u = rng.random()
    if u < 0.5:
        return Rectangle((float(rng.uniform(*BAR_LENGTHS)), float(rng.uniform(*LARGE_THICKNESS))))
    w = float(rng.uniform(*LT_SPANS))
    h = w * float(rng.uniform(0.6, 1.0))
    t = float(rng.uniform(*LARGE_THICKNESS))
    return l_shape(w, h, t) if u < 0.75 else t_shape(w, h, t)


def held_out_cases(
    n: int, seed: int, polygons: bool = False, large: bool = False
) -> list[tuple[Shape, np.ndarray]]:
    """``n`` (shape, motion) cases drawn like the training data but from a separate seed
    (``polygons``: random convex polygons instead of circles and rectangles; ``large``:
    ``large_shape`` objects)."""
    rng = np.random.default_rng([seed, 7919])
    make = large_shape if large else random_polygon if polygons else sample_shape
    return [(make(rng), sample_motion(rng)) for _ in range(n)]


def _stats(rows: list[dict[str, float]], motions: list[np.ndarray]) -> dict[str, float]:
    et = np.array([r["err_t"] for r in rows])
    er = np.array([r["err_r"] for r in rows])
    mt = np.array([np.hypot(m[0], m[1]) for m in motions])
    out: dict[str, float] = {"pushes": len(rows)}
    for tt, tr in TOLERANCES:
        out[f"within_{tt}m_{tr}rad"] = float(np.mean((et <= tt) & (er <= tr)))
    out.update({
        "mean_err_t": float(et.mean()), "median_err_t": float(np.median(et)),
        "mean_err_r": float(er.mean()), "median_err_r": float(np.median(er)),
        "median_err_t_upto_0.2m": float(np.median(et[mt <= 0.2])) if np.any(mt <= 0.2)
        else float("nan"),
        "contact_validity": float(np.mean([r["valid"] for r in rows])),
        "mean_robots": float(np.mean([r["n_robots"] for r in rows])),
    })
    return out


def evaluate(
    proposers: dict[str, ProposalModel],
    cases_per_budget: int = 60,
    k: int = 4,
    seed: int = 12345,
    budgets: tuple[int, ...] = (1, 2, 3),
    progress: bool = True,
    polygons: bool = False,
    large: bool = False,
) -> dict[str, Any]:
    """Run every proposer on the same held-out cases; returns a JSON-ready report.

    ``polygons``: evaluate on random convex polygons (out of distribution) instead;
    ``large``: on large objects (``large_shape``).
    """
    from tqdm import tqdm

    report: dict[str, Any] = {"seed": seed, "cases_per_budget": cases_per_budget, "k": k,
                              "approach_m": APPROACH, "polygons": polygons, "large": large,
                              "results": {}}
    total = len(proposers) * len(budgets) * cases_per_budget
    bar = tqdm(total=total, unit="case", disable=not progress)
    for name, prop in proposers.items():
        per_budget: dict[str, Any] = {}
        for b in budgets:
            cases = held_out_cases(cases_per_budget, seed + b, polygons, large)
            rows, motions, times, first = [], [], [], []
            for i, (shape, motion) in enumerate(cases):
                t0 = time.perf_counter()
                props = prop.propose(shape, motion, b, k=k, seed=seed * 1000 + i)
                times.append(time.perf_counter() - t0)
                for j, p in enumerate(props):
                    rows.append(execute_proposal(shape, p, motion))
                    motions.append(motion)
                    if j == 0:
                        first.append(rows[-1])
                bar.update(1)
            st = _stats(rows, motions)
            st["median_propose_ms"] = 1e3 * float(np.median(times))
            st["first"] = _stats(first, [c[1] for c in cases])
            per_budget[str(b)] = st
        report["results"][name] = per_budget
    bar.close()
    return report


def format_report(report: dict[str, Any]) -> str:
    """A plain-text table of ``evaluate``'s report."""
    cols = [("within_0.05m_0.1rad", "<=5cm/.1", "{:.0%}"), ("within_0.1m_0.2rad", "<=10cm/.2",
            "{:.0%}"), ("mean_err_t", "mean_t", "{:.3f}"), ("median_err_t", "med_t", "{:.3f}"),
            ("mean_err_r", "mean_r", "{:.3f}"), ("median_err_r", "med_r", "{:.3f}"),
            ("contact_validity", "valid", "{:.0%}"), ("mean_robots", "robots", "{:.2f}"),
            ("median_propose_ms", "ms", "{:.1f}")]
    kind = ("large objects (bars 1.0-1.5 m, L/T shapes 0.8-1.2 m)" if report.get("large")
            else "random convex polygons" if report.get("polygons")
            else "circles and rectangles")
    w = max(10, *(len(name) for name in report["results"]))
    lines = [f"held-out {kind}, cases per budget: {report['cases_per_budget']}, proposals per "
             f"case: {report['k']}, seed {report['seed']}",
             f"{'proposer':<{w}} {'b':>2} " + " ".join(f"{h:>9}" for _, h, _ in cols)]
    for name, per in report["results"].items():
        for b, st in per.items():
            lines.append(f"{name:<{w}} {b:>2} " + " ".join(
                f"{fmt.format(st[key]):>9}" for key, _, fmt in cols))
    lines.append("first proposal of each case only (the one a planner tries first):")
    for name, per in report["results"].items():
        for b, st in per.items():
            lines.append(f"{name:<{w}} {b:>2} " + " ".join(
                f"{fmt.format(st['first'].get(key, st[key])):>9}" for key, _, fmt in cols))
    return "\n".join(lines)
