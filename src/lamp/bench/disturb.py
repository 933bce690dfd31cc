"""``lamp bench --disturb PRESET``: the disturbances of each job of a robustness sweep.

The presets are ``lamp.contract.disturb.PRESETS`` plus ``one-robot-fails``: one robot,
drawn per scene and seed, stops for good at a time drawn from the first half of the run's
expected duration, ``FAILURE_HORIZON`` times the straight-line distance of the scene's
objects at the robots' speed (measured: LAMP-Lazy's runs on the paper suites last 4-8
times that, so the failure falls in the first half of nearly every run). Deterministic for
the scene and seed.
"""

from __future__ import annotations

import zlib

import numpy as np

from lamp.contract.disturb import PRESETS, Disturbances
from lamp.scene.model import Scene

__all__ = ["DISTURB_PRESETS", "FAILURE_HORIZON", "disturbances_for"]

#: Expected run duration per second of straight-line object travel at the robots' speed.
FAILURE_HORIZON = 6.0
DISTURB_PRESETS = (*PRESETS, "one-robot-fails")


def disturbances_for(preset: str, scene: Scene, seed: int) -> Disturbances:
    """The disturbances of preset ``preset`` for one job (``ValueError`` for another name)."""
    if preset in PRESETS:
        return PRESETS[preset]
    if preset != "one-robot-fails":
        raise ValueError(f"unknown disturbance preset {preset!r}; expected one of: "
                         f"{', '.join(DISTURB_PRESETS)}")
    rng = np.random.default_rng([zlib.crc32(scene.name.encode()), int(seed)])
    travel = float(np.sum(np.hypot(*(scene.object_goals()[:, :2]
                                     - scene.object_starts()[:, :2]).T)))
    horizon = FAILURE_HORIZON * travel / scene.physics.robot_speed
    robot = int(rng.integers(scene.n_robots))
    return Disturbances(robot_failures=((robot, float(rng.uniform(0.0, 0.5 * horizon))),))
