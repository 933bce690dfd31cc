"""A plain geometric proposer: the data-generation contact strategies, without learning.

Each strategy places ``b`` robots on the *contact ring* (the curve one robot radius plus a
few millimetres outside the object) and lets every robot follow its contact rigidly with the
object along the requested motion (``rigid_pushes``), which is how GCo commanded pushes when
it generated its training data. The strategies (GCo's, see gco-facts.md "Training data"):

- ``behind``: pushers behind the motion, spread along the back; the push line is shifted
  sideways by the quasi-static lever arm that produces the requested rotation;
- ``guides``: one such pusher plus one or two side guides that stop the object drifting;
- ``two_sided``: two pushers at +-alpha around the back (plus one behind for b = 3);
- ``rotation``: pushers where the rigid motion drives the robot most into the surface
  (offset pushes, couples for turning on the spot);
- ``random``: boundary points drawn with weight on pushing effectiveness.

``GeometricProposer`` draws several candidates per requested proposal and keeps the ones
whose contact forces can best produce the required quasi-static wrench (frictionless
non-negative least squares against an ellipsoidal limit surface), so its first proposals
are its best guesses and the rest keep diversity for cluttered scenes.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from lamp.manip.contact_ring import Ring, characteristic_radius, contact_ring
from lamp.manip.contacts import (
    CONTACT_OFFSET,
    HORIZON,
    ROBOT_RADIUS,
    as_shape,
    check_budget,
    check_motion,
    ray_hit,
    rigid_pushes,
)
from lamp.manip.proposals import Proposal, ShapeLike, check_k, make_rng
from lamp.scene.model import Shape

MIN_SEPARATION = 2.0 * ROBOT_RADIUS + 0.01
"""Smallest centre distance between two robots of one formation (m)."""
STRATEGIES = ("behind", "guides", "two_sided", "rotation", "random")


# --------------------------------------------------------------------------- strategies
def _rot(u: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([c * u[0] - s * u[1], s * u[0] + c * u[1]])


@dataclass(frozen=True)
class _Frame:
    """Motion-derived quantities the strategies share."""

    shape: Shape
    ring: Ring
    motion: np.ndarray
    d: np.ndarray  # unit translation direction (random when the motion is a pure rotation)
    perp: np.ndarray  # d turned by +90 degrees
    trans: float
    cbar: float
    lever: float  # signed lateral offset of the push line giving the requested rotation
    half_width: float  # support half-width of the shape across d


def _frame(shape: Shape, motion: np.ndarray, rng: np.random.Generator) -> _Frame:
    ring = contact_ring(shape)
    trans = float(np.hypot(motion[0], motion[1]))
    if trans > 1e-3:
        d = motion[:2] / trans
    else:
        a = rng.uniform(-np.pi, np.pi)
        d = np.array([np.cos(a), np.sin(a)])
    perp = np.array([-d[1], d[0]])
    cbar = characteristic_radius(shape)
    # quasi-static, ellipsoidal limit surface: moment / force = cbar^2 * omega / |v|; a push
    # along d whose line is shifted by l along perp has moment -l * force.
    lever = -cbar**2 * motion[2] / max(trans, 1e-3)
    half_width = float(np.max(ring.boundary @ perp))
    return _Frame(shape, ring, motion, d, perp, trans, cbar, lever, half_width)


def _back_index(f: _Frame, lateral: float) -> int | None:
    """Ring index behind the object on the push line shifted by ``lateral`` along perp."""
    hit = ray_hit(f.shape, lateral * f.perp, -f.d)
    if hit is None:
        return None
    return f.ring.nearest(hit[0] + CONTACT_OFFSET * hit[1])


def _side_index(f: _Frame, sign: float, along: float) -> int | None:
    hit = ray_hit(f.shape, along * f.d, sign * f.perp)
    if hit is None:
        return None
    return f.ring.nearest(hit[0] + CONTACT_OFFSET * hit[1])


def _clip_lever(f: _Frame, lever: float, frac: float = 0.8) -> float:
    lim = frac * f.half_width
    return float(np.clip(lever, -lim, lim))


def _effectiveness(f: _Frame) -> np.ndarray:
    """How fast the rigidly carried robot moves into the surface at each ring sample."""
    p, n = f.ring.points, f.ring.normals
    m = f.motion
    vx = m[0] - m[2] * p[:, 1]
    vy = m[1] + m[2] * p[:, 0]
    return -(vx * n[:, 0] + vy * n[:, 1])


def _spread(f: _Frame, center: int, b: int, spacing: float) -> list[int]:
    if b == 1:
        return [center]
    if b == 2:
        return [f.ring.walk(center, -0.5 * spacing), f.ring.walk(center, 0.5 * spacing)]
    return [f.ring.walk(center, -spacing), center, f.ring.walk(center, spacing)]


def strategy_behind(f: _Frame, b: int, rng: np.random.Generator, jitter: float) -> list[int] | None:
    lever = _clip_lever(f, f.lever * (1.0 + jitter * rng.normal(0.0, 0.3))
                        + jitter * rng.normal(0.0, 0.03))
    i0 = _back_index(f, lever)
    if i0 is None:
        return None
    spacing = MIN_SEPARATION + 0.01 + jitter * rng.uniform(0.0, 0.06)
    return _spread(f, i0, b, spacing)


def strategy_guides(f: _Frame, b: int, rng: np.random.Generator, jitter: float) -> list[int] | None:
    if b < 2:
        return strategy_behind(f, b, rng, jitter)
    lever = _clip_lever(f, f.lever * (1.0 + jitter * rng.normal(0.0, 0.3)))
    i0 = _back_index(f, lever)
    along = jitter * rng.uniform(-0.4, 0.2) * f.half_width
    sides = [1.0, -1.0] if b == 3 else [float(rng.choice([1.0, -1.0]))]
    idx = [_side_index(f, s, along) for s in sides]
    if i0 is None or any(i is None for i in idx):
        return None
    return [i0, *idx]


def strategy_two_sided(f: _Frame, b: int, rng: np.random.Generator, jitter: float) -> list[int] | None:
    if b < 2:
        return strategy_rotation(f, b, rng, jitter)
    alpha = np.deg2rad(45.0 + jitter * rng.uniform(-20.0, 20.0))
    skew = np.clip(f.lever / max(f.half_width, 1e-3), -1.0, 1.0) * np.deg2rad(20.0)
    out = []
    for s in (1.0, -1.0):
        hit = ray_hit(f.shape, np.zeros(2), _rot(-f.d, s * alpha + skew))
        if hit is None:
            return None
        out.append(f.ring.nearest(hit[0] + CONTACT_OFFSET * hit[1]))
    if b == 3:
        i0 = _back_index(f, _clip_lever(f, f.lever))
        if i0 is None:
            return None
        out.append(i0)
    return out


def _pick_weighted(
    f: _Frame, w: np.ndarray, b: int, rng: np.random.Generator, greedy_first: bool
) -> list[int] | None:
    """Pick b ring samples with probability ~ w, at least MIN_SEPARATION apart."""
    w = np.clip(w, 0.0, None)
    chosen: list[int] = []
    for j in range(b):
        if chosen:
            d = np.min(np.hypot(*(f.ring.points[:, None, :] - f.ring.points[chosen][None]).transpose(2, 0, 1)), axis=1)
            w = np.where(d >= MIN_SEPARATION + 0.005, w, 0.0)
        total = w.sum()
        if total <= 0.0:
            return None
        i = int(np.argmax(w)) if (greedy_first and j == 0) else int(rng.choice(len(w), p=w / total))
        chosen.append(i)
    return chosen


def strategy_rotation(f: _Frame, b: int, rng: np.random.Generator, jitter: float) -> list[int] | None:
    e = _effectiveness(f)
    if e.max() <= 1e-9:
        return None
    w = np.clip(e / e.max(), 0.0, None) ** 4
    return _pick_weighted(f, w, b, rng, greedy_first=jitter == 0.0)


def strategy_random(f: _Frame, b: int, rng: np.random.Generator, jitter: float) -> list[int] | None:
    e = _effectiveness(f)
    scale = max(float(e.max()), 1e-9)
    w = np.clip(e / scale, 0.0, None) + 0.05
    return _pick_weighted(f, w, b, rng, greedy_first=False)


_STRATEGY_FUNCS: dict[str, Callable[[_Frame, int, np.random.Generator, float], list[int] | None]] = {
    "behind": strategy_behind,
    "guides": strategy_guides,
    "two_sided": strategy_two_sided,
    "rotation": strategy_rotation,
    "random": strategy_random,
}


def strategy_contacts(
    shape: ShapeLike,
    motion: ArrayLike,
    budget: int,
    strategy: str,
    rng: np.random.Generator,
    jitter: float = 1.0,
) -> np.ndarray | None:
    """Contacts (b, 2) placed by one named strategy, or None when it cannot place them.

    ``jitter`` scales the randomisation (0: the strategy's nominal placement, 1: the
    randomised variants used for data generation).
    """
    if strategy not in _STRATEGY_FUNCS:
        raise ValueError(f"strategy must be one of {', '.join(STRATEGIES)}, got {strategy!r}")
    f = _frame(as_shape(shape), check_motion(motion), rng)
    return _strategy_contacts(f, check_budget(budget), strategy, rng, jitter)


def _strategy_contacts(
    f: _Frame, b: int, strategy: str, rng: np.random.Generator, jitter: float
) -> np.ndarray | None:
    if f.trans <= 1e-3:  # pure rotation: draw a fresh reference direction per candidate
        f = _frame(f.shape, f.motion, rng)
    idx = _STRATEGY_FUNCS[strategy](f, b, rng, jitter)
    if idx is None or len(set(idx)) != len(idx):
        return None
    c = f.ring.points[np.asarray(idx)]
    if len(c) > 1:
        d = np.hypot(*(c[:, None, :] - c[None, :, :]).transpose(2, 0, 1))
        d[np.diag_indices(len(c))] = np.inf
        if d.min() < MIN_SEPARATION - 1e-9:
            return None
    return c.copy()


# --------------------------------------------------------------------------- wrench score
def _nnls_residual(w: np.ndarray, target: np.ndarray) -> np.ndarray:
    """min_{lambda >= 0} |W lambda - target| for a batch: W (M, 3, b), target (M, 3).

    Exact for small b by enumerating active sets (an active set whose unconstrained least
    squares solution is non-negative is feasible; the best feasible one is optimal).
    """
    m, _, b = w.shape
    best = np.linalg.norm(target, axis=1)
    for size in range(1, b + 1):
        for subset in itertools.combinations(range(b), size):
            a = w[:, :, list(subset)]
            ata = np.einsum("mki,mkj->mij", a, a) + 1e-10 * np.eye(size)
            atb = np.einsum("mki,mk->mi", a, target)
            lam = np.linalg.solve(ata, atb[..., None])[..., 0]
            res = np.linalg.norm(np.einsum("mki,mi->mk", a, lam) - target, axis=1)
            ok = np.all(lam >= -1e-9, axis=1)
            best = np.where(ok & (res < best), res, best)
    return best


def wrench_residual(shape: ShapeLike, contacts: np.ndarray, motion: ArrayLike) -> np.ndarray:
    """How far pushes at ``contacts`` (M, b, 2) are from producing the motion's wrench.

    0 means the frictionless contact forces can produce exactly the quasi-static wrench
    direction the motion needs; 1 means none of it. Quasi-static model: an ellipsoidal
    limit surface with moment scale ``characteristic_radius``.
    """
    shp = as_shape(shape)
    m = check_motion(motion)
    c = np.asarray(contacts, dtype=float)
    cbar = characteristic_radius(shp)
    target = np.array([m[0], m[1], cbar * m[2]])
    norm = np.linalg.norm(target)
    if norm < 1e-9:
        return np.zeros(len(c))
    target = target / norm
    # push direction = inward normal at the touched boundary point
    from lamp.manip.contacts import closest_boundary

    q, u = closest_boundary(shp, c)
    force = -u
    moment = (q[..., 0] * force[..., 1] - q[..., 1] * force[..., 0]) / cbar
    w = np.concatenate([force, moment[..., None]], axis=-1).transpose(0, 2, 1)  # (M, 3, b)
    return _nnls_residual(w, np.repeat(target[None], len(c), axis=0))


# --------------------------------------------------------------------------- the proposer
def _strategy_weights(budget: int, motion: np.ndarray, cbar: float) -> dict[str, float]:
    trans = float(np.hypot(motion[0], motion[1]))
    rot = abs(float(motion[2])) * cbar
    rot_dominated = rot > 1.5 * trans
    if budget == 1:
        w = {"behind": 0.4, "rotation": 0.4, "random": 0.2}
    elif budget == 2:
        w = {"behind": 0.3, "guides": 0.15, "two_sided": 0.2, "rotation": 0.2, "random": 0.15}
    else:
        w = {"behind": 0.2, "guides": 0.3, "two_sided": 0.2, "rotation": 0.15, "random": 0.15}
    if rot_dominated:
        w["rotation"] = w.get("rotation", 0.0) + 0.4
    return w


class GeometricProposer:
    """Proposals from the hand-made contact strategies, ranked by a quasi-static wrench check.

    Same API as the learned model (``lamp.manip.ProposalModel``); fast (a few ms for k = 16)
    and deterministic for a given seed. ``oversample`` candidates are drawn per requested
    proposal; ``temperature`` controls how strongly the wrench residual decides which survive
    (small: best only; large: uniform). ``jitter`` is the strategies' randomisation.
    """

    horizon: int = HORIZON
    #: The strategies place contacts for robots of this radius (``CONTACT_OFFSET``).
    robot_radius: float = ROBOT_RADIUS

    def __init__(self, oversample: int = 3, temperature: float = 0.05, jitter: float = 0.5) -> None:
        if oversample < 1:
            raise ValueError(f"oversample must be >= 1, got {oversample!r}")
        if temperature <= 0:
            raise ValueError(f"temperature must be > 0, got {temperature!r}")
        self.oversample = int(oversample)
        self.temperature = float(temperature)
        self.jitter = float(jitter)

    def propose(
        self,
        shape: ShapeLike,
        motion: ArrayLike,
        budget: int,
        k: int = 16,
        seed: int | np.random.Generator | None = None,
    ) -> list[Proposal]:
        """``k`` proposals (best-ranked first) for moving ``shape`` by ``motion`` (object frame)."""
        shp = as_shape(shape)
        m = check_motion(motion)
        b = check_budget(budget)
        k = check_k(k)
        rng = make_rng(seed)
        weights = _strategy_weights(b, m, characteristic_radius(shp))
        names = list(weights)
        p = np.array([weights[n] for n in names])
        p /= p.sum()
        want = k * self.oversample
        cands: list[tuple[np.ndarray, str]] = []
        attempts = 0
        frame = _frame(shp, m, rng)
        while len(cands) < want and attempts < 4 * want:
            attempts += 1
            name = names[int(rng.choice(len(names), p=p))]
            c = _strategy_contacts(frame, b, name, rng, self.jitter)
            if c is not None:
                cands.append((c, name))
        if not cands:  # degenerate request: fall back to the most effective single pushes
            for bb in range(b, 0, -1):
                c = strategy_contacts(shp, m, bb, "random", rng, 1.0)
                if c is not None:
                    cands.append((c, "random"))
                    break
            if not cands:
                ring = contact_ring(shp)
                cands.append((ring.points[[int(rng.integers(len(ring)))]].copy(), "random"))
        # rank: score each candidate, sample k without replacement ~ exp(-residual / T)
        by_size: dict[int, list[int]] = {}
        for i, (c, _) in enumerate(cands):
            by_size.setdefault(len(c), []).append(i)
        res = np.empty(len(cands))
        for idx in by_size.values():
            res[idx] = wrench_residual(shp, np.stack([cands[i][0] for i in idx]), m)
        logits = -res / self.temperature
        gumbel = rng.gumbel(size=len(cands))
        order = np.argsort(-(logits + gumbel))[: min(k, len(cands))]
        order = order[np.argsort(res[order], kind="stable")]
        chosen = [int(i) for i in order]
        while len(chosen) < k:  # fewer distinct candidates than asked for: repeat the best
            chosen.append(chosen[len(chosen) % max(1, len(order))])
        return [
            Proposal(cands[i][0].copy(), rigid_pushes(cands[i][0], m, self.horizon),
                     f"geometric:{cands[i][1]}")
            for i in chosen
        ]

    def propose_batch(
        self,
        shape: ShapeLike,
        motions: Sequence[ArrayLike] | np.ndarray,
        budget: int,
        k: int = 16,
        seed: int | np.random.Generator | None = None,
    ) -> list[list[Proposal]]:
        """``propose`` for each motion in turn (one shared random stream)."""
        rng = make_rng(seed)
        return [self.propose(shape, m, budget, k, rng) for m in motions]
