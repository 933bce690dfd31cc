"""Reinforcement-learning environments over the project's scenes and MuJoCo simulator.

Importing this package registers the Gymnasium environment ``lamp/Push-v0``:

>>> import gymnasium, lamp.env
>>> env = gymnasium.make("lamp/Push-v0", scene="maze-07")   # or a scene file path

and ``lamp.env.parallel_env(scene=...)`` builds the PettingZoo parallel environment (one
agent per robot). Both run ``lamp.env.core.PushCore``; see ``docs/env.md``.
"""

from __future__ import annotations

import gymnasium

from lamp.env.core import PushConfig, PushCore, RewardWeights, resolve_scene
from lamp.env.gym_env import PushEnv
from lamp.env.parallel import PushParallelEnv, parallel_env

#: The registered Gymnasium id.
ENV_ID = "lamp/Push-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="lamp.env.gym_env:PushEnv")

__all__ = [
    "ENV_ID",
    "PushConfig",
    "PushCore",
    "PushEnv",
    "PushParallelEnv",
    "RewardWeights",
    "parallel_env",
    "resolve_scene",
]
