"""Held-out evaluation of a mid-level policy: ``lamp rl eval`` and the training curve.

``evaluate(policy, task, episodes, seed)`` runs ``episodes`` episodes of the mid-level
task (``lamp.rl.tasks``: ``open`` or ``maps``, full robot scatter) drawn with ``seed``,
and reports the share that reached the subgoal and the mean final distance to it.

Episodes run side by side in ``TeamVecEnv`` (``SIMS`` simulations, one batched policy
call per step); simulation e runs a fixed quota of episodes and only its first ``quota``
count, so the set of episodes, and the result, depends on (task, episodes, seed) only,
not on which episodes end first. The episodes are drawn on the benchmark scenes (the
paper families' 100 suite scenes, ``suite_scenes``), which training never sees: it trains
on maps of the same generators drawn apart from them (``lamp.rl.maps``). Scenes whose
``robots.speed`` is not the policy's are refused (ValueError naming the scene).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lamp.rl.tasks import FAMILIES, check_speed, mid_level_config, task_stage

#: Simulations stepped side by side.
SIMS = 10
#: The default evaluation seed (training uses seeds below it).
EVAL_SEED = 10_000


@dataclass(frozen=True)
class EvalResult:
    """What ``evaluate`` measured."""

    task: str
    episodes: int
    seed: int
    success_rate: float
    mean_distance: float  # final object-to-subgoal distance [m], mean over episodes
    mean_time: float  # simulated seconds per episode, mean


def suite_scenes(suites=FAMILIES):
    """The benchmark scenes of ``suites`` (where evaluation episodes are drawn)."""
    from lamp.suites.registry import resolve_scene, suite_files

    return [resolve_scene(p.stem) for s in suites for p in suite_files(s)]


def policy_config(policy):
    """The mid-level ``PushConfig`` with the policy's own speed, time, control and patch
    settings."""
    env = policy.info.env_settings
    keep = {k: env[k] for k in ("max_speed", "time_limit", "patch_size", "patch_spacing",
                                "patch_range") if k in env}
    return mid_level_config(frame_skip=int(env.get("frame_skip", 10)), **keep)


def evaluate(policy, task: str = "open", episodes: int = 100, seed: int = EVAL_SEED,
             scenes=None) -> EvalResult:
    """See the module docstring; ``policy`` is a per-robot ``PushPolicy``."""
    from lamp.rl.agents import LAYOUT
    from lamp.rl.vec import TeamVecEnv

    if policy.info.layout != LAYOUT:
        raise ValueError(f"evaluate: a {policy.info.layout!r} policy; only {LAYOUT!r} "
                         "policies are evaluated here")
    if not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes = {episodes!r}: must be an integer >= 1")
    sims = min(SIMS, episodes)
    quota = [episodes // sims + (e < episodes % sims) for e in range(sims)]
    scenes = scenes or suite_scenes()
    config = policy_config(policy)
    check_speed(scenes, config.max_speed, "evaluate")
    env = TeamVecEnv(scenes, sims, seed, config, stage=task_stage(task))
    obs = env.reset()
    done = [0] * sims
    kept: list[dict[str, float]] = []
    while sum(done) < episodes:
        before = len(env.finished)
        obs, _, _, _ = env.step(policy.act_rows(obs))
        for rec in env.finished[before:]:
            e = int(rec["sim"])
            if done[e] < quota[e]:
                done[e] += 1
                kept.append(rec)
    return EvalResult(
        task, episodes, seed,
        success_rate=float(np.mean([r["success"] for r in kept])),
        mean_distance=float(np.mean([r["distance"] for r in kept])),
        mean_time=float(np.mean([r["time"] for r in kept])),
    )
