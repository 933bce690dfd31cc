"""Recovery pushes: a pinned object gets one verified short motion to a free pose."""

from __future__ import annotations

import numpy as np
import pytest

from lamp.geometry import se2
from lamp.planners.config import PlannerConfig
from lamp.planners.lazy import LazyPlanner
from lamp.planners.recovery import RECOVERY_MOTIONS, is_recovery_motion, recovery_push
from lamp.planners.task import ManipulationTask
from lamp.scene.loader import scene_from_dict

WALL = {"type": "rectangle", "center": [1.0, 1.95], "size": [2.0, 0.1], "angle": 0.0}


@pytest.fixture(scope="module")
def task():
    from lamp.manip import GeometricProposer

    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "pinned", "workspace": [2.0, 2.0],
        "robots": {"radius": 0.05, "starts": [[0.3, 0.3], [0.6, 0.3], [0.9, 0.3]]},
        "obstacles": [WALL],
        "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [1.0, 1.0, 0.0],
                     "goal": [1.5, 0.6, 0.0]}]})
    return ManipulationTask(scene, 0, scene.object_starts(), GeometricProposer(),
                            PlannerConfig(), seed=0)


#: pressed 5 mm into the wall (its top edge at y = 1.905, the wall's bottom at 1.9)
PINNED = np.array([1.0, 1.805, 0.0])


def test_recovery_frees_a_pinned_box(task):
    lattice = LazyPlanner.from_task(task).lattice
    assert not task.object_space.pose_free(PINNED)
    calls = task.stats.verify_calls
    trans = recovery_push(lattice, task.verifier, PINNED, task.scene.robot_starts_array)
    assert trans is not None
    assert np.allclose(trans.q_from, PINNED)
    assert task.object_space.pose_free(trans.q_to)
    assert is_recovery_motion(trans.q_from, trans.q_to)
    assert task.stats.verify_calls > calls  # the verifier accepted it
    # it moved away from the wall: the end pose has more clearance than the start
    assert task.object_space.clearance(trans.q_to) > task.object_space.clearance(PINNED)


def test_recovery_motions_are_in_the_model_range():
    m = np.array(RECOVERY_MOTIONS)
    assert len(m) == len({tuple(r) for r in m.tolist()}) and not (m == 0).all(axis=1).any()
    assert np.abs(m[:, :2]).max() <= 0.2 and np.abs(m[:, 2]).max() <= 0.5
    q = np.array([0.3, -0.2, 2.0])
    assert is_recovery_motion(q, se2.compose(q, m[7]))
    assert not is_recovery_motion(q, se2.compose(q, np.array([0.03, 0.0, 0.0])))


def test_lazy_returns_a_partial_plan_when_the_object_is_pinned(task):
    """2.5 cm into the wall: beyond the start connections' tolerance, so the full search
    cannot even start; the planner answers with one recovery push instead of failing."""
    deep = np.array([1.0, 1.825, 0.0])
    planner = LazyPlanner.from_task(task)
    plan = planner.plan(deep, task.scene.robot_starts_array)
    assert plan.solved and plan.partial
    assert len(plan.transitions) == 1 and planner.recoveries == 1
    assert is_recovery_motion(deep, plan.transitions[0].q_to)
    assert task.object_space.pose_free(plan.transitions[0].q_to)
