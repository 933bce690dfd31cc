"""Training throughput of the mid-level policy (issue: "training throughput first").

One core (``OMP_NUM_THREADS=1``, one torch thread). Three figures per configuration,
median over ``--repeats``:

* ``env``: environment steps per second under random commands (episodes that end are
  reset; the reset counts), in simulation steps and in simulated seconds per second;
* ``train``: PPO's steps per second (``model.learn``: rollouts and updates), counted as
  SB3 counts them (per slot) and in simulated seconds per second.

Configurations:

* ``before``: what the first policies trained with: one ``lamp/Push-v0`` environment
  (goal frame, 20 ms steps, flattened centralised observation), PPO with 2048-step
  rollouts;
* ``now``: ``lamp.rl.vec.TeamVecEnv`` with ``--sims`` simulations, one slot per robot,
  50 ms steps, per-robot observations, the settings of ``lamp rl train``.

Scenes: the paper suites' maps (their object paths are computed once before timing).

Run: ``python benchmarks/bench_rl.py [--steps 30000] [--repeats 3] [--sims 1 4 16]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

_PATHS: dict[str, object] = {}


def _vec(sims: int, scenes):
    from lamp.rl.tasks import Curriculum, EpisodeSampler, mid_level_config
    from lamp.rl.vec import TeamVecEnv

    if not _PATHS:  # object paths once, outside the timing
        every = EpisodeSampler(scenes, 0)
        _PATHS.update({sc.name: every.path(k) for k, sc in enumerate(scenes)})
    env = TeamVecEnv(scenes, sims, 0, mid_level_config(), Curriculum(), total_steps=10**9)
    for s in env.samplers:
        s._paths = {k: _PATHS[sc.name] for k, sc in enumerate(s.scenes)}
    return env


def env_rate(env, steps: int) -> float:
    """Simulation steps per second under random commands."""
    rng = np.random.default_rng(0)
    env.reset()
    n_sims = env.num_envs // env.n_robots
    calls = max(1, steps // n_sims)
    acts = rng.uniform(-1, 1, (calls, env.num_envs, 2)).astype(np.float32)
    t = time.perf_counter()
    for a in acts:
        env.step(a)
    return calls * n_sims / (time.perf_counter() - t)


def train_rate_now(sims: int, scenes, steps: int) -> float:
    """PPO steps (per robot slot) per second with ``lamp rl train``'s settings."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import Logger

    from lamp.rl.train import TrainSettings

    s = TrainSettings()
    env = _vec(sims, scenes)
    rollout = max(16, min(s.rollout, steps // env.num_envs))
    model = PPO("MlpPolicy", env, seed=0, device="cpu", n_steps=rollout,
                batch_size=rollout * env.num_envs // 6, n_epochs=s.epochs,
                policy_kwargs={"net_arch": list(s.hidden)})
    t = time.perf_counter()
    model.set_logger(Logger(None, []))  # no SB3-<date> log folder
    model.learn(total_timesteps=steps)
    return model.num_timesteps / (time.perf_counter() - t)


def _before_env(scenes):
    import gymnasium as gym

    from lamp.env import PushEnv
    from lamp.rl.tasks import SUBGOAL_TIME, SUBGOAL_TOLERANCE

    env = PushEnv(scenes[0], frame="goal", frame_skip=10, time_limit=SUBGOAL_TIME,
                  position_tolerance=SUBGOAL_TOLERANCE, orientation_tolerance=None)
    return gym.wrappers.FlattenObservation(env)


def train_rate_before(scenes, steps: int) -> float:
    from stable_baselines3 import PPO
    from stable_baselines3.common.logger import Logger

    env = _before_env(scenes)
    model = PPO("MlpPolicy", env, seed=0, device="cpu", n_steps=min(2048, steps),
                batch_size=256, policy_kwargs={"net_arch": [64, 64]})
    t = time.perf_counter()
    model.set_logger(Logger(None, []))  # no SB3-<date> log folder
    model.learn(total_timesteps=steps)
    return model.num_timesteps / (time.perf_counter() - t)


def env_rate_before(scenes, steps: int) -> float:
    env = _before_env(scenes)
    rng = np.random.default_rng(0)
    env.reset()
    t = time.perf_counter()
    for _ in range(steps):
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, (3, 2)))
        if term or trunc:
            env.reset()
    return steps / (time.perf_counter() - t)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=30000, help="steps per measurement")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sims", type=int, nargs="+", default=[1, 4, 16])
    args = ap.parse_args()
    torch.set_num_threads(1)
    from lamp.rl.evaluate import suite_scenes

    scenes = suite_scenes()
    med = statistics.median
    rows = []
    e = med(env_rate_before(scenes, args.steps // 3) for _ in range(args.repeats))
    tr = med(train_rate_before(scenes, args.steps // 3) for _ in range(args.repeats))
    rows.append(("before: 1 env, 20 ms steps", e, e * 0.02, tr, tr * 0.02))
    for sims in args.sims:
        env = _vec(sims, scenes)
        e = med(env_rate(env, args.steps // 3) for _ in range(args.repeats))
        tr = med(train_rate_now(sims, scenes, args.steps) for _ in range(args.repeats))
        # SB3 counts robot slots: simulation steps are tr / 3
        rows.append((f"now: {sims} sims x 3 robots, 50 ms steps", e, e * 0.05, tr, tr / 3 * 0.05))
    print(f"{'configuration':<38} {'env sim-steps/s':>15} {'env sim-s/s':>11} "
          f"{'PPO steps/s':>11} {'PPO sim-s/s':>11}")
    for name, e, es, tr, ts in rows:
        print(f"{name:<38} {e:>15.0f} {es:>11.1f} {tr:>11.0f} {ts:>11.1f}")


if __name__ == "__main__":
    main()
