"""Training the mid-level pushing policy with PPO (stable-baselines3) on ``lamp/Push-v0``.

The mid-level task is what the MAPush-style high level asks of it (``lamp.baselines.mapush``):
push the object to a subgoal ``SUBGOAL_AHEAD`` metres further along its obstacle-aware
object path, within ``SUBGOAL_TOLERANCE`` (orientation ignored), in ``SUBGOAL_TIME``
simulated seconds. Every episode is randomised (``SubgoalSampler``): a benchmark map
(the built-in suites' scenes), a pose along the object's lattice path from its start to
its goal, the subgoal further along that path, and the robots scattered around the object
in free space. Everything is seeded: a run is reproducible from its seed (same machine,
same library versions).

``train(...)`` writes ``OUT/policy.pt`` + ``policy.json`` (see ``lamp.rl.policy``) and
``OUT/curve.json`` (success rate on fixed held-out episodes against training steps).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from lamp.env.core import PushConfig, resolve_scene
from lamp.env.gym_env import PushEnv
from lamp.geometry.robot_space import RobotSpace
from lamp.scene.model import Scene

#: Distance along the object path from the object to its subgoal [m] (high and mid level).
SUBGOAL_AHEAD = 0.5
#: The mid level's success radius around a subgoal [m].
SUBGOAL_TOLERANCE = 0.15
#: Simulated time the mid level gets per subgoal [s].
SUBGOAL_TIME = 8.0
#: Robots start at most this far from the object's bounding circle [m] (suite scenes place
#: them up to about 0.6 m away; later subgoals find them right at the object).
ROBOT_SCATTER = 0.8
#: Training families (the paper's suites).
TRAIN_SUITES = ("random", "maze", "tilt", "warehouse")


def mid_level_config() -> PushConfig:
    """The environment settings of the mid-level task."""
    return PushConfig(position_tolerance=SUBGOAL_TOLERANCE, orientation_tolerance=None,
                      time_limit=SUBGOAL_TIME, frame="goal")


def along(path: np.ndarray) -> np.ndarray:
    """Cumulative translation length along a (P, 3) pose path."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path[:, :2], axis=0).T))])


def pose_at(path: np.ndarray, s: float) -> np.ndarray:
    """The path pose at arc length ``s`` (clamped to the path; poses are not interpolated
    across headings: the next lattice pose at or after ``s``)."""
    acc = along(path)
    return path[min(int(np.searchsorted(acc, s)), len(path) - 1)].copy()


def scatter_robots(scene: Scene, poses: np.ndarray, index: int, rng: np.random.Generator,
                   near: float = ROBOT_SCATTER, tries: int = 400) -> np.ndarray | None:
    """Robot centres in free space within ``near`` of object ``index``'s bounding circle,
    not overlapping each other; None when no placement was found."""
    space = RobotSpace.from_scene(scene, object_poses=poses, robot_radius=scene.robot_radius)
    r = scene.robot_radius
    c = poses[index, :2]
    bound = scene.objects[index].shape.bounding_radius
    out: list[np.ndarray] = []
    for _ in range(tries):
        ang = rng.uniform(-math.pi, math.pi)
        dist = bound + r + rng.uniform(0.01, near)
        p = c + dist * np.array([math.cos(ang), math.sin(ang)])
        if not space.is_free(p[None])[0]:
            continue
        if any(np.hypot(*(p - q)) < 2 * r + 0.01 for q in out):
            continue
        out.append(p)
        if len(out) == scene.n_robots:
            return np.array(out)
    return None


class SubgoalSampler:
    """Random mid-level episodes over the maps of ``scenes`` (names or Scenes)."""

    def __init__(self, scenes: list[Scene | str], seed: int) -> None:
        self.scenes = [resolve_scene(s) for s in scenes]
        if not self.scenes:
            raise ValueError("SubgoalSampler: no scenes")
        self.rng = np.random.default_rng(seed)
        self._paths: dict[int, np.ndarray | None] = {}

    def path(self, k: int) -> np.ndarray | None:
        """Object 0's lattice path from its start to its goal in scene k (cached)."""
        if k not in self._paths:
            from lamp.search.gco_lattice import gco_object_path

            sc = self.scenes[k]
            p = gco_object_path(sc, 0, sc.objects[0].start, inflation=0.0, time_limit=5.0)
            self._paths[k] = None if p is None or len(p) < 2 else np.asarray(p, float)
        return self._paths[k]

    def sample(self) -> tuple[int, dict[str, Any]]:
        """(scene index, reset options) of one episode."""
        for _ in range(1000):
            k = int(self.rng.integers(len(self.scenes)))
            path = self.path(k)
            if path is None:
                continue
            total = along(path)[-1]
            s = self.rng.uniform(0.0, max(total - 0.1, 0.0))
            pose = pose_at(path, s)
            goal = pose_at(path, s + SUBGOAL_AHEAD)
            if math.hypot(*(goal[:2] - pose[:2])) <= SUBGOAL_TOLERANCE:
                continue
            scene = self.scenes[k]
            poses = scene.object_starts()
            poses[0] = pose
            robots = scatter_robots(scene, poses, 0, self.rng)
            if robots is None:
                continue
            return k, {"object_poses": poses, "robot_positions": robots, "goal": goal}
        raise RuntimeError("SubgoalSampler: no episode found in 1000 tries")


class SubgoalEnv(gym.Env):
    """The mid-level task as one Gymnasium environment with a flat observation (what PPO
    trains on): every reset draws an episode from a ``SubgoalSampler``."""

    metadata = {"render_modes": []}

    def __init__(self, scenes: list[Scene | str], seed: int) -> None:
        self.sampler = SubgoalSampler(scenes, seed)
        self.envs: dict[int, PushEnv] = {}
        first = self._env(0)
        n = first.core.n_robots
        for sc in self.sampler.scenes:
            if sc.n_robots != n:
                raise ValueError(f"scene {sc.name}: {sc.n_robots} robots, the others have {n}")
        self.dict_space = first.observation_space
        self.observation_space = spaces.flatten_space(self.dict_space)
        self.action_space = first.action_space
        self.current = first

    def _env(self, k: int) -> PushEnv:
        if k not in self.envs:
            self.envs[k] = PushEnv(self.sampler.scenes[k], config=mid_level_config())
        return self.envs[k]

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        k, opts = self.sampler.sample()
        self.current = self._env(k)
        obs, info = self.current.reset(options=opts)
        return spaces.flatten(self.dict_space, obs), info

    def step(self, action):
        obs, r, term, trunc, info = self.current.step(action)
        return spaces.flatten(self.dict_space, obs), r, term, trunc, info


@dataclass(frozen=True)
class TrainSettings:
    """One training run (``lamp rl train`` options)."""

    steps: int = 1_000_000
    seed: int = 0
    eval_every: int = 50_000
    eval_episodes: int = 40
    hidden: tuple[int, ...] = (64, 64)
    threads: int = 1
    rollout: int = 2048  # PPO steps per update (n_steps)

    def __post_init__(self) -> None:
        for name in ("steps", "eval_every", "eval_episodes", "threads", "rollout"):
            v = getattr(self, name)
            if not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} = {v!r}: must be an integer >= 1")


def evaluate(policy_fn, env: SubgoalEnv, episodes: int) -> float:
    """Success rate of ``policy_fn(flat_obs) -> action`` on ``episodes`` episodes of ``env``."""
    wins = 0
    for _ in range(episodes):
        obs, _ = env.reset()
        while True:
            obs, _, term, trunc, info = env.step(policy_fn(obs))
            if term or trunc:
                wins += bool(info["is_success"])
                break
    return wins / episodes


def export_actor(model, info_kwargs: dict[str, Any]):
    """The deterministic actor of an SB3 PPO ``model`` as a ``PushPolicy``."""
    import torch

    from lamp.rl.policy import PolicyInfo, PushPolicy

    linears = [m for m in model.policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)]
    linears.append(model.policy.action_net)
    layers = [(m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
              for m in linears]
    return PushPolicy(layers, PolicyInfo(**info_kwargs))


def info_kwargs(env: SubgoalEnv, settings: TrainSettings, training: dict[str, Any]):
    """``PolicyInfo`` fields of a policy trained on ``env``."""
    cfg = mid_level_config()
    return {
        "n_robots": env.current.core.n_robots, "obs_dim": int(env.observation_space.shape[0]),
        "hidden": tuple(settings.hidden),
        "env_settings": {"position_tolerance": cfg.position_tolerance,
                         "orientation_tolerance": cfg.orientation_tolerance,
                         "time_limit": cfg.time_limit, "frame_skip": cfg.frame_skip,
                         "max_speed": cfg.max_speed, "patch_size": cfg.patch_size,
                         "patch_spacing": cfg.patch_spacing, "patch_range": cfg.patch_range,
                         "frame": cfg.frame},
        "training": training,
    }


def train(out: str | Path, settings: TrainSettings, scenes: list[str] | None = None,
          progress=None) -> dict[str, Any]:
    """Train, evaluate along the way and write the policy and curve into ``out``; returns
    the curve record. ``progress(step, success_rate)`` is called after each evaluation."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    from lamp.io import write_json_atomic
    from lamp.suites.registry import suite_files

    torch.set_num_threads(settings.threads)
    names = scenes or [p.stem for s in TRAIN_SUITES for p in suite_files(s)]
    env = SubgoalEnv(names, seed=settings.seed)
    eval_env = SubgoalEnv(names, seed=settings.seed + 10_000)
    model = PPO("MlpPolicy", env, seed=settings.seed, device="cpu", n_steps=settings.rollout,
                batch_size=min(256, settings.rollout), learning_rate=3e-4, gamma=0.99, ent_coef=0.0,
                policy_kwargs={"net_arch": list(settings.hidden)}, verbose=0)
    curve: list[dict[str, float]] = []
    t0 = time.perf_counter()

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)

    def run_eval(step: int) -> None:
        actor = export_actor(model, info_kwargs(env, settings, {}))
        # the same held-out episodes every time
        eval_env.sampler.rng = np.random.default_rng(settings.seed + 10_000)
        rate = evaluate(actor.act_flat, eval_env, settings.eval_episodes)
        curve.append({"steps": step, "success_rate": rate,
                      "wall_s": round(time.perf_counter() - t0, 1)})
        # an interrupted run still leaves its latest policy and curve
        actor.save(out / "policy.pt")
        write_json_atomic(out / "curve.json", {"steps": step, "seed": settings.seed,
                                               "partial": True, "curve": curve})
        if progress is not None:
            progress(step, rate)

    class Every(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.next = settings.eval_every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                run_eval(self.num_timesteps)
                self.next += settings.eval_every
            return True

    run_eval(0)
    model.learn(total_timesteps=settings.steps, callback=Every())
    if not curve or curve[-1]["steps"] != model.num_timesteps:
        run_eval(model.num_timesteps)
    wall = time.perf_counter() - t0
    record = {
        "steps": int(model.num_timesteps), "seed": settings.seed, "wall_s": round(wall, 1),
        "threads": settings.threads, "scenes": len(names), "curve": curve,
        "subgoal_ahead": SUBGOAL_AHEAD, "subgoal_tolerance": SUBGOAL_TOLERANCE,
        "subgoal_time": SUBGOAL_TIME,
    }
    policy = export_actor(model, info_kwargs(
        env, settings, {k: v for k, v in record.items() if k != "curve"}))
    policy.save(out / "policy.pt")
    write_json_atomic(out / "curve.json", record)
    return record
