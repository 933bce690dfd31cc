"""``lamp bench --disturb PRESET``: the disturbances of each job of a robustness sweep.

The presets are ``lamp.contract.disturb.PRESETS`` plus ``one-robot-fails``: one robot,
drawn per scene and seed, stops for good during the first motion in which it moves, at a
fraction of that motion drawn from ``FAILURE_FRACTION`` (``Disturbances.working_failures``).
So the failure fires in every run in which that robot works at all, whatever the schedule
and however long the run; the result says when (``disturbances.robot_failures_fired``),
and a run in which it did not fire counts as not disturbed. Deterministic for the scene and
seed.
"""

from __future__ import annotations

import zlib

import numpy as np

from lamp.contract.disturb import PRESETS, Disturbances
from lamp.scene.model import Scene

__all__ = ["DISTURB_PRESETS", "FAILURE_FRACTION", "disturbances_for"]

#: Where in its first motion the failing robot stops: a fraction drawn from this range.
FAILURE_FRACTION = (0.1, 0.9)
DISTURB_PRESETS = (*PRESETS, "one-robot-fails")


def disturbances_for(preset: str, scene: Scene, seed: int) -> Disturbances:
    """The disturbances of preset ``preset`` for one job (``ValueError`` for another name)."""
    if preset in PRESETS:
        return PRESETS[preset]
    if preset != "one-robot-fails":
        raise ValueError(f"unknown disturbance preset {preset!r}; expected one of: "
                         f"{', '.join(DISTURB_PRESETS)}")
    rng = np.random.default_rng([zlib.crc32(scene.name.encode()), int(seed)])
    robot = int(rng.integers(scene.n_robots))
    return Disturbances(working_failures=((robot, float(rng.uniform(*FAILURE_FRACTION))),))
