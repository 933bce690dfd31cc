"""Benchmark of the Gspi multi-robot motion planner (``lamp.mrmp.plan_paths``).

(a) LAMP's common case: 3 robots to 3 contact points around the object being pushed (the
    object is an obstacle), 100 instances per map family (50 per start kind). Scenes come
    from the built-in suites (``lamp.suites``: the object placed at its start or at a
    random pose near its way to the goal, at least 1 cm from obstacles) when they are
    available, else from this file's own cluttered map families with the same names.
    Start kinds: ``contact`` (robots stand in contact after the previous push, 1 mm
    clear) and ``spread`` (robots anywhere within 1.5 m of the object on suite maps).
    Timed cold (the space for the new object pose built inside the call; LAMP's first
    Gspi call at a pose) and with the space prebuilt (LAMP's further proposals there).
(b) 10, 30 and 100 robots in an open 4 m x 4 m map with scattered obstacles, each robot's
    own goal 1-3 m from its start (the planner may assign them differently).
(c) the same instances with the baseline: PIBT without goal swapping (same optimal initial
    assignment, same lattice and checks), side by side as success and time ratios.

Every successful plan is re-verified by the independent checker in ``tests/``.

Run: ``python benchmarks/bench_mrmp.py [--quick] [--families random,maze] [--n 50]``.
Figures: per call on one thread (``OMP_NUM_THREADS=1``), CPU (process) time and wall
time; median and p95 over instances; failed calls included. Ratios use CPU time, which a
busy shared machine disturbs much less than wall time.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import shapely  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from mrmp_checker import check_plan  # noqa: E402

from lamp.geometry.robot_space import RobotSpace, clear_caches  # noqa: E402
from lamp.geometry.shapes import to_shapely  # noqa: E402
from lamp.mrmp import plan_paths  # noqa: E402
from lamp.mrmp.distance_field import get_lattice  # noqa: E402
from lamp.mrmp.gspi import warmup  # noqa: E402
from lamp.scene.model import (  # noqa: E402
    Circle,
    Obstacle,
    Rectangle,
    Scene,
    SceneObject,
)

R = 0.05
FAMILIES = ("random", "maze", "tilt", "warehouse")


# ----------------------------------------------------------------------------------------
# own map families (used when lamp.suites is not available)
# ----------------------------------------------------------------------------------------


def _family_obstacles(family: str, rng: np.random.Generator) -> list[Obstacle]:
    obs: list[Obstacle] = []
    if family == "random":
        for _ in range(int(rng.integers(10, 18))):
            x, y = rng.uniform(0.3, 3.7, 2)
            if rng.random() < 0.4:
                obs.append(Obstacle(Circle(float(rng.uniform(0.08, 0.25))), (x, y, 0.0)))
            else:
                obs.append(Obstacle(Rectangle((float(rng.uniform(0.1, 0.6)),
                                               float(rng.uniform(0.1, 0.6)))), (x, y, 0.0)))
    elif family == "maze":
        # walls on a 1 m grid with random gaps (corridors about 0.9 m wide)
        for k in (1, 2, 3):
            for seg in range(4):
                if rng.random() < 0.55:
                    obs.append(Obstacle(Rectangle((1.0 - 0.45, 0.08)),
                                        (seg + 0.5 + float(rng.choice([-0.22, 0.22])), k, 0.0)))
                if rng.random() < 0.45:
                    obs.append(Obstacle(Rectangle((0.08, 1.0 - 0.45)),
                                        (k, seg + 0.5 + float(rng.choice([-0.22, 0.22])), 0.0)))
    elif family == "tilt":
        for _ in range(int(rng.integers(8, 13))):
            x, y = rng.uniform(0.4, 3.6, 2)
            obs.append(Obstacle(Rectangle((float(rng.uniform(0.4, 1.0)), 0.08)),
                                (x, y, float(rng.uniform(-np.pi, np.pi)))))
    elif family == "warehouse":
        for col in (0.9, 1.9, 2.9):
            for row in (0.9, 2.4):
                if rng.random() < 0.85:
                    obs.append(Obstacle(Rectangle((0.35, 1.0)),
                                        (col + float(rng.uniform(-0.1, 0.1)), row + 0.3, 0.0)))
    else:
        raise ValueError(f"unknown family {family!r}")
    return obs


def _free(geoms: list, p: np.ndarray, W: float, H: float, clear: float) -> bool:
    if not (clear <= p[0] <= W - clear and clear <= p[1] <= H - clear):
        return False
    pt = shapely.Point(*p)
    return all(shapely.distance(g, pt) >= clear for g in geoms)


def _sample_points(rng, geoms, n, W, H, taken=(), tries=5000, box=None) -> np.ndarray | None:
    pts: list[np.ndarray] = []
    for _ in range(tries):
        if len(pts) == n:
            break
        p = rng.uniform([0, 0], [W, H]) if box is None else rng.uniform(box[0], box[1])
        if not _free(geoms, p, W, H, R + 1e-3):
            continue
        if any(np.hypot(*(p - q)) < 2 * R + 1e-3 for q in list(pts) + list(taken)):
            continue
        pts.append(p)
    return np.array(pts) if len(pts) == n else None


def _contacts(shape, pose, rng, k: int) -> np.ndarray:
    """k contact points 1 mm more than r outside the object boundary, on distinct sides."""
    poly = to_shapely(shape, pose)
    ring = poly.exterior
    L = ring.length
    out = []
    base = rng.uniform(0, L)
    for j in range(k):
        s = (base + j * L / k + rng.uniform(-0.1, 0.1) * L / k) % L
        p = np.array(ring.interpolate(s).coords[0])
        # outward normal by finite difference along the ring (counter-clockwise exterior)
        q = np.array(ring.interpolate((s + 1e-3) % L).coords[0])
        t = (q - p) / max(np.hypot(*(q - p)), 1e-12)
        nrm = np.array([t[1], -t[0]])
        if poly.contains(shapely.Point(*(p + 0.01 * nrm))):
            nrm = -nrm
        c = p + nrm * (R + 1e-3)
        # push outwards until exactly clear (corners)
        for _ in range(20):
            d = shapely.distance(poly, shapely.Point(*c))
            if d >= R + 1e-3 - 1e-9:
                break
            c = c + nrm * (R + 1e-3 - d)
        out.append(c)
    return np.array(out)


def contact_instance(family: str, seed: int, start_kind: str):
    """(scene, object_poses, starts, goals) for case (a); None when sampling failed."""
    rng = np.random.default_rng(seed)
    W = H = 4.0
    for _ in range(50):
        obs = _family_obstacles(family, rng)
        if rng.random() < 0.5:
            shape = Rectangle((float(rng.uniform(0.15, 0.5)), float(rng.uniform(0.15, 0.5))))
        else:
            shape = Circle(float(rng.uniform(0.1, 0.3)))
        pose = (*rng.uniform(0.6, 3.4, 2), float(rng.uniform(-np.pi, np.pi)))
        obj_g = to_shapely(shape, pose)
        geoms = [to_shapely(o.shape, o.pose) for o in obs]
        if any(shapely.distance(obj_g, g) < 2 * R + 0.05 for g in geoms):
            continue
        scene = Scene(f"{family}-{seed}", (W, H), ((0.1, 0.1),) * 3,
                      (SceneObject(shape, pose, pose),), tuple(obs), R)
        allg = geoms + [obj_g]
        goals = _contacts(shape, pose, rng, 3)
        if not all(_free(allg, g, W, H, R) for g in goals):
            continue
        if min(np.hypot(*(goals[a] - goals[b])) for a in range(3) for b in range(a)) < 2 * R:
            continue
        if start_kind == "contact":
            starts = _contacts(shape, pose, rng, 3)
            if not all(_free(allg, s, W, H, R) for s in starts):
                continue
            if min(np.hypot(*(starts[a] - starts[b])) for a in range(3) for b in range(a)) < 2 * R:
                continue
        else:
            starts = _sample_points(rng, allg, 3, W, H)
            if starts is None:
                continue
        return scene, np.array([pose]), starts, goals
    return None


def _suite_scenes(family: str) -> list[Scene] | None:
    """The built-in suite's scenes, or None when the suites are not available."""
    try:
        from lamp.suites.registry import suite_scenes
    except ImportError:
        return None
    try:
        return list(suite_scenes(family))
    except Exception as exc:  # noqa: BLE001 - a suite being regenerated must not stop us
        print(f"  (suite {family!r} not loadable: {exc}; using own maps)")
        return None


def suite_instance(scene: Scene, seed: int, start_kind: str):
    """Case (a) on a suite scene: the first object at a pose on (or near) its way from
    start to goal, 3 contacts around it; robots in contact (after a push) or spread
    within 1.5 m. None when sampling failed."""
    rng = np.random.default_rng(seed)
    W, H = scene.workspace
    obj = scene.objects[0]
    others = [to_shapely(o.shape, o.start) for o in scene.objects[1:]]
    geoms = [to_shapely(o.shape, o.pose) for o in scene.obstacles] + others
    border = shapely.box(0, 0, W, H).exterior
    a = np.array(obj.start, float)
    b = np.array(obj.goal, float)
    for _ in range(200):
        u = rng.uniform(0, 1)
        pose = a + u * (b - a) + np.r_[rng.normal(0, 0.25, 2), rng.uniform(-np.pi, np.pi)]
        if seed % 4 == 0:
            pose = a.copy()
        og = to_shapely(obj.shape, pose)
        if not shapely.box(0, 0, W, H).contains(og) or shapely.distance(og, border) < 0.01:
            continue
        if any(shapely.distance(og, g) < 0.01 for g in geoms):
            continue
        allg = geoms + [og]
        goals = _contacts(obj.shape, pose, rng, 3)
        if not all(_free(allg, g, W, H, R) for g in goals):
            continue
        if min(np.hypot(*(goals[i] - goals[j])) for i in range(3) for j in range(i)) < 2 * R:
            continue
        if start_kind == "contact":
            starts = _contacts(obj.shape, pose, rng, 3)
            if not all(_free(allg, q, W, H, R) for q in starts):
                continue
            if min(np.hypot(*(starts[i] - starts[j])) for i in range(3) for j in range(i)) < 2 * R:
                continue
        else:
            box = (np.maximum(pose[:2] - 1.5, 0), np.minimum(pose[:2] + 1.5, [W, H]))
            starts = _sample_points(rng, allg, 3, W, H, box=box)
            if starts is None:
                continue
        poses = scene.object_starts()
        poses[0] = pose
        return scene, poses, starts, goals
    return None


def many_robot_instance(n: int, seed: int, size: float = 4.0):
    """Case (b): n robots, scattered obstacles, each robot's own goal 1-3 m away."""
    rng = np.random.default_rng(seed)
    W = H = size
    obs = []
    for _ in range(int(8 * (size / 4.0) ** 2)):
        x, y = rng.uniform(0.3, size - 0.3, 2)
        if rng.random() < 0.5:
            obs.append(Obstacle(Circle(float(rng.uniform(0.05, 0.15))), (x, y, 0.0)))
        else:
            obs.append(Obstacle(Rectangle((float(rng.uniform(0.1, 0.3)),
                                           float(rng.uniform(0.1, 0.3)))),
                                (x, y, float(rng.uniform(-3, 3)))))
    geoms = [to_shapely(o.shape, o.pose) for o in obs]
    starts = _sample_points(rng, geoms, n, W, H, tries=100000)
    if starts is None:
        return None
    goals: list[np.ndarray] = []
    for i in range(n):
        for _ in range(2000):
            a = rng.uniform(0, 2 * np.pi)
            d = rng.uniform(1.0, 3.0)
            g = starts[i] + d * np.array([np.cos(a), np.sin(a)])
            if not _free(geoms, g, W, H, R + 1e-3):
                continue
            if any(np.hypot(*(g - q)) < 2 * R + 1e-3 for q in goals):
                continue
            goals.append(g)
            break
        else:
            return None
    obj = SceneObject(Circle(0.01), (size - 0.02, size - 0.02, 0.0), (size - 0.02, size - 0.02, 0.0))
    scene = Scene(f"open-{n}-{seed}", (W, H), tuple(map(tuple, starts)), (obj,), tuple(obs), R)
    return scene, None, starts, np.array(goals)


# ----------------------------------------------------------------------------------------


def _run(inst, swap: bool, time_limit: float, verify: bool = True, warm: bool = False):
    """One call. Cold (default): the space for this object pose is built inside the call
    (only the scene's static layer is cached, as in LAMP after its first call); warm: the
    space and its lattice already exist (LAMP's further proposals at the same pose)."""
    scene, poses, S, G = inst
    if warm:
        space = RobotSpace.from_scene(scene, object_poses=poses)
        get_lattice(space)
    else:
        clear_caches(keep_base=True)
        RobotSpace.from_scene(scene, exclude_objects=range(len(scene.objects)))
    t0 = time.perf_counter()
    c0 = time.process_time()
    plan = plan_paths(scene, S, G, object_poses=poses, time_limit=time_limit,
                      goal_swapping=swap)
    dc = time.process_time() - c0
    dt = time.perf_counter() - t0
    if verify:
        check_plan(scene, S, G, plan, object_poses=poses)
    return plan.success, dt, plan.iterations, plan.paths.shape[1], dc


def _summ(label: str, res: list[tuple]) -> tuple[float, float, float]:
    """Print success and times; returns (success rate, median, p95) of the CPU time."""
    ok = np.array([r[0] for r in res])
    t = np.array([r[1] for r in res]) * 1e3
    it = np.array([r[2] for r in res])
    T = np.array([r[3] for r in res])
    c = np.array([r[4] for r in res]) * 1e3
    print(f"  {label:<26} success {ok.mean() * 100:5.1f}% ({ok.sum():3d}/{len(ok)})  "
          f"CPU median {np.median(c):7.2f} ms  p95 {np.percentile(c, 95):8.2f} ms | "
          f"wall median {np.median(t):7.2f} ms  p95 {np.percentile(t, 95):8.2f} ms  "
          f"max {t.max():7.1f} ms | steps {np.median(it):.0f}, rows {np.median(T):.0f}")
    return ok.mean(), float(np.median(c)), float(np.percentile(c, 95))


def _compare(a: tuple, b: tuple) -> None:
    sr = a[0] / b[0] if b[0] > 0 else float("inf")
    print(f"  ratio Gspi/baseline: success {sr:.2f}x, median CPU time {a[1] / b[1]:.2f}x, "
          f"p95 CPU time {a[2] / b[2]:.2f}x")


def bench_space(families: list[str]) -> None:
    """Cost of RobotSpace construction on the 4 m maps: the static layer (first call per
    scene), a new object pose laid over it, a cache hit, and the 5 cm planning lattice."""
    rows: dict[str, list[float]] = {"static layer + object": [], "new object pose": [],
                                    "cache hit": [], "lattice 5 cm": [], "lattice 2 cm": []}
    for fam in families:
        scenes = _suite_scenes(fam) or [contact_instance(fam, 7 + 1000 * k, "spread")[0]
                                        for k in range(10)]
        for sc in scenes:
            pose = np.array(sc.object_starts())
            for key, fn in (
                ("static layer + object", lambda sc=sc: (clear_caches(),
                                                          RobotSpace.from_scene(sc))),
                ("new object pose", lambda sc=sc, pose=pose: RobotSpace.from_scene(
                    sc, object_poses=pose + [0.01, 0.0, 0.0])),
                ("cache hit", lambda sc=sc, pose=pose: RobotSpace.from_scene(
                    sc, object_poses=pose + [0.01, 0.0, 0.0])),
                ("lattice 5 cm", lambda sc=sc, pose=pose: get_lattice(RobotSpace.from_scene(
                    sc, object_poses=pose + [0.01, 0.0, 0.0]), 0.05)),
                ("lattice 2 cm", lambda sc=sc, pose=pose: get_lattice(RobotSpace.from_scene(
                    sc, object_poses=pose + [0.01, 0.0, 0.0]), 0.02)),
            ):
                c0 = time.process_time()
                fn()
                rows[key].append(time.process_time() - c0)
    print("\n(0) RobotSpace on the 4 m maps (CPU ms per call, median / p95 over scenes)")
    for key, v in rows.items():
        a = np.array(v) * 1e3
        print(f"  {key:<24} {np.median(a):7.2f} / {np.percentile(a, 95):7.2f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer instances")
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--n", type=int, default=50,
                    help="instances per family and start kind in (a)")
    ap.add_argument("--many", default="10,30,100", help="robot counts for (b)")
    ap.add_argument("--many-n", type=int, default=20, help="instances per count in (b)")
    ap.add_argument("--time-limit", type=float, default=5.0)
    args = ap.parse_args()
    n_a = 20 if args.quick else args.n
    n_b = 5 if args.quick else args.many_n
    warmup()
    print(f"Gspi benchmark: times per plan_paths call (CPU = process time, robust to a busy "
          f"machine; wall = elapsed); load average at start {os.getloadavg()[0]:.1f}")

    bench_space(args.families.split(","))

    print("\n(a) 3 robots -> 3 contact points around the object")
    all_g: list = []
    all_w: list = []
    all_b: list = []
    for fam in args.families.split(","):
        for kind in ("contact", "spread"):
            insts = []
            seed = 0
            scenes = _suite_scenes(fam)
            source = f"suite {fam} ({len(scenes)} scenes)" if scenes else f"own {fam} maps"
            while len(insts) < n_a and seed < 20 * n_a:
                if scenes:
                    inst = suite_instance(scenes[seed % len(scenes)], seed, kind)
                else:
                    inst = contact_instance(fam, 1000 * seed + 7, kind)
                seed += 1
                if inst is not None:
                    insts.append(inst)
            rg = [_run(x, True, args.time_limit) for x in insts]
            rw = [_run(x, True, args.time_limit, warm=True) for x in insts]
            rb = [_run(x, False, args.time_limit) for x in insts]
            print(f" {source} / starts {kind}: {len(insts)} instances")
            a = _summ("Gspi (cold space)", rg)
            _summ("Gspi (space prebuilt)", rw)
            b = _summ("baseline PIBT (no swaps)", rb)
            _compare(a, b)
            all_g += rg
            all_w += rw
            all_b += rb
    print(" all families:")
    a = _summ("Gspi (cold space)", all_g)
    _summ("Gspi (space prebuilt)", all_w)
    _compare(a, _summ("baseline PIBT (no swaps)", all_b))

    print("\n(b) many robots, open 4 m x 4 m map with scattered obstacles, goals 1-3 m away")
    for n in (int(v) for v in args.many.split(",")):
        insts = []
        seed = 0
        while len(insts) < n_b:
            inst = many_robot_instance(n, 31 * seed + n)
            seed += 1
            if inst is not None:
                insts.append(inst)
        rg = [_run(x, True, args.time_limit) for x in insts]
        rb = [_run(x, False, args.time_limit) for x in insts]
        print(f" N = {n}:")
        a = _summ("Gspi", rg)
        b = _summ("baseline PIBT (no swaps)", rb)
        _compare(a, b)


if __name__ == "__main__":
    main()
