"""Gspi's result does not depend on the clock when its counts end the search.

The steps run in compiled chunks whose length follows the measured time per step; the
stall count is still applied at the exact step (a chunk never runs past the step where a
stall would be declared), so a fast clock (simulated load) gives the same plan.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.mrmp import plan_paths
from lamp.mrmp.gspi import GspiStatus
from lamp.scene.model import Obstacle, Rectangle, Scene


def _corridor() -> Scene:
    """A single lane along y = 0.25: robots cannot pass each other."""
    walls = (Obstacle(Rectangle((2.0, 0.19)), (1.0, 0.095, 0.0)),
             Obstacle(Rectangle((2.0, 0.19)), (1.0, 0.5 - 0.095, 0.0)))
    return Scene("corridor", (2.0, 0.5), ((0.1, 0.1),), (), walls, 0.05)


def _deadlock(stall_steps: int):
    scene = _corridor()
    S = np.array([[0.3, 0.25], [1.0, 0.25]])
    return plan_paths(scene, S, S[::-1].copy(), goal_swapping=False, initial_goal_of=[0, 1],
                      lattice_step=0.05, time_limit=1e6, stall_steps=stall_steps,
                      max_steps=100_000)


@settings(max_examples=15, deadline=None)
@given(stall_steps=st.integers(1, 400), factor=st.floats(2.0, 5000.0))
def test_stall_is_declared_at_the_same_step_under_load(stall_steps, factor):
    calm = _deadlock(stall_steps)
    assert calm.status is GspiStatus.STALLED
    real = time.perf_counter
    t0 = real()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(time, "perf_counter", lambda: t0 + (real() - t0) * factor)
        busy = _deadlock(stall_steps)
    assert busy.status is GspiStatus.STALLED
    assert busy.iterations == calm.iterations
    assert np.array_equal(busy.paths, calm.paths)


@settings(max_examples=10, deadline=None)
@given(k=st.integers(40, 300), more=st.integers(1, 300))
def test_stall_count_is_exact(k, more):
    """Past the last improvement, the search runs exactly ``stall_steps`` + 1 steps: a
    longer stall count runs that many more steps on the same deadlock."""
    a, b = _deadlock(k), _deadlock(k + more)
    assert b.iterations - a.iterations == more
