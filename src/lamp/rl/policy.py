"""The shared mid-level pushing policy: an MLP actor exported from a PPO run.

A policy file is a pair: ``NAME.pt`` holds only tensors (the actor's weights, read with
``torch.load(weights_only=True)``, so loading runs no pickled code) and ``NAME.json`` its
description (layer sizes, the environment settings it was trained with, the number of
robots, the training run's figures, the input ``layout``). Two layouts:

* ``"team"`` (the first policies): one actor maps the flattened ``lamp/Push-v0``
  observation (``gymnasium.spaces.flatten`` of its Dict space) to all robots' commands;
* ``"per-robot"`` (``lamp.rl.agents``): one actor, shared by every robot, maps each
  robot's own row to that robot's command.

Either way the layers are Linear + Tanh and acting is deterministic (the mean action,
clipped to [-1, 1]).
"""

from __future__ import annotations

import json
import pickle
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import torch
from gymnasium import spaces

from lamp.rl.agents import LAYOUT as AGENT_LAYOUT
from lamp.rl.agents import agent_dim, agent_rows

#: The shipped policy (``lamp rl train`` writes the same pair of files).
DEFAULT_POLICY = Path(str(resources.files("lamp.rl") / "checkpoints" / "mapush_policy.pt"))
#: Input layouts (see the module docstring).
LAYOUTS = ("team", AGENT_LAYOUT)


@dataclass(frozen=True)
class PolicyInfo:
    """The description stored beside the weights."""

    n_robots: int
    obs_dim: int
    hidden: tuple[int, ...]
    env_settings: dict[str, Any]
    training: dict[str, Any]
    layout: str = "team"

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise ValueError(f"layout = {self.layout!r}: must be one of {', '.join(LAYOUTS)}")


class PushPolicy:
    """Deterministic actor: flattened observation -> (N, 2) velocity commands in [-1, 1]."""

    def __init__(self, layers: list[tuple[np.ndarray, np.ndarray]], info: PolicyInfo) -> None:
        self.info = info
        mods: list[torch.nn.Module] = []
        for k, (w, b) in enumerate(layers):
            lin = torch.nn.Linear(w.shape[1], w.shape[0])
            with torch.no_grad():
                lin.weight.copy_(torch.as_tensor(w))
                lin.bias.copy_(torch.as_tensor(b))
            mods.append(lin)
            if k < len(layers) - 1:
                mods.append(torch.nn.Tanh())
        self.net = torch.nn.Sequential(*mods).eval()
        if layers[0][0].shape[1] != info.obs_dim:
            raise ValueError(
                f"policy: first layer takes {layers[0][0].shape[1]} inputs, the description "
                f"says obs_dim = {info.obs_dim}"
            )

    @property
    def robot_speed(self) -> float:
        """The robots' speed the policy was trained for [m/s]: the speed of a full-scale
        command (``env_settings["max_speed"]``; ``PushConfig``'s 0.5 when not recorded)."""
        return float(self.info.env_settings.get("max_speed", 0.5))

    @property
    def subgoal_time(self) -> float:
        """Simulated seconds per subgoal the policy was trained with (its episodes'
        ``time_limit``)."""
        return float(self.info.env_settings.get("time_limit", 8.0))

    def check_env(self, n_robots: int, obs_space: spaces.Dict, what: str) -> None:
        """ValueError naming ``what`` when the environment does not fit the policy."""
        if n_robots != self.info.n_robots:
            raise ValueError(
                f"{what}: has {n_robots} robots, but the policy was trained for "
                f"{self.info.n_robots}"
            )
        if self.info.layout == AGENT_LAYOUT:
            dim = agent_dim(n_robots, int(obs_space["patch"].shape[-1]))
        else:
            dim = spaces.flatdim(obs_space)
        if dim != self.info.obs_dim:
            raise ValueError(
                f"{what}: observation has {dim} values, the policy takes {self.info.obs_dim} "
                "(different patch settings)"
            )

    def act(self, obs_space: spaces.Dict, obs: dict[str, np.ndarray]) -> np.ndarray:
        """(N, 2) commands for one centralised observation."""
        if self.info.layout == AGENT_LAYOUT:
            return self.act_rows(agent_rows(obs))
        return self.act_flat(spaces.flatten(obs_space, obs))

    def act_rows(self, rows: np.ndarray) -> np.ndarray:
        """(M, 2) commands of a per-robot policy for M per-robot rows (any robots, any
        simulations: the actor is shared)."""
        x = torch.as_tensor(np.asarray(rows, np.float32))
        with torch.no_grad():
            a = self.net(x).numpy()
        return np.clip(a, -1.0, 1.0)

    def act_flat(self, flat_obs: np.ndarray) -> np.ndarray:
        """(N, 2) commands for one flattened observation."""
        x = torch.as_tensor(np.asarray(flat_obs, np.float32))[None]
        with torch.no_grad():
            a = self.net(x)[0].numpy()
        return np.clip(a, -1.0, 1.0).reshape(self.info.n_robots, 2)

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> None:
        """Write ``path`` (.pt, tensors only) and its ``.json`` description atomically."""
        from lamp.io import atomic_output, write_json_atomic

        path = Path(path)
        tensors = {}
        for k, m in enumerate(m for m in self.net if isinstance(m, torch.nn.Linear)):
            tensors[f"layer{k}.weight"] = m.weight.detach().clone()
            tensors[f"layer{k}.bias"] = m.bias.detach().clone()
        with atomic_output(path) as tmp:
            torch.save(tensors, tmp)
        info = self.info
        write_json_atomic(path.with_suffix(".json"), {
            "format": "lamp-push-policy/1", "n_robots": info.n_robots, "obs_dim": info.obs_dim,
            "hidden": list(info.hidden), "env_settings": info.env_settings,
            "training": info.training, "layout": info.layout,
        })


def load_policy(path: str | Path | None = None) -> PushPolicy:
    """Read a policy (default: the shipped one); ValueError naming the file when it is
    missing or malformed. Weights are read with ``weights_only=True``."""
    path = Path(DEFAULT_POLICY if path is None else path)
    meta_path = path.with_suffix(".json")
    for p in (path, meta_path):
        if not p.is_file():
            raise ValueError(f"{p}: policy file not found")
    try:
        meta = json.loads(meta_path.read_text())
        if meta.get("format") != "lamp-push-policy/1":
            raise ValueError(f"format is {meta.get('format')!r}, expected 'lamp-push-policy/1'")
        tensors = torch.load(path, map_location="cpu", weights_only=True)
        n_layers = len(meta["hidden"]) + 1
        layers = [
            (tensors[f"layer{k}.weight"].numpy(), tensors[f"layer{k}.bias"].numpy())
            for k in range(n_layers)
        ]
        info = PolicyInfo(int(meta["n_robots"]), int(meta["obs_dim"]),
                          tuple(int(h) for h in meta["hidden"]), dict(meta["env_settings"]),
                          dict(meta.get("training", {})), str(meta.get("layout", "team")))
        return PushPolicy(layers, info)
    except (KeyError, TypeError, ValueError, RuntimeError, EOFError, OSError,
            pickle.UnpicklingError) as exc:
        raise ValueError(f"{path}: not a valid policy: {exc}") from None
