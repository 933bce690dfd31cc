"""LAMP-Lazy takes again the pushes Verify found earlier in the same ``plan`` call
(``lamp.planners.lazy``, departure at Alg. 2 line 19): the plan is the paper's, edge for
edge and robot position for robot position, and it makes Verify calls only for what it
has not asked before.

The reference below is Alg. 2's ``Plan`` (lines 10-24) as printed, on a planner with an
empty Tree_eval (a first call, so lines 25-40 never run), with the same D* Lite, lattice
and penalties. Verify is a deterministic stand-in whose answers (and failures) are a
function of the edge, its attempt and the robots' start, drawn by Hypothesis.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lamp.contract.transition import Transition
from lamp.planners.config import PlannerConfig
from lamp.planners.lazy import LazyPlanner, join_lattice
from lamp.planners.task import ManipulationTask
from lamp.planners.task_stats import TaskStats
from lamp.scene import scene_from_dict

SCENE = {
    "format": "lamp-scene/1", "name": "reuse", "workspace": [2.4, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "rectangle", "center": [1.3, 0.75], "size": [0.1, 0.9]}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.8, 1.0, 0.0],
                 "goal": [1.8, 0.55, 1.5708]}],
}
#: Budgets no test reaches: the two planners must end on their paths, not on counts.
CONFIG = PlannerConfig.of(max_verify_calls=10**6, max_plan_iterations=300)


class FakeVerify:
    """Verify as a pure function of (edge, attempt, robots' start): it fails with
    probability ``p`` (a hash of the arguments and ``salt``), else returns a push whose
    robots end halfway to the object's new position. Every call is logged."""

    def __init__(self, p: float, salt: int) -> None:
        self.p, self.salt = p, salt
        self.stats = TaskStats()
        self.calls: list[tuple[bytes, bytes, int, bytes]] = []

    def verify(self, q_from, q_to, q_R, attempt=0):
        self.stats.verify_calls += 1
        q_from, q_to, q_R = (np.asarray(a, float) for a in (q_from, q_to, q_R))
        key = (q_from.tobytes(), q_to.tobytes(), int(attempt), q_R.tobytes())
        self.calls.append(key)
        digest = hashlib.sha256(repr((self.salt, key)).encode()).digest()
        if int.from_bytes(digest[:8], "little") / 2.0**64 < self.p:
            return None
        end = 0.5 * q_R + 0.5 * q_to[:2]
        return Transition(q_from, q_to, np.zeros((0, 2)), np.zeros((0, 2, 2)),
                          q_R[:, None, :].copy(), np.stack([q_R, end], axis=1))


def paper_plan(planner: LazyPlanner, q_O: np.ndarray, q_R0: np.ndarray):
    """Alg. 2 lines 10-24 on an empty Tree_eval: the edges and robot ends of the plan,
    or None when the iterations run out or no path is left."""
    lattice, failures = planner.lattice, {}
    for _ in range(CONFIG.lazy.max_plan_iterations):
        start, edges = join_lattice(lattice, q_O)
        path = planner.dstar.plan_shortest_path(start, edges)  # line 11
        if not path:
            return None
        plan, q_R = [], np.asarray(q_R0, float)
        for curr, nxt in zip(path, path[1:], strict=False):  # line 13
            attempt = failures.get((curr, nxt), 0)
            trans = planner.verifier.verify(lattice.pose(curr), lattice.pose(nxt), q_R,
                                            attempt)  # line 16
            if trans is None:  # lines 17-20: UpdateChange, discard, break
                failures[(curr, nxt)] = attempt + 1
                planner.dstar.penalize(curr, nxt, CONFIG.lazy.edge_penalty)
                plan = None
                break
            plan.append(((curr, nxt), trans.robot_end))
            q_R = trans.robot_end  # line 24
        if plan is not None:
            return plan
    return None


def _planner(task: ManipulationTask, fake: FakeVerify) -> LazyPlanner:
    planner = LazyPlanner.from_task(task)
    planner.verifier = fake  # type: ignore[assignment]
    return planner


@pytest.fixture(scope="module")
def task():
    from lamp.manip import GeometricProposer

    scene = scene_from_dict(SCENE)
    poses = np.array([o.start for o in scene.objects], float)
    return ManipulationTask(scene, 0, poses, GeometricProposer(), CONFIG, seed=0)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.function_scoped_fixture])
@given(p=st.floats(0.0, 0.3), salt=st.integers(0, 2**31))
def test_lazy_plan_is_the_papers_with_no_verify_asked_twice(task, p, salt):
    q_O, q_R = task.object_poses[0], task.scene.robot_starts_array
    ours_fake, paper_fake = FakeVerify(p, salt), FakeVerify(p, salt)
    ours = _planner(task, ours_fake).plan(q_O, q_R)
    ref = paper_plan(_planner(task, paper_fake), q_O, q_R)
    assert ours.solved == (ref is not None)
    if ref is not None:
        assert [t.edge for t in ours.transitions] == [e for e, _ in ref]
        for t, (_, end) in zip(ours.transitions, ref, strict=True):
            assert np.array_equal(t.robot_end, end)
    # never the same question twice in one call; each answer not asked again is counted
    assert len(set(ours_fake.calls)) == len(ours_fake.calls)
    assert set(ours_fake.calls) <= set(paper_fake.calls)
    assert ours_fake.stats.verify_reused == len(paper_fake.calls) - len(ours_fake.calls)
