"""Training the mid-level pushing policy with PPO (stable-baselines3).

One actor, shared by every robot (``lamp.rl.agents``), trained on every robot's experience
in ``TeamVecEnv`` (``n_sims`` simulations of the mid-level task stepped together, one
batched forward pass per step), through the ``Curriculum`` of ``lamp.rl.tasks``: robots
start close to the object in open space, then scatter to the full distance, then half of
the episodes are on the cluttered maps. The reward is ``lamp.env``'s with MAPush's "robots
behind the object" term (``lamp.rl.tasks.MID_REWARD``). The robots drive at
``lamp.rl.tasks.ROBOT_SPEED`` (the scenes' default ``robots.speed``; training scenes at
another speed are refused). Training maps: ``lamp.rl.maps`` (the paper families'
generators on streams apart from the benchmark suites'); the held-out evaluations along
the way run on the benchmark scenes themselves, which training never sees.

``train(out, settings)`` writes ``OUT/policy.pt`` + ``policy.json`` (``lamp.rl.policy``)
and ``OUT/curve.json``: held-out subgoal success (``lamp.rl.evaluate``, both tasks)
against training steps, written after every evaluation, so an interrupted run leaves its
latest policy and curve. Steps are counted as SB3 counts them, per robot (``steps``);
the curve also gives simulation steps and simulated seconds. Everything is seeded and
budgets are counts: a run is reproducible from its seed (same machine and library
versions).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from lamp.rl.evaluate import EVAL_SEED, evaluate, suite_scenes
from lamp.rl.maps import (
    MAPS_PER_FAMILY,
    TRAIN_MAP_SEED,
    check_map_seed,
    maps_record,
    training_maps,
)
from lamp.rl.tasks import (
    MID_REWARD,
    SUBGOAL_AHEAD,
    SUBGOAL_TIME,
    SUBGOAL_TOLERANCE,
    Curriculum,
    check_speed,
    mid_level_config,
)


@dataclass(frozen=True)
class TrainSettings:
    """One training run (``lamp rl train`` options); validated on construction."""

    steps: int = 6_000_000  # robot-steps (SB3's count: simulation steps x robots)
    seed: int = 0
    eval_every: int = 500_000
    eval_episodes: int = 50
    hidden: tuple[int, ...] = (128, 128)
    threads: int = 1
    n_sims: int = 16  # simulations stepped together
    rollout: int = 256  # PPO steps per slot per update (n_steps)
    batch: int = 2048
    epochs: int = 5
    learning_rate: float = 3e-4
    map_seed: int = TRAIN_MAP_SEED  # base seed of the training maps (lamp.rl.maps)
    maps_per_family: int = MAPS_PER_FAMILY

    def __post_init__(self) -> None:
        check_map_seed(self.map_seed, self.maps_per_family)
        for name in ("steps", "eval_every", "eval_episodes", "threads", "n_sims", "rollout",
                     "batch", "epochs"):
            v = getattr(self, name)
            if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                raise ValueError(f"{name} = {v!r}: must be an integer >= 1")
        if not isinstance(self.seed, int) or self.seed < 0 or self.seed >= EVAL_SEED // 8000:
            raise ValueError(f"seed = {self.seed!r}: must be an integer in [0, "
                             f"{EVAL_SEED // 8000}) (higher seeds draw evaluation episodes)")
        if not self.hidden or any(not isinstance(h, int) or h < 1 for h in self.hidden):
            raise ValueError(f"hidden = {self.hidden!r}: must be positive layer sizes")
        if not (0 < self.learning_rate < 1):
            raise ValueError(f"learning_rate = {self.learning_rate!r}: must be in (0, 1)")


def export_actor(model, info_kwargs: dict[str, Any]):
    """The deterministic actor of an SB3 PPO ``model`` as a ``PushPolicy``."""
    import torch

    from lamp.rl.policy import PolicyInfo, PushPolicy

    linears = [m for m in model.policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)]
    linears.append(model.policy.action_net)
    layers = [(m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
              for m in linears]
    return PushPolicy(layers, PolicyInfo(**info_kwargs))


def info_kwargs(n_robots: int, obs_dim: int, config, settings: TrainSettings,
                training: dict[str, Any]) -> dict[str, Any]:
    """``PolicyInfo`` fields of a per-robot policy trained with ``config``."""
    from lamp.rl.agents import LAYOUT

    return {
        "n_robots": n_robots, "obs_dim": obs_dim, "hidden": tuple(settings.hidden),
        "env_settings": {"position_tolerance": config.position_tolerance,
                         "orientation_tolerance": config.orientation_tolerance,
                         "time_limit": config.time_limit, "frame_skip": config.frame_skip,
                         "max_speed": config.max_speed, "patch_size": config.patch_size,
                         "patch_spacing": config.patch_spacing,
                         "patch_range": config.patch_range, "frame": config.frame},
        "training": training, "layout": LAYOUT,
    }


def train(out: str | Path, settings: TrainSettings, scenes=None, progress=None,
          resume: bool = False, eval_scenes=None) -> dict[str, Any]:
    """Train, evaluate along the way and write the policy and curve into ``out``; returns
    the curve record. ``progress(entry)`` is called with every curve entry. ``scenes``:
    the training maps (default: ``lamp.rl.maps.training_maps`` of the settings' map seed);
    ``eval_scenes``: the maps of the held-out evaluations (default: the benchmark scenes).
    ValueError naming the scene when one has another ``robots.speed`` than the task's.

    ``resume``: continue the run in ``out`` from its last evaluation (the PPO state saved
    there, ``ppo.zip``) instead of starting again; its settings must be these, except
    ``steps``, which may grow (the curriculum then follows the new total). The step count
    carries on; the episodes after the resumption are drawn from
    a stream of their own (seeded by the seed and the step count), so a resumed run is
    reproducible but not identical to an uninterrupted one. ValueError naming the file
    when there is nothing to resume or the settings differ."""
    import torch
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.logger import Logger

    from lamp.io import write_json_atomic
    from lamp.rl.vec import TeamVecEnv

    torch.set_num_threads(settings.threads)
    config = mid_level_config()
    maps = None
    if scenes is None:
        scenes = training_maps(settings.map_seed, settings.maps_per_family)
        maps = maps_record(settings.map_seed, settings.maps_per_family)
    eval_scenes = eval_scenes or suite_scenes()
    check_speed(scenes, config.max_speed, "lamp rl train")
    env = TeamVecEnv(scenes, settings.n_sims, settings.seed, config, Curriculum(),
                     total_steps=settings.steps)
    n = env.n_robots
    out = Path(out)
    head = _head(settings, scenes, maps, eval_scenes, n, config)
    curve: list[dict[str, Any]] = []
    if resume:
        curve, model = _resumed(out, head, env)
    else:
        model = _new_ppo(env, settings)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter() - (curve[-1]["wall_s"] if curve else 0.0)
    seen = [0]

    def actor(training: dict[str, Any]):
        return export_actor(model, info_kwargs(n, env.observation_space.shape[0], config,
                                               settings, training))

    def run_eval(step: int) -> None:
        policy = actor({})
        res = {t: evaluate(policy, t, settings.eval_episodes, EVAL_SEED, scenes=eval_scenes)
               for t in ("open", "maps")}
        recent = env.finished[seen[0]:]
        seen[0] = len(env.finished)
        stage = env.stage()
        entry = {"steps": step, "sim_steps": step // n,
                 "sim_s": round(step // n * env.current[0].period, 1),
                 "success_open": res["open"].success_rate,
                 "success_maps": res["maps"].success_rate,
                 "distance_open": round(res["open"].mean_distance, 4),
                 "distance_maps": round(res["maps"].mean_distance, 4),
                 "train_success": (round(sum(r["success"] for r in recent) / len(recent), 4)
                                   if recent else None),
                 "scatter": round(stage.scatter, 3), "maps_share": round(stage.maps_share, 3),
                 "wall_s": round(time.perf_counter() - t0, 1)}
        curve.append(entry)
        policy.save(out / "policy.pt")  # an interrupted run keeps its latest policy
        model.save(out / "ppo.zip")  # ... and can resume from here
        write_json_atomic(out / "curve.json", {**head, "partial": True, "curve": curve})
        if progress is not None:
            progress(entry)

    class Every(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.next = (model.num_timesteps // settings.eval_every + 1) * settings.eval_every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                run_eval(self.num_timesteps)
                self.next += settings.eval_every
            return True

    # no log folder: SB3's default logger makes an empty SB3-<date> folder per run
    model.set_logger(Logger(None, []))
    if model.num_timesteps < settings.steps:
        model.learn(total_timesteps=settings.steps - model.num_timesteps, callback=Every(),
                    reset_num_timesteps=not resume)
    if not curve or curve[-1]["steps"] != model.num_timesteps:
        run_eval(model.num_timesteps)
    wall = time.perf_counter() - t0
    record = {**head, "steps": int(model.num_timesteps), "wall_s": round(wall, 1),
              "curve": curve}
    final = {k: v for k, v in record.items() if k != "curve"}
    actor(final).save(out / "policy.pt")
    write_json_atomic(out / "curve.json", record)
    return record


def _new_ppo(env, settings: TrainSettings):
    """A fresh PPO learner of ``settings`` on ``env`` (the shipped policy's hyperparameters)."""
    from stable_baselines3 import PPO

    return PPO("MlpPolicy", env, seed=settings.seed, device="cpu", n_steps=settings.rollout,
               batch_size=settings.batch, n_epochs=settings.epochs,
               learning_rate=settings.learning_rate, gamma=0.99, gae_lambda=0.95,
               ent_coef=0.0, policy_kwargs={"net_arch": list(settings.hidden)}, verbose=0)


def _head(settings: TrainSettings, scenes, maps: dict[str, Any] | None, eval_scenes,
          n_robots: int, config) -> dict[str, Any]:
    """What a run's curve and policy record about its settings, maps and task."""
    return {"seed": settings.seed,
            "settings": {**asdict(settings), "hidden": list(settings.hidden)},
            "robots": n_robots, "scenes": len(scenes),
            "maps": maps or {"given": sorted(s.name for s in scenes)},
            "eval_maps": _maps_named(eval_scenes), "robot_speed": config.max_speed,
            "subgoal_ahead": SUBGOAL_AHEAD, "subgoal_tolerance": SUBGOAL_TOLERANCE,
            "subgoal_time": SUBGOAL_TIME, "frame_skip": config.frame_skip,
            "reward": MID_REWARD}


def _resumed(out: Path, head: dict[str, Any], env):
    """(curve so far, PPO model) of the run in ``out`` (see ``train``'s ``resume``)."""
    import json

    import numpy as np
    from stable_baselines3 import PPO

    for name in ("curve.json", "ppo.zip"):
        if not (out / name).is_file():
            raise ValueError(f"{out / name}: not found; nothing to resume")
    old = json.loads((out / "curve.json").read_text())
    def same(key: str, value: Any) -> Any:  # the step budget may grow
        if key == "settings" and isinstance(value, dict):
            return {k: v for k, v in value.items() if k != "steps"}
        return value

    for key in ("seed", "settings", "robots", "scenes", "maps", "robot_speed"):
        if same(key, old.get(key)) != same(key, head[key]):
            raise ValueError(f"{out / 'curve.json'}: the run to resume has {key} = "
                             f"{old.get(key)!r}, this one {head[key]!r}")
    model = PPO.load(out / "ppo.zip", env=env, device="cpu")
    env.robot_steps = int(model.num_timesteps)
    for e, sampler in enumerate(env.samplers):
        sampler.rng = np.random.default_rng([head["seed"], e, env.robot_steps])
    return list(old["curve"]), model


def _maps_named(scenes) -> dict[str, Any]:
    """The evaluation maps as a record: the benchmark suites they come from (scene count
    per suite, by name), or their names."""
    from collections import Counter

    from lamp.suites.registry import SUITES

    suites = Counter(s.name.rsplit("-", 1)[0] for s in scenes)
    if set(suites) <= set(SUITES):
        return {"suites": dict(suites), "maps": len(scenes)}
    return {"given": sorted(s.name for s in scenes)}
