"""``Collide`` (paper Alg. 1 line 21): which of the manipulation model's proposals can push
the object from a given pose.

A proposal lives in the object frame, and rigid motions preserve distances and linear
interpolation, so two of ``Collide``'s three tests do not depend on where the object is: a
contact inside the object and two pushing robots closer than 2r. :func:`prepare_candidates`
does them once per proposal set (:class:`PushCandidates`); :func:`usable_mask` does the
third, push paths in the robots' free space, per pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lamp.contract.trajectory import MAX_STEP, densify
from lamp.geometry import se2
from lamp.geometry.shapes import signed_distance
from lamp.planners.robot_routing import RobotValidity
from lamp.scene.model import Shape

__all__ = ["PushCandidates", "pairwise_min_distance", "prepare_candidates", "usable_mask"]


@dataclass(frozen=True)
class PushCandidates:
    """The K proposals for one (motion, budget, attempt), prepared for fast ``Collide`` checks.

    The pose-independent tests are done once (``intrinsic_ok``). The pose-dependent one is
    done per pose on ``dense_points``: every push path densified to ``MAX_STEP / 2`` in the
    object frame and stacked, proposal ``i`` owning rows ``starts[i]:starts[i + 1]``.
    """

    pushes_local: list[np.ndarray]  # K arrays (B, H, 2), object frame
    intrinsic_ok: np.ndarray  # (K,) bool
    dense_points: np.ndarray  # (P, 2) stacked densified push points, object frame
    starts: np.ndarray  # (K + 1,) row offsets into dense_points


def pairwise_min_distance(paths: np.ndarray) -> float:
    """Smallest distance between any two of the (B, T, 2) synchronised paths."""
    b = paths.shape[0]
    if b < 2:
        return np.inf
    i, j = np.triu_indices(b, 1)
    d = paths[i] - paths[j]
    return float(np.sqrt(np.min(d[..., 0] ** 2 + d[..., 1] ** 2)))


def prepare_candidates(props: list, shape: Shape, robot_radius: float,
                       contact_tolerance: float) -> PushCandidates:
    """The model proposals ``props`` (each with ``pushes``: (B, H, 2), object frame) with
    ``Collide``'s pose-independent tests done: every contact at least ``robot_radius -
    contact_tolerance`` outside ``shape`` and no two pushing robots closer than 2r."""
    r = robot_radius
    pushes = [np.asarray(p.pushes, float) for p in props]
    dense = [densify(p, MAX_STEP / 2) for p in pushes]
    ok = np.array([
        bool(np.all(signed_distance(shape, p[:, 0]) >= r - contact_tolerance))
        and pairwise_min_distance(d) >= 2 * r - 1e-9
        for p, d in zip(pushes, dense, strict=True)
    ], dtype=bool)
    sizes = [d.shape[0] * d.shape[1] for d in dense]
    points = np.concatenate([d.reshape(-1, 2) for d in dense]) if dense else np.zeros((0, 2))
    return PushCandidates(pushes, ok, points,
                          np.concatenate([[0], np.cumsum(sizes)]).astype(int))


def usable_mask(robots: RobotValidity, q_from: np.ndarray,
                cands: PushCandidates) -> np.ndarray:
    """``Collide`` for all K candidates at once: which are usable with the object at ``q_from``?

    A proposal is rejected when a contact or any point of a push path leaves the robots'
    free space (obstacles, other objects, border), when a contact lies inside the object
    (deeper than the contact tolerance), or when two pushing robots come closer than 2r.
    The pose-independent tests come precomputed (``PushCandidates.intrinsic_ok``); the
    free-space test is one query for all the candidates' points, in the robots' space
    around ``q_from`` (``robots.static_space_near``; a point beyond its window counts as
    not free), asked only when some candidate passed the others.
    """
    ok = cands.intrinsic_ok.copy()
    if not ok.any():
        return ok
    free = robots.static_space_near(q_from).is_free(
        se2.transform_points(q_from, cands.dense_points))
    ok &= np.logical_and.reduceat(free, cands.starts[:-1])
    return ok
