"""The ``ObjectPlanner`` contract, run against every registered closed-loop planner.

On a small scene with the geometric model: ``plan`` returns a ``Plan`` with a status;
its transitions chain (each starts at the object pose and robots the previous one ends
at, the first at the state asked for); every robot path, approach and push, passes the
independent checker of ``tests/mrmp_checker.py`` (steps of at most 2 cm, clearance from
obstacles and the workspace border, robot-robot distance); ``report_failure`` followed by
``plan`` works; ``clear`` makes the next plan the one a fresh planner gives.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from mrmp_checker import check_plan

from lamp.contract.plan import Plan, PlanStatus
from lamp.contract.trajectory import MAX_STEP
from lamp.contract.transition import Transition
from lamp.pipeline import registry
from lamp.planners.config import PlannerConfig
from lamp.planners.task import ManipulationTask
from lamp.scene import scene_from_dict

CLOSED_LOOP = [s.name for s in registry.specs() if s.closed_loop]

SCENE = {
    "format": "lamp-scene/1", "name": "contract", "workspace": [2.2, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
    "obstacles": [{"type": "circle", "center": [1.5, 0.45], "radius": 0.12}],
    "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                 "goal": [1.25, 1.0, 0.0]}],
}


@pytest.fixture(scope="module")
def proposer():
    from lamp.manip import GeometricProposer

    return GeometricProposer()


def make_task(proposer, seed: int = 0) -> ManipulationTask:
    scene = scene_from_dict(SCENE)
    poses = np.array([o.start for o in scene.objects], float)
    return ManipulationTask(scene, 0, poses, proposer, PlannerConfig(), seed=seed)


class _Without:
    """The scene with the pushed object left out (robots touch it while pushing)."""

    def __init__(self, scene, index: int) -> None:
        self.d = scene.to_dict()
        self.d["objects"] = [o for k, o in enumerate(self.d["objects"]) if k != index]

    def to_dict(self) -> dict:
        return self.d


def _check_paths(scene, paths: np.ndarray, object_poses) -> None:
    """``paths`` (N, T, 2) as a plan from its first to its last row, through the checker."""
    paths = np.asarray(paths, float)
    while paths.shape[1] > 1 and np.array_equal(paths[:, -1], paths[:, -2]):
        paths = paths[:, :-1]  # holding rows at the end are no motion
    n = paths.shape[0]
    plan = SimpleNamespace(paths=paths, goal_of=np.arange(n), success=True, reason="")
    check_plan(scene, paths[:, 0], paths[:, -1], plan, object_poses=object_poses,
               max_spacing=MAX_STEP, require_success=True)


def check_contract(task: ManipulationTask, plan: Plan, q_O: np.ndarray, q_R: np.ndarray) -> None:
    assert isinstance(plan, Plan) and isinstance(plan.status, PlanStatus)
    assert plan.solved == bool(plan.transitions)
    q, robots = np.asarray(q_O, float), np.asarray(q_R, float)
    for i, t in enumerate(plan.transitions):
        assert isinstance(t, Transition)
        # the first transition may start on the lattice node the object sits on
        tol = 1e-3 if i == 0 else 1e-9
        assert np.allclose(t.q_from, q, atol=tol, rtol=0), (i, t.q_from, q)
        assert np.allclose(t.robot_start, robots, atol=1e-9, rtol=0), (i, t.robot_start, robots)
        assert np.array_equal(t.move[:, -1], t.manip[:, 0])
        _check_paths(task.scene, t.move, task.poses_with(t.q_from))
        _check_paths(_Without(task.scene, task.index), t.manip, None)
        q, robots = t.q_to, t.robot_end


def _same(a: Plan, b: Plan) -> bool:
    if a.status is not b.status or len(a.transitions) != len(b.transitions):
        return False
    return all(np.array_equal(x.q_to, y.q_to) and np.array_equal(x.robot_paths, y.robot_paths)
               for x, y in zip(a.transitions, b.transitions, strict=True))


@pytest.mark.parametrize("name", CLOSED_LOOP)
def test_planner_contract(name, proposer):
    spec = registry.get(name)
    task = make_task(proposer)
    q_O, q_R = task.object_poses[task.index].copy(), task.scene.robot_starts_array.copy()
    planner = spec.factory(task)
    first = planner.plan(q_O, q_R)
    check_contract(task, first, q_O, q_R)
    assert first.solved, (name, first.status)  # every planner can make this short move

    planner.report_failure(first.transitions[0])
    again = planner.plan(q_O, q_R)
    check_contract(task, again, q_O, q_R)

    # from the state the first transition leads to (a replan after one executed segment)
    t0 = first.transitions[0]
    later = planner.plan(t0.q_to, t0.robot_end)
    check_contract(task, later, t0.q_to, t0.robot_end)

    planner.clear()
    cleared = planner.plan(q_O, q_R)
    fresh = spec.factory(make_task(proposer)).plan(q_O, q_R)
    check_contract(task, cleared, q_O, q_R)
    assert _same(cleared, fresh), name


def test_every_closed_loop_planner_is_covered():
    assert set(CLOSED_LOOP) >= {"lazy", "astar", "astar-replan", "gco-ori", "gco-var"}


def test_the_contract_check_catches_a_broken_chain(proposer):
    """The checks above can fail: a plan whose second transition starts elsewhere does."""
    task = make_task(proposer)
    q_O, q_R = task.object_poses[task.index].copy(), task.scene.robot_starts_array.copy()
    plan = registry.get("lazy").factory(task).plan(q_O, q_R)
    assert len(plan.transitions) >= 2
    t = plan.transitions[1]
    moved = Transition(t.q_from + np.array([0.05, 0.0, 0.0]), t.q_to, t.contacts,
                       t.pushes_local, t.move, t.manip, t.edge)
    broken = Plan(PlanStatus.SOLVED, [plan.transitions[0], moved, *plan.transitions[2:]])
    with pytest.raises(AssertionError):
        check_contract(task, broken, q_O, q_R)
    first = plan.transitions[0]
    jumpy = first.move[:, ::3]  # every third row: steps of up to 6 cm
    assert np.hypot(*np.diff(jumpy, axis=1).transpose(2, 0, 1)).max() > MAX_STEP
    with pytest.raises(AssertionError, match="step"):
        _check_paths(task.scene, jumpy, task.poses_with(first.q_from))
    through = first.move.copy()
    through[0, 1:-1] = SCENE["obstacles"][0]["center"]  # robot 0 jumps into the obstacle
    with pytest.raises(AssertionError):
        _check_paths(task.scene, through, task.poses_with(first.q_from))
