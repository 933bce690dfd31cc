"""The MuJoCo push dataset: simulated pushes by the contact strategies, kept when they work.

One sample (as GCo's training data): draw an object (circle r 0.10-0.30 m
or rectangle with sides 0.15-0.50 m), a budget b in {1, 2, 3}, a requested motion (dx, dy
in [-0.2, 0.2] m, dtheta in [-0.5, 0.5] rad, object frame) and a contact strategy; place b
robots touching the object (``lamp.manip.geometric``), command each robot to follow its
contact rigidly with the object along the linear SE(2) interpolation of the motion, execute
in ``lamp.sim.Simulator`` in open space and record the robots. The sample is kept when the
achieved motion lands within ``accept_translation`` / ``accept_rotation`` of the request; its
labels are the *achieved* motion and the robots' *recorded* paths (H = 20 waypoints,
time-uniform, object frame of the start pose).

Storage is compact (shape parameters, not images) in one ``.npz``; see ``PushDataset``.
Generation is parallel over processes (``multiprocessing``), shows a tqdm bar and is
deterministic for a given seed and chunking (each chunk has its own seed sequence child).
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.se2 import relative, transform_points, wrap_angle
from lamp.geometry.team import DEFAULT_TEAM
from lamp.manip.contacts import HORIZON, MAX_ROBOTS, MOTION_RANGE, ROBOT_RADIUS, rigid_pushes
from lamp.manip.geometric import STRATEGIES, strategy_contacts
from lamp.scene.model import Circle, Rectangle, Scene, SceneObject, Shape

log = logging.getLogger(__name__)

WORKSPACE = 4.0
"""Side of the open square workspace the pushes run in (m); the object starts at its centre."""
SIM_STEP = round(0.9 * DEFAULT_TEAM.row_step, 12)
"""Densified step of the commanded robot paths (m), under the simulator's 0.02 m limit."""
MOTION_LIMITS = np.array(MOTION_RANGE)
"""Bounds of the requested motions (|dx|, |dy| in m, |dtheta| in rad)."""
SHAPE_CIRCLE, SHAPE_RECTANGLE = 0, 1
CIRCLE_RADII = (0.10, 0.30)
"""Range of the training circles' radii (m)."""
RECTANGLE_SIDES = (0.15, 0.50)
"""Range of the training rectangles' side lengths (m)."""
TRAINED_EXTENT = RECTANGLE_SIDES[1]
"""The largest rectangle the training data covers (m), measured as
``lamp.manip.scaling.shape_extent`` does (the side of the smallest origin-centred square,
aligned with the object's axes, that holds it): the learned model sees larger rectangles
and polygons scaled down to this (``lamp.manip.scaling``)."""
TRAINED_CIRCLE_EXTENT = 2.0 * CIRCLE_RADII[1]
"""The same bound for circles (m): the largest training circle's diameter."""

# strategy weights per budget (GCo's strategies; 'random' are the randomised variants)
_STRATEGY_WEIGHTS = {
    1: {"behind": 0.45, "rotation": 0.35, "random": 0.2},
    2: {"behind": 0.3, "guides": 0.2, "two_sided": 0.2, "rotation": 0.15, "random": 0.15},
    3: {"behind": 0.2, "guides": 0.3, "two_sided": 0.2, "rotation": 0.15, "random": 0.15},
}


# --------------------------------------------------------------------------- execution
def densify(paths: ArrayLike, max_step: float = SIM_STEP) -> np.ndarray:
    """Insert rows into synchronised paths (N, T, 2) so no robot moves more than max_step."""
    p = np.asarray(paths, dtype=float)
    if p.shape[1] < 2:
        return p.copy()
    step = np.hypot(*np.moveaxis(np.diff(p, axis=1), 2, 0)).max(axis=0)  # (T-1,)
    n_sub = np.maximum(1, np.ceil(step / max_step - 1e-12).astype(int))
    s = np.concatenate([[0.0], np.cumsum(n_sub)])
    t = np.arange(int(s[-1]) + 1)
    seg = np.clip(np.searchsorted(s, t, side="right") - 1, 0, len(n_sub) - 1)
    frac = (t - s[seg]) / n_sub[seg]
    return p[:, seg] + frac[None, :, None] * (p[:, seg + 1] - p[:, seg])


def object_scene(shape: Shape, n_robots: int, robot_starts: np.ndarray) -> Scene:
    """A tiny open scene: ``shape`` at the centre of a WORKSPACE square, robots given."""
    c = 0.5 * WORKSPACE
    return Scene(
        name="manip-push",
        workspace=(WORKSPACE, WORKSPACE),
        robot_starts=tuple((float(x), float(y)) for x, y in robot_starts),
        objects=(SceneObject(shape, (c, c, 0.0), (c, c, 0.0)),),
    )


@dataclass(frozen=True)
class PushOutcome:
    """Result of executing one push in open space (object frame of the start pose)."""

    achieved: np.ndarray  # (3,) achieved object motion
    robot_paths: np.ndarray  # (b, H, 2) recorded robot paths, time-uniform
    steps: int  # physics steps simulated


def execute_push(
    shape: Shape, contacts: np.ndarray, pushes: np.ndarray, horizon: int = HORIZON
) -> PushOutcome:
    """Run one push in the simulator: robots start at ``contacts`` and follow ``pushes``.

    Everything is in the object's frame at its start pose; the object starts at rest at the
    centre of an empty WORKSPACE square with orientation 0.
    """
    from lamp.sim import SETTLE_TIME, Simulator

    c0 = np.array([0.5 * WORKSPACE, 0.5 * WORKSPACE, 0.0])
    contacts = np.asarray(contacts, dtype=float).reshape(-1, 2)
    b = len(contacts)
    start = transform_points(c0, contacts)
    sim = Simulator(object_scene(shape, b, start))
    paths = densify(transform_points(c0, np.asarray(pushes, dtype=float)))
    out = sim.execute(paths, record_every=5)
    achieved = relative(c0, out.object_poses[0])
    tr = out.trace
    assert tr is not None
    t_move = max(out.sim_time - SETTLE_TIME, 1e-9)
    tq = np.linspace(0.0, t_move, horizon)
    rec = np.empty((b, horizon, 2))
    for i in range(b):
        for a in range(2):
            rec[i, :, a] = np.interp(tq, tr.times, tr.robot_positions[:, i, a])
    rec = rec - c0[:2]  # world -> object frame (orientation 0 at the start)
    rec[:, 0] = contacts
    return PushOutcome(achieved, rec, out.steps)


# --------------------------------------------------------------------------- sampling
def sample_shape(rng: np.random.Generator) -> Shape:
    """A training object: circle of radius in ``CIRCLE_RADII`` or rectangle with sides in
    ``RECTANGLE_SIDES``."""
    if rng.random() < 0.4:
        return Circle(float(rng.uniform(*CIRCLE_RADII)))
    return Rectangle((float(rng.uniform(*RECTANGLE_SIDES)), float(rng.uniform(*RECTANGLE_SIDES))))


def sample_motion(rng: np.random.Generator) -> np.ndarray:
    """A requested motion: mostly uniform in the box, some pure translations / rotations."""
    m = rng.uniform(-MOTION_LIMITS, MOTION_LIMITS)
    u = rng.random()
    if u < 0.15:
        m[2] = 0.0
    elif u < 0.25:
        m[:2] = 0.0
    elif u < 0.35:
        m[2] *= 0.2
    return m


def shape_params(shape: Shape) -> tuple[int, float, float]:
    """(type code, p0, p1): circle (0, r, r), rectangle (1, sx, sy)."""
    if isinstance(shape, Circle):
        return SHAPE_CIRCLE, shape.radius, shape.radius
    if isinstance(shape, Rectangle):
        return SHAPE_RECTANGLE, float(shape.size[0]), float(shape.size[1])
    raise ValueError(f"the dataset stores circles and rectangles only, got {type(shape).__name__}")


def shape_from_params(kind: int, p0: float, p1: float) -> Shape:
    if int(kind) == SHAPE_CIRCLE:
        return Circle(float(p0))
    return Rectangle((float(p0), float(p1)))


@dataclass
class _Chunk:
    """Raw output of one worker chunk (accepted samples plus per-strategy counts)."""

    shape: list
    budget: list
    strategy: list
    requested: list
    achieved: list
    contacts: list
    paths: list
    tried: np.ndarray
    kept: np.ndarray
    steps: int


def _run_chunk(args: tuple[int, np.random.SeedSequence, float, float]) -> _Chunk:
    """Try ``n`` pushes from one seed sequence (the worker entry point)."""
    n, seq, acc_t, acc_r = args
    rng = np.random.default_rng(seq)
    ch = _Chunk([], [], [], [], [], [], [], np.zeros(len(STRATEGIES), int),
                np.zeros(len(STRATEGIES), int), 0)
    shape = sample_shape(rng)
    for j in range(n):
        if j % 4 == 0:  # a few pushes per object keep the compiled-model cache warm
            shape = sample_shape(rng)
        b = int(rng.integers(1, MAX_ROBOTS + 1))
        motion = sample_motion(rng)
        w = _STRATEGY_WEIGHTS[b]
        names = list(w)
        p = np.array([w[k] for k in names])
        name = names[int(rng.choice(len(names), p=p / p.sum()))]
        si = STRATEGIES.index(name)
        contacts = strategy_contacts(shape, motion, b, name, rng, jitter=1.0)
        ch.tried[si] += 1
        if contacts is None:
            continue
        out = execute_push(shape, contacts, rigid_pushes(contacts, motion))
        ch.steps += out.steps
        err_t = float(np.hypot(*(out.achieved[:2] - motion[:2])))
        err_r = abs(float(wrap_angle(out.achieved[2] - motion[2])))
        if err_t > acc_t or err_r > acc_r:
            continue
        ch.kept[si] += 1
        ch.shape.append(shape_params(shape))
        ch.budget.append(b)
        ch.strategy.append(si)
        ch.requested.append(motion)
        ch.achieved.append(out.achieved)
        pad_c = np.full((MAX_ROBOTS, 2), np.nan)
        pad_p = np.full((MAX_ROBOTS, HORIZON, 2), np.nan)
        pad_c[:b] = contacts
        pad_p[:b] = out.robot_paths
        ch.contacts.append(pad_c)
        ch.paths.append(pad_p)
    return ch


# --------------------------------------------------------------------------- the dataset
@dataclass
class PushDataset:
    """Accepted pushes, one row each (unused robot slots are NaN).

    shape_kind (S,) int8 (0 circle, 1 rectangle); shape_params (S, 2) (r, r) or (sx, sy);
    budget (S,) int8; strategy (S,) int8 (index into ``STRATEGIES``); requested (S, 3);
    achieved (S, 3) object motions (object frame); contacts (S, 3, 2); paths (S, 3, H, 2)
    recorded robot paths (object frame, ``paths[:, i, 0] == contacts[:, i]``).
    """

    shape_kind: np.ndarray
    shape_params: np.ndarray
    budget: np.ndarray
    strategy: np.ndarray
    requested: np.ndarray
    achieved: np.ndarray
    contacts: np.ndarray
    paths: np.ndarray
    meta: dict

    def __len__(self) -> int:
        return len(self.budget)

    def save(self, path: str | Path) -> None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(
            path,
            shape_kind=self.shape_kind, shape_params=self.shape_params.astype(np.float32),
            budget=self.budget, strategy=self.strategy,
            requested=self.requested.astype(np.float32), achieved=self.achieved.astype(np.float32),
            contacts=self.contacts.astype(np.float32), paths=self.paths.astype(np.float32),
            meta=np.array(json.dumps(self.meta)),
        )

    @classmethod
    def load(cls, path: str | Path) -> PushDataset:
        with np.load(Path(path)) as z:
            return cls(
                z["shape_kind"], z["shape_params"].astype(np.float64), z["budget"],
                z["strategy"], z["requested"].astype(np.float64),
                z["achieved"].astype(np.float64), z["contacts"].astype(np.float64),
                z["paths"].astype(np.float64), json.loads(str(z["meta"])),
            )

    @classmethod
    def concatenate(cls, parts: list[PushDataset]) -> PushDataset:
        fields = ["shape_kind", "shape_params", "budget", "strategy", "requested", "achieved",
                  "contacts", "paths"]
        meta = {"parts": [p.meta for p in parts]}
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in fields), meta)

    def subset(self, idx: np.ndarray) -> PushDataset:
        fields = ["shape_kind", "shape_params", "budget", "strategy", "requested", "achieved",
                  "contacts", "paths"]
        return PushDataset(*(getattr(self, f)[idx] for f in fields), dict(self.meta))

    def shapes(self) -> Iterator[Shape]:
        for k, (p0, p1) in zip(self.shape_kind, self.shape_params, strict=True):
            yield shape_from_params(int(k), p0, p1)


def generate(
    n_attempts: int,
    seed: int = 0,
    workers: int = 1,
    chunk: int = 64,
    accept_translation: float = 0.05,
    accept_rotation: float = 0.15,
    progress: bool = True,
) -> PushDataset:
    """Simulate ``n_attempts`` pushes and keep the accepted ones (see module docstring).

    Deterministic for a given (n_attempts, seed, chunk) whatever the number of workers.
    """
    if n_attempts < 1:
        raise ValueError(f"n_attempts must be >= 1, got {n_attempts!r}")
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers!r}")
    n_chunks = math.ceil(n_attempts / chunk)
    seqs = np.random.SeedSequence(seed).spawn(n_chunks)
    sizes = [min(chunk, n_attempts - i * chunk) for i in range(n_chunks)]
    jobs = [(s, q, accept_translation, accept_rotation) for s, q in zip(sizes, seqs, strict=True)]
    t0 = time.perf_counter()
    from tqdm import tqdm

    bar = tqdm(total=n_attempts, unit="push", disable=not progress, smoothing=0.05)
    results: list[_Chunk] = []
    if workers == 1:
        for job in jobs:
            results.append(_run_chunk(job))
            bar.update(job[0])
    else:
        import multiprocessing as mp

        with mp.get_context("spawn").Pool(workers, initializer=_worker_init) as pool:
            for job, res in zip(jobs, pool.imap(_run_chunk, jobs), strict=True):
                results.append(res)
                bar.update(job[0])
    bar.close()
    wall = time.perf_counter() - t0
    tried = sum(r.tried for r in results)
    kept = sum(r.kept for r in results)
    meta = {
        "seed": seed,
        "robot_radius": ROBOT_RADIUS,
        "attempts": n_attempts,
        "chunk": chunk,
        "accepted": int(kept.sum()),
        "accept_translation": accept_translation,
        "accept_rotation": accept_rotation,
        "wall_time_s": wall,
        "workers": workers,
        "physics_steps": int(sum(r.steps for r in results)),
        "per_strategy": {
            name: {"tried": int(t), "kept": int(k), "rate": float(k / t) if t else 0.0}
            for name, t, k in zip(STRATEGIES, tried, kept, strict=True)
        },
    }
    cat = {f: [x for r in results for x in getattr(r, f)]
           for f in ("shape", "budget", "strategy", "requested", "achieved", "contacts", "paths")}
    s = len(cat["budget"])
    sp = np.array(cat["shape"], dtype=float).reshape(s, 3)
    return PushDataset(
        shape_kind=sp[:, 0].astype(np.int8),
        shape_params=sp[:, 1:],
        budget=np.array(cat["budget"], dtype=np.int8),
        strategy=np.array(cat["strategy"], dtype=np.int8),
        requested=np.array(cat["requested"], dtype=float).reshape(s, 3),
        achieved=np.array(cat["achieved"], dtype=float).reshape(s, 3),
        contacts=np.array(cat["contacts"], dtype=float).reshape(s, MAX_ROBOTS, 2),
        paths=np.array(cat["paths"], dtype=float).reshape(s, MAX_ROBOTS, HORIZON, 2),
        meta=meta,
    )


def _worker_init() -> None:
    """Keep every worker single-threaded (the cores are shared)."""
    import os

    os.environ.setdefault("OMP_NUM_THREADS", "1")


def synthetic_dataset(n: int, seed: int = 0) -> PushDataset:
    """``n`` samples labelled without simulation (achieved = requested, paths = the rigid
    pushes): for tests and for exercising training before simulated data exists."""
    rng = np.random.default_rng(seed)
    rows: dict[str, list] = {k: [] for k in ("shape", "budget", "strategy", "motion",
                                             "contacts", "paths")}
    while len(rows["budget"]) < n:
        shape = sample_shape(rng)
        b = int(rng.integers(1, MAX_ROBOTS + 1))
        motion = sample_motion(rng)
        name = str(rng.choice(list(_STRATEGY_WEIGHTS[b])))
        c = strategy_contacts(shape, motion, b, name, rng)
        if c is None:
            continue
        pad_c = np.full((MAX_ROBOTS, 2), np.nan)
        pad_p = np.full((MAX_ROBOTS, HORIZON, 2), np.nan)
        pad_c[:b] = c
        pad_p[:b] = rigid_pushes(c, motion)
        for key, v in zip(rows, (shape_params(shape), b, STRATEGIES.index(name), motion, pad_c,
                                 pad_p), strict=True):
            rows[key].append(v)
    sp = np.array(rows["shape"], dtype=float)
    motion = np.array(rows["motion"], dtype=float)
    return PushDataset(
        shape_kind=sp[:, 0].astype(np.int8), shape_params=sp[:, 1:],
        budget=np.array(rows["budget"], dtype=np.int8),
        strategy=np.array(rows["strategy"], dtype=np.int8),
        requested=motion, achieved=motion.copy(), contacts=np.array(rows["contacts"]),
        paths=np.array(rows["paths"]), meta={"seed": seed, "synthetic": True},
    )
