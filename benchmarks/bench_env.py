"""Environment steps per second of ``lamp/Push-v0`` and the PettingZoo parallel environment.

One core (MuJoCo single-threaded, ``OMP_NUM_THREADS=1``), 3-robot suite scenes, default
settings (20 ms per step). Two action streams:
- ``random``: uniform random commands (mostly free motion);
- ``push``: every robot drives at the active object (contact-rich: robots press on it).
Episodes that end are reset (the reset time counts). Prints, per scene and stream, the
median (and min, max) over repeats of steps per second for the raw Gymnasium environment,
the one ``gymnasium.make`` returns (with its checking wrappers) and the PettingZoo one.

Run: ``python benchmarks/bench_env.py [--steps 2000] [--repeats 5] [--scenes random-01 ...]``
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium  # noqa: E402
import numpy as np  # noqa: E402

import lamp.env  # noqa: E402


def push_action(obs) -> np.ndarray:
    """Every robot straight at the active object's position (the common frame's origin)."""
    d = -obs["robots"].astype(float)
    return d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]


def run_gym(env, steps: int, mode: str, rng) -> float:
    obs, _ = env.reset(seed=0)
    randoms = rng.uniform(-1, 1, (steps, *env.action_space.shape)).astype(np.float32)
    t = time.perf_counter()
    for i in range(steps):
        a = randoms[i] if mode == "random" else push_action(obs)
        obs, _, term, trunc, _ = env.step(a)
        if term or trunc:
            obs, _ = env.reset()
    return steps / (time.perf_counter() - t)


def run_parallel(env, steps: int, mode: str, rng) -> float:
    obs, _ = env.reset(seed=0)
    agents = list(env.possible_agents)
    randoms = rng.uniform(-1, 1, (steps, len(agents), 2))
    t = time.perf_counter()
    for i in range(steps):
        if mode == "random":
            acts = {a: randoms[i, k] for k, a in enumerate(agents)}
        else:
            acts = {}
            for a in agents:
                d = -obs[a]["self"].astype(float)
                acts[a] = d / max(float(np.hypot(*d)), 1e-9)
        obs, _, terms, truncs, _ = env.step(acts)
        if any(terms.values()) or any(truncs.values()):
            obs, _ = env.reset()
    return steps / (time.perf_counter() - t)


def fmt(xs) -> str:
    xs = np.asarray(xs)
    return f"median {np.median(xs):7.0f}  (min {xs.min():.0f}, max {xs.max():.0f})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--scenes", nargs="+",
                    default=["random-01", "maze-01", "tilt-01", "warehouse-01"])
    args = ap.parse_args()
    print(f"env steps per second, one core, {args.steps} steps x {args.repeats} repeats")
    for name in args.scenes:
        raw = lamp.env.PushEnv(name)
        made = gymnasium.make(lamp.env.ENV_ID, scene=name)
        par = lamp.env.parallel_env(name)
        print(f"{name}: {raw.core.n_robots} robots, {len(raw.scene.obstacles)} obstacles, "
              f"{raw.core.period * 1000:.0f} ms per step")
        for mode in ("random", "push"):
            for label, env, fn in (("gym raw", raw, run_gym), ("gym make", made, run_gym),
                                   ("pettingzoo", par, run_parallel)):
                fn(env, 200, mode, np.random.default_rng(0))  # warm-up
                rates = [fn(env, args.steps, mode, np.random.default_rng(r))
                         for r in range(args.repeats)]
                print(f"  {mode:6s} {label:10s} {fmt(rates)}")


if __name__ == "__main__":
    main()
