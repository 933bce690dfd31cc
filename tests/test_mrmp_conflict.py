"""Gspi's pair rule (``lamp.mrmp.gspi_kernels.conflict``) against a plain reference, and
the repair's checks built on it: two robots that end at one point never pass, even
when both end on goal vertices (the exemption is for two goals closer than 2r)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp.gspi_kernels import conflict
from lamp.mrmp.repair_hash import build_hash, clear_of, gather, move_ok

TWO_R = 0.1


def _closest(a, b, c, d, both: bool) -> tuple[float, float]:
    """The closest approach of the relative motion by dense sampling (4,001 instants, the
    exact ends included) and the rule's threshold: min(2r, start distance[, end distance
    when both end on goals at two points])."""
    s = np.linspace(0.0, 1.0, 4001)[:, None]
    rel = (np.asarray(a) - np.asarray(c)) * (1 - s) + (np.asarray(b) - np.asarray(d)) * s
    dist = np.hypot(rel[:, 0], rel[:, 1])
    thr = min(TWO_R, dist[0])
    if both and dist[-1] > 0.0:
        thr = min(thr, dist[-1])
    return float(dist.min()), thr


def _reference(a, b, c, d, both: bool) -> bool:
    """The rule by sampling: the distance may not fall below the threshold."""
    closest, thr = _closest(a, b, c, d, both)
    return closest < thr - 1e-6


_pt = st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3))


@settings(max_examples=300, deadline=None)
@given(a=_pt, b=_pt, c=_pt, d=_pt, both=st.booleans(), same_end=st.booleans())
def test_conflict_matches_reference(a, b, c, d, both, same_end) -> None:
    """Random pairs of motions, half of them ending at one point: ``conflict`` gives the
    reference's answer wherever the closest approach is not within sampling error of the
    threshold; motions ending at one point always conflict."""
    if same_end:
        d = b
    if math.dist(a, c) < 1e-6:
        return  # two robots never start at one point
    got = conflict(*a, *b, *c, *d, TWO_R, both)
    if same_end:
        assert got
    # away from the threshold (sampling resolves the closest approach to ~1e-4 m)
    closest, thr = _closest(a, b, c, d, both)
    if abs(closest - thr) > 1e-3:
        assert got == _reference(a, b, c, d, both)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(2, 12))
def test_repair_checks_refuse_two_robots_onto_one_goal(seed, n) -> None:
    """A robot moving onto the goal vertex another robot moves onto in the same step is
    refused by ``move_ok`` and by ``clear_of`` over the gathered motions, though both
    end on goal vertices (before, the goals' exemption let them meet there)."""
    rng = np.random.default_rng(seed)
    V = 4 * n  # vertices; the last n are goal vertices (gv0 = V - n)
    gv0 = V - n
    coords = rng.random((V, 2)) * 0.6
    VX = rng.integers(0, gv0, size=(2, n))
    g = gv0 + int(rng.integers(n))
    k = int(rng.integers(1, n))
    VX[1, k] = g  # robot k moves onto goal vertex g in step 0
    a = int(rng.integers(gv0))
    if math.dist(coords[a], coords[VX[0, k]]) < 1e-9:
        return
    cs = TWO_R + 2 * 0.6 + 1e-6
    hh, x0, y0, ny = build_hash(VX, coords, cs, True)
    skip = np.zeros(n, np.bool_)
    none = np.zeros(0, np.bool_)
    assert not move_ok(0, 0, a, g, VX, coords, gv0, hh, x0, y0, cs, ny, TWO_R, skip, none)
    buf = np.empty((n, 5))
    m = gather(0, 0, a, VX, coords, gv0, hh, x0, y0, cs, ny, 10.0, skip, buf)
    assert not clear_of(coords[a, 0], coords[a, 1], coords[g, 0], coords[g, 1], True, buf,
                        m, TWO_R)
