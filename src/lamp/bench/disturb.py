"""``lamp bench --disturb PRESET``: the disturbances of each job of a robustness sweep.

The presets are ``lamp.contract.disturb.PRESETS`` plus ``one-robot-fails``: one robot,
drawn per scene and seed, stops for good at a time drawn from ``FAILURE_FRACTION`` of the
earliest time at which any object of the scene could be placed (the least of the objects'
own bounds in ``lamp.scene.bounds``: the nearest robot's drive to touch it plus its
straight-line travel, at the robots' speed). No run places an object before that time, so
the failure fires in every run that places one, at the same time for every planner; the
result says when (``disturbances.robot_failures_fired``), and a run that ended before it
counts as not disturbed. Deterministic for the scene and seed.
"""

from __future__ import annotations

import zlib

import numpy as np

from lamp.contract.disturb import PRESETS, Disturbances
from lamp.scene.bounds import makespan_lower_bound
from lamp.scene.model import Scene

__all__ = ["DISTURB_PRESETS", "FAILURE_FRACTION", "disturbances_for"]

#: When the failing robot stops: this fraction (drawn) of the earliest possible placement.
FAILURE_FRACTION = (0.2, 0.8)
DISTURB_PRESETS = (*PRESETS, "one-robot-fails")


def disturbances_for(preset: str, scene: Scene, seed: int) -> Disturbances:
    """The disturbances of preset ``preset`` for one job (``ValueError`` for another name)."""
    if preset in PRESETS:
        return PRESETS[preset]
    if preset != "one-robot-fails":
        raise ValueError(f"unknown disturbance preset {preset!r}; expected one of: "
                         f"{', '.join(DISTURB_PRESETS)}")
    rng = np.random.default_rng([zlib.crc32(scene.name.encode()), int(seed)])
    # the straight-line bound: the preset's failure times stay those of its published runs
    earliest = min(makespan_lower_bound(scene, straight_line=True).per_object)
    robot = int(rng.integers(scene.n_robots))
    when = float(rng.uniform(*FAILURE_FRACTION)) * earliest
    return Disturbances(robot_failures=((robot, when),))
