"""Many mid-level episodes stepped together, one slot per robot (parameter sharing).

``TeamVecEnv`` is a stable-baselines3 ``VecEnv`` whose slots are robots: ``n_sims``
simulations of the mid-level task (``lamp.rl.tasks``) with N robots each give
``n_sims * N`` slots, slot ``e * N + i`` being robot i of simulation e. PPO then trains
one actor that every robot shares, on every robot's experience (MAPush's MAPPO setting),
and one batched forward pass serves all simulations, which is what makes training fast
on a CPU. Each robot's observation is its row of ``lamp.rl.agents.agent_rows``; every
robot of a simulation receives the team's reward; a simulation that ends (success,
object outside the workspace, time) starts its next episode at once, as SB3 expects
(the last observation in ``infos[slot]["terminal_observation"]``,
``"TimeLimit.truncated"`` set on a time-out).

The episodes' difficulty follows ``curriculum`` by the share of ``total_steps`` done,
counted in robot-steps: a count, so a run is reproducible from its seed.
Simulation e draws from its own share of the scenes (round robin), so each scene's
MuJoCo model lives in one simulation only.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env import VecEnv

from lamp.env.core import PushConfig, PushCore
from lamp.rl.agents import agent_dim, agent_rows
from lamp.rl.tasks import Curriculum, EpisodeSampler, Stage
from lamp.scene.model import Scene

#: Bound on every per-robot observation value (metres and unit vectors; the paper maps
#: are at most a few metres across).
OBS_BOUND = 50.0


class TeamVecEnv(VecEnv):
    """See the module docstring. ``stage`` (optional) fixes the difficulty instead."""

    def __init__(self, scenes: list[Scene], n_sims: int, seed: int, config: PushConfig,
                 curriculum: Curriculum | None = None, total_steps: int = 1,
                 stage: Stage | None = None) -> None:
        if n_sims < 1:
            raise ValueError(f"n_sims = {n_sims!r}: must be >= 1")
        n = {s.n_robots for s in scenes}
        if len(n) != 1:
            raise ValueError(f"scenes have different numbers of robots: {sorted(n)}")
        self.n_robots = n.pop()
        self.config = config
        self.curriculum = curriculum or Curriculum()
        self.total_steps = max(int(total_steps), 1)
        self.fixed = stage
        self.robot_steps = 0
        self.samplers = [
            EpisodeSampler(scenes[e % len(scenes)::n_sims] or scenes, seed=seed * 7919 + e)
            for e in range(n_sims)
        ]
        self.cores: list[dict[str, PushCore]] = [{} for _ in range(n_sims)]
        self.current: list[PushCore] = []
        self.finished: list[dict[str, float]] = []  # one record per finished episode
        dim = agent_dim(self.n_robots, config.patch_size)
        self.render_mode = None  # nothing to draw (SB3 asks)
        obs_space = spaces.Box(-OBS_BOUND, OBS_BOUND, (dim,), np.float32)
        super().__init__(n_sims * self.n_robots, obs_space,
                         spaces.Box(-1.0, 1.0, (2,), np.float32))
        self._actions = np.zeros((self.num_envs, 2), np.float32)

    # ----------------------------------------------------------------- episodes
    def stage(self) -> Stage:
        if self.fixed is not None:
            return self.fixed
        return self.curriculum.stage(self.robot_steps / self.total_steps)

    def _start(self, e: int) -> np.ndarray:
        scene, opts = self.samplers[e].sample(self.stage())
        core = self.cores[e].get(scene.name)
        if core is None:
            core = self.cores[e][scene.name] = PushCore(scene, self.config)
        core.reset(**opts)
        self.current[e] = core
        return agent_rows(core.observe())

    def reset(self) -> np.ndarray:
        self.current = [None] * len(self.samplers)  # type: ignore[list-item]
        return np.concatenate([self._start(e) for e in range(len(self.samplers))])

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, np.float32).reshape(self.num_envs, 2)

    def step_wait(self):
        n = self.n_robots
        obs = np.empty((self.num_envs, self.observation_space.shape[0]), np.float32)
        rewards = np.empty(self.num_envs, np.float32)
        dones = np.zeros(self.num_envs, bool)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for e, core in enumerate(self.current):
            sl = slice(e * n, (e + 1) * n)
            out = core.step(self._actions[sl])
            rows = agent_rows(core.observe())
            rewards[sl] = out.reward
            if out.terminated or out.truncated:
                dones[sl] = True
                self.finished.append({"sim": e, "success": float(out.info["is_success"]),
                                      "distance": float(out.info["position_error"]),
                                      "time": float(out.info["sim_time"])})
                for i in range(n):
                    infos[e * n + i] = {"terminal_observation": rows[i],
                                        "TimeLimit.truncated": bool(out.truncated),
                                        "is_success": bool(out.info["is_success"])}
                rows = self._start(e)
            obs[sl] = rows
        self.robot_steps += self.num_envs
        return obs, rewards, dones, infos

    # ------------------------------------------------------------ VecEnv plumbing
    def close(self) -> None:
        self.cores = [{} for _ in self.samplers]

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(self, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *args, indices=None, **kwargs) -> list[Any]:
        raise NotImplementedError(f"TeamVecEnv has no per-slot method {method_name!r}")

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)
