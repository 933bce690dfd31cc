"""``lamp/Push-v0``: the Gymnasium environment, centralised control of all robots.

>>> import gymnasium, lamp.env
>>> env = gymnasium.make("lamp/Push-v0", scene="maze-07")
>>> obs, info = env.reset(seed=0)
>>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Spaces (N robots, P = ``patch_size``), all float32; the task, reward and termination are
described in ``lamp.env.core`` and ``docs/env.md``:

- action: Box(-1, 1, (N, 2)), velocity command of every robot in units of ``max_speed``;
- observation: Dict(robots (N, 2), object (2,), goal (4,), extent (2,), patch (N, P, P)),
  see ``PushCore.observe``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from lamp.env.core import PushConfig, PushCore
from lamp.scene.model import Scene

#: Keys ``reset(options=...)`` accepts.
RESET_OPTIONS = ("object_poses", "robot_positions", "goal", "object")


def reset_kwargs(options: dict[str, Any] | None, strict: bool = True) -> dict[str, Any]:
    """``PushCore.reset`` arguments from reset options; unknown keys are a ValueError
    listing the valid ones (or dropped, with ``strict=False``)."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise ValueError(f"options must be a dict, got {options!r}")
    unknown = sorted(set(options) - set(RESET_OPTIONS))
    if unknown and strict:
        raise ValueError(
            f"unknown reset option(s) {', '.join(map(repr, unknown))}; "
            f"valid: {', '.join(RESET_OPTIONS)}"
        )
    out = {k: options[k] for k in RESET_OPTIONS if k in options}
    if "object" in out:
        out["active"] = out.pop("object")
    return out


def make_config(config: PushConfig | None, overrides: dict[str, Any]) -> PushConfig:
    """``config`` (default ``PushConfig()``) with keyword ``overrides`` applied."""
    from dataclasses import fields, replace

    base = config if config is not None else PushConfig()
    valid = {f.name for f in fields(PushConfig)}
    unknown = sorted(set(overrides) - valid)
    if unknown:
        raise ValueError(
            f"unknown environment setting(s) {', '.join(map(repr, unknown))}; "
            f"valid: {', '.join(sorted(valid))}"
        )
    return replace(base, **overrides)


def make_core(scene: Scene | str | Path, render_mode: str | None, render_modes: list[str],
              config: PushConfig | None, overrides: dict[str, Any]) -> PushCore:
    """The shared task behind both environments, after checking ``render_mode``."""
    if render_mode is not None and render_mode not in render_modes:
        raise ValueError(f"render_mode = {render_mode!r}: must be None or one of {render_modes}")
    return PushCore(scene, make_config(config, overrides))


def common_bounds(scene: Scene) -> float:
    """Bound on any coordinate in the common frame (workspace diagonal plus a margin)."""
    return float(math.hypot(*scene.workspace)) + 1.0


def observation_space(core: PushCore) -> spaces.Dict:
    """The centralised observation space of ``core`` (see ``PushCore.observe``)."""
    n, p = core.n_robots, core.config.patch_size
    b = common_bounds(core.scene)
    return spaces.Dict(
        {
            "robots": spaces.Box(-b, b, (n, 2), np.float32),
            "object": spaces.Box(-1.0, 1.0, (2,), np.float32),
            "goal": spaces.Box(
                np.array([-b, -b, -1, -1], np.float32), np.array([b, b, 1, 1], np.float32)
            ),
            "extent": spaces.Box(0.0, b, (2,), np.float32),
            "patch": spaces.Box(0.0, 1.0, (n, p, p), np.float32),
        }
    )


class PushEnv(gym.Env):
    """Push the scene's objects to their goals with all robots (see the module docstring).

    Args:
        scene: a ``Scene``, a scene file path or a built-in scene name (``"maze-07"``).
        render_mode: None or ``"rgb_array"``.
        config: a ``PushConfig``; keyword arguments override its fields.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

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
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.core.period)}
        self.action_space = spaces.Box(-1.0, 1.0, (self.core.n_robots, 2), np.float32)
        self.observation_space = observation_space(self.core)
        self._renderer = None

    @property
    def scene(self) -> Scene:
        return self.core.scene

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Objects and robots at rest at the scene's starts (or ``options``: object_poses
        (K, 3), robot_positions (N, 2), goal (3,) for the first object, object: index of
        the first object to push). Nothing here is random: ``seed`` only seeds
        ``self.np_random`` and the spaces' samplers."""
        super().reset(seed=seed)
        if seed is not None:
            self.action_space.seed(seed)
        self.core.reset(**reset_kwargs(options))
        return self.core.observe(), self.core.info()

    def step(self, action):
        out = self.core.step(action)
        return self.core.observe(), out.reward, out.terminated, out.truncated, out.info

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            from lamp.env.render import FrameRenderer

            self._renderer = FrameRenderer(self.core.scene)
        return self._renderer.frame_of(self.core)
