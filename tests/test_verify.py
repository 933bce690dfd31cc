"""Verify's batched proposal check against a direct, one-proposal-at-a-time reference."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.contract.trajectory import MAX_STEP, densify
from lamp.geometry import se2
from lamp.geometry.shapes import signed_distance
from lamp.manip import GeometricProposer
from lamp.planners.collide import pairwise_min_distance, usable_mask
from lamp.planners.config import PlannerConfig
from lamp.planners.task import ManipulationTask
from lamp.suites.registry import suite_scenes

SCENE = suite_scenes("maze")[3]  # cluttered: many proposals collide somewhere
TASK = ManipulationTask(SCENE, 0, SCENE.object_starts(),
                        GeometricProposer(), PlannerConfig(), seed=0)
W, H = SCENE.workspace

def collide(task: ManipulationTask, q_from: np.ndarray, pushes_local: np.ndarray) -> bool:
    """Alg. 1's ``Collide`` for one proposal, checked in the world frame at ``q_from``."""
    r = task.robot_radius
    if np.any(signed_distance(task.shape, pushes_local[:, 0]) < r - task.config.verify.contact_tolerance):
        return True
    dense = densify(se2.transform_points(q_from, pushes_local), MAX_STEP / 2)
    if not np.all(task.static_space.is_free(dense.reshape(-1, 2))):
        return True
    return pairwise_min_distance(dense) < 2 * r - 1e-9


motions = st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-0.5, 0.5))


@settings(max_examples=40, deadline=None)
@given(x=st.floats(0.0, W), y=st.floats(0.0, H), theta=st.floats(-np.pi, np.pi),
       motion=motions, budget=st.integers(1, 3), attempt=st.integers(0, 2))
def test_usable_mask_matches_collide(x, y, theta, motion, budget, attempt) -> None:
    q_from = np.array([x, y, theta])
    cands = TASK.verifier.proposals.push_candidates(np.array(motion), budget, attempt)
    mask = usable_mask(TASK, q_from, cands)
    direct = np.array([not collide(TASK, q_from, p) for p in cands.pushes_local])
    assert mask.tolist() == direct.tolist()


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 4), st.integers(1, 6), st.integers(0, 2**31 - 1))
def test_pairwise_min_distance_matches_brute_force(b, t, seed) -> None:
    paths = np.random.default_rng(seed).uniform(-1, 1, (b, t, 2))
    brute = min((np.linalg.norm(paths[i, k] - paths[j, k])
                 for i in range(b) for j in range(i + 1, b) for k in range(t)), default=np.inf)
    assert np.isclose(pairwise_min_distance(paths), brute)


def test_a_closed_task_is_freed_by_reference_counting_alone() -> None:
    """``ManipulationTask.close`` breaks the task <-> Verifier cycle: with the garbage
    collector off, a closed task that was used (its caches filled) is freed as soon as
    its last name goes; an unclosed one is not."""
    import gc
    import weakref

    def used_task(close: bool) -> weakref.ref:
        task = ManipulationTask(SCENE, 0, SCENE.object_starts(), GeometricProposer(),
                                PlannerConfig(), seed=0)
        q = np.asarray(SCENE.object_starts()[0], float)
        task.robot_space_at(q, task.window(q))  # fills the robot-space cache
        ref = weakref.ref(task)
        if close:
            task.close()
        return ref

    gc.collect()
    gc.disable()
    try:
        assert used_task(close=True)() is None
        assert used_task(close=False)() is not None  # the cycle holds it
    finally:
        gc.enable()
        gc.collect()
