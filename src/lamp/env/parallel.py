"""PettingZoo parallel environment over the pushing task: one agent per robot.

>>> import lamp.env
>>> env = lamp.env.parallel_env(scene="maze-07")
>>> obs, infos = env.reset(seed=0)
>>> obs, rewards, terms, truncs, infos = env.step(
...     {a: env.action_space(a).sample() for a in env.agents})

Agents are ``robot_0 .. robot_{N-1}`` (robot i of the scene). Every agent's action is
Box(-1, 1, (2,)), its robot's velocity command in units of ``max_speed``. Its observation
is the centralised one seen from that robot, float32: ``self`` (2,) its own centre,
``others`` (N-1, 2) the other robots' centres in index order, ``object``, ``goal``,
``extent`` as in ``lamp/Push-v0``, and ``patch`` (P, P) its own occupancy patch. The team
shares one reward (the Gymnasium environment's), and all agents terminate or are truncated
together, after which ``agents`` is empty.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from lamp.env.core import PushConfig
from lamp.env.gym_env import common_bounds, make_core, reset_kwargs
from lamp.scene.model import Scene


class PushParallelEnv(ParallelEnv):
    """One agent per robot; see the module docstring.

    ``reset(options=...)`` takes the keys of ``lamp/Push-v0``; other keys are ignored
    (PettingZoo's API test passes placeholder options).
    """

    metadata = {"name": "lamp_push_v0", "render_modes": ["rgb_array"], "render_fps": 50,
                "is_parallelizable": True}

    def __init__(
        self,
        scene: Scene | str | Path,
        render_mode: str | None = None,
        config: PushConfig | None = None,
        **settings: Any,
    ) -> None:
        self.core = make_core(scene, render_mode, self.metadata["render_modes"], config,
                              settings)
        self.render_mode = render_mode
        n = self.core.n_robots
        self.possible_agents = [f"robot_{i}" for i in range(n)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._others = {a: np.array([j for j in range(n) if j != i], np.intp)
                        for a, i in self._index.items()}
        p = self.core.config.patch_size
        b = common_bounds(self.core.scene)
        self._obs_space = spaces.Dict(
            {
                "self": spaces.Box(-b, b, (2,), np.float32),
                "others": spaces.Box(-b, b, (n - 1, 2), np.float32),
                "object": spaces.Box(-1.0, 1.0, (2,), np.float32),
                "goal": spaces.Box(
                    np.array([-b, -b, -1, -1], np.float32), np.array([b, b, 1, 1], np.float32)
                ),
                "extent": spaces.Box(0.0, b, (2,), np.float32),
                "patch": spaces.Box(0.0, 1.0, (p, p), np.float32),
            }
        )
        self._act_spaces = {a: spaces.Box(-1.0, 1.0, (2,), np.float32)
                            for a in self.possible_agents}
        self._renderer = None

    def observation_space(self, agent: str) -> spaces.Dict:
        self._check_agent(agent)
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Box:
        self._check_agent(agent)
        return self._act_spaces[agent]

    def _check_agent(self, agent: str) -> None:
        if agent not in self._index:
            raise ValueError(f"unknown agent {agent!r}; agents: {', '.join(self.possible_agents)}")

    def _observations(self) -> dict[str, dict[str, np.ndarray]]:
        o = self.core.observe()
        rob = o["robots"]
        shared = {"object": o["object"], "goal": o["goal"], "extent": o["extent"]}
        out = {}
        for a in self.agents:
            i = self._index[a]
            out[a] = {"self": rob[i], "others": rob[self._others[a]], **shared,
                      "patch": o["patch"][i]}
        return out

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None):
        """As ``lamp/Push-v0``'s reset; ``seed`` seeds the action spaces' samplers only."""
        if seed is not None:
            for k, a in enumerate(self.possible_agents):
                self._act_spaces[a].seed(seed + k)
        self.core.reset(**reset_kwargs(options, strict=False))
        self.agents = list(self.possible_agents)
        info = self.core.info()
        return self._observations(), {a: dict(info) for a in self.agents}

    def step(self, actions: dict[str, Any]):
        """All live agents must act; a missing, unknown or non-finite action is a ValueError
        naming the agent."""
        if not self.agents:
            raise ValueError("step: the episode is over; call reset first")
        if not isinstance(actions, dict):
            raise ValueError(f"actions must be a dict agent -> (vx, vy), got {actions!r}")
        unknown = sorted(set(actions) - set(self.agents))
        if unknown:
            raise ValueError(f"actions for unknown or finished agent(s): {unknown}")
        joint = np.zeros((self.core.n_robots, 2))
        for a in self.agents:
            if a not in actions:
                raise ValueError(f"no action for agent {a!r}")
            one = np.asarray(actions[a], dtype=float) if not isinstance(actions[a], str) else None
            if one is None or one.shape != (2,):
                raise ValueError(f"actions[{a!r}] = {actions[a]!r}: must be a (vx, vy) pair")
            if not np.isfinite(one).all():
                raise ValueError(f"actions[{a!r}] = {one.tolist()} is not finite")
            joint[self._index[a]] = one
        out = self.core.step(joint)
        obs = self._observations()
        live = list(self.agents)
        rewards = dict.fromkeys(live, out.reward)
        terms = dict.fromkeys(live, out.terminated)
        truncs = dict.fromkeys(live, out.truncated)
        infos = {a: dict(out.info) for a in live}
        if out.terminated or out.truncated:
            self.agents = []
        return obs, rewards, terms, truncs, infos

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            from lamp.env.render import FrameRenderer

            self._renderer = FrameRenderer(self.core.scene)
        return self._renderer.frame_of(self.core)

    def close(self) -> None:
        self._renderer = None


def parallel_env(scene: Scene | str | Path, render_mode: str | None = None,
                 config: PushConfig | None = None, **settings: Any) -> PushParallelEnv:
    """The PettingZoo parallel environment of ``scene`` (see ``PushParallelEnv``)."""
    return PushParallelEnv(scene, render_mode=render_mode, config=config, **settings)
