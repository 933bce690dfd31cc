"""End-to-end tests of the LAMP planners and baselines on small scenes (geometric proposer)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from lamp import solve
from lamp.cli import app
from lamp.contract.plan import PlanStatus
from lamp.planners.config import PlannerConfig
from lamp.planners.lamp_astar import LampAStar
from lamp.planners.lazy import LazyPlanner
from lamp.planners.task import ManipulationTask
from lamp.scene import scene_from_dict

TIME_KEYS = {"planning_time_s", "total_planning_time_s", "median_planning_time_s", "wall_time_s",
             "executed_planning_time_s", "unexecuted_planning_time_s",
             "planning_time_per_segment_s"}


def small_scene(goal=(1.45, 1.0, 0.0), obstacles=()) -> dict:
    return {
        "format": "lamp-scene/1",
        "name": "small",
        "workspace": [2.2, 2.0],
        "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
        "obstacles": list(obstacles),
        "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                     "goal": list(goal)}],
    }


@pytest.fixture(scope="module")
def proposer():
    from lamp.manip import GeometricProposer

    return GeometricProposer()


def strip_times(d: dict) -> dict:
    d = {k: v for k, v in d.items() if k not in TIME_KEYS}
    d["objects"] = [{k: v for k, v in o.items() if k != "planning_time_s"} for o in d["objects"]]
    return d


def test_lazy_solves_small_scene_end_to_end(proposer):
    scene = scene_from_dict(small_scene())
    result = solve(scene, "lazy", seed=0, model=proposer).to_dict()
    assert result["success"], result
    obj = result["objects"][0]
    assert obj["full_horizon_plan"]
    assert obj["position_error"] <= 0.1 and obj["orientation_error"] <= 0.1
    assert result["segments"] == len(result["planning_time_s"]) >= 1
    assert result["makespan"] > 0


def test_lazy_turns_object_around_a_wall(proposer):
    wall = {"type": "rectangle", "center": [1.2, 0.55], "size": [0.1, 1.1], "angle": 0.0}
    scene = scene_from_dict(small_scene(goal=(1.7, 0.6, 1.5708), obstacles=[wall]))
    result = solve(scene, "lazy", seed=1, model=proposer).to_dict()
    assert result["success"], result


def test_same_seed_same_result(proposer):
    scene = scene_from_dict(small_scene())
    a = strip_times(solve(scene, "lazy", seed=3, model=proposer).to_dict())
    b = strip_times(solve(scene, "lazy", seed=3, model=proposer).to_dict())
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_lazy_replanning_reuses_verified_transitions(proposer):
    """Alg. 2: a second Plan from a state on the verified path needs no new Verify call,
    and one after a small drift needs far fewer than the first plan."""
    scene = scene_from_dict(small_scene())
    task = ManipulationTask(scene, 0, scene.object_starts(), proposer, PlannerConfig(), seed=0)
    planner = LazyPlanner.from_task(task)
    first = planner.plan(scene.object_starts()[0], scene.robot_starts_array)
    assert first.solved and len(first.transitions) >= 3
    calls_first = task.stats.verify_calls
    mid = first.transitions[1]
    again = planner.plan(mid.q_from, mid.robot_start)
    assert again.solved
    assert task.stats.verify_calls == calls_first  # everything came from Tree_eval / D_T
    drifted = mid.q_from + np.array([0.02, -0.03, 0.05])
    replanned = planner.plan(drifted, mid.robot_start)
    assert replanned.solved
    assert task.stats.verify_calls - calls_first < calls_first


def test_astar_solves_short_move(proposer):
    scene = scene_from_dict(small_scene(goal=(1.15, 1.0, 0.0)))
    result = solve(scene, "astar-replan", seed=0, model=proposer, time_limit=120).to_dict()
    assert result["success"], result
    assert result["objects"][0]["full_horizon_plan"]


def test_astar_plans_around_a_wall(proposer):
    """The lattice cost-to-go leads LAMP-A* around the wall instead of into it."""
    wall = {"type": "rectangle", "center": [1.2, 0.55], "size": [0.1, 1.1], "angle": 0.0}
    scene = scene_from_dict(small_scene(goal=(1.7, 0.6, 0.0), obstacles=[wall]))
    poses = scene.object_starts()
    task = ManipulationTask(scene, 0, poses, proposer, PlannerConfig(), seed=0)
    plan = LampAStar.from_task(task).plan(poses[0], scene.robot_starts_array)
    assert plan.solved
    path = plan.object_path
    assert np.allclose(path[-1], scene.objects[0].goal, atol=1e-6)
    assert path[:, 1].max() > 1.1  # over the top of the wall (it ends at y = 1.1)
    assert all(np.allclose(a.q_to, b.q_from) for a, b in zip(plan.transitions[:-1], plan.transitions[1:], strict=True))


def test_astar_gives_up_at_once_without_an_object_route(proposer):
    wall = {"type": "rectangle", "center": [1.2, 1.0], "size": [0.1, 2.0], "angle": 0.0}
    scene = scene_from_dict(small_scene(goal=(1.7, 1.0, 0.0), obstacles=[wall]))
    poses = scene.object_starts()
    task = ManipulationTask(scene, 0, poses, proposer, PlannerConfig(), seed=0)
    assert LampAStar.from_task(task).plan(poses[0], scene.robot_starts_array).status is PlanStatus.NO_PATH
    assert task.stats.verify_calls == 0


@pytest.mark.parametrize("planner", ["gco-var", "gco-ori"])
def test_gco_baselines_run(proposer, planner):
    scene = scene_from_dict(small_scene())
    config = PlannerConfig.of(max_segments=8)
    result = solve(scene, planner, seed=0, model=proposer, config=config).to_dict()
    assert result["planner"] == planner
    assert result["segments"] <= 8
    assert not result["objects"][0]["full_horizon_plan"]


def test_cli_run_rejects_bad_input(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("format: lamp-scene/1\nname: x\n")
    res = CliRunner().invoke(app, ["run", str(bad), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "bad.yaml" in res.output
    good = tmp_path / "good.yaml"
    good.write_text(json.dumps(small_scene()))
    res = CliRunner().invoke(app, ["run", str(good), "--planner", "nope"])
    assert res.exit_code == 2
    assert "nope" in res.output
    assert not (tmp_path / "o").exists()


def test_cli_run_writes_result_json(tmp_path):
    good = tmp_path / "good.yaml"
    good.write_text(json.dumps(small_scene(goal=(1.15, 1.0, 0.0))))
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["run", str(good), "--model", "geometric", "--out", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads((out / "result.json").read_text())
    for key in ("scene", "planner", "seed", "success", "objects", "segments", "planning_time_s",
                "total_planning_time_s", "makespan", "replans", "wall_time_s"):
        assert key in data
    assert data["planner"] == "lazy" and data["scene"] == "small"


@pytest.mark.parametrize("starts", [
    [[0.2, 0.3]],  # one robot: budget 1 only
    [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9], [0.2, 1.2], [0.2, 1.5]],  # five: two must wait
])
def test_lazy_handles_other_team_sizes(proposer, starts):
    d = small_scene(goal=(1.25, 1.0, 0.0))
    d["robots"]["starts"] = starts
    scene = scene_from_dict(d)
    result = solve(scene, "lazy", seed=0, model=proposer).to_dict()
    assert result["success"], result


def test_lazy_forgets_a_cached_push_it_cannot_route_to(proposer):
    """A Tree_eval entry whose re-routing fails is dropped, not only penalised: the next
    plan through that pose verifies the motion again instead of meeting the same push."""
    scene = scene_from_dict(small_scene())
    task = ManipulationTask(scene, 0, scene.object_starts(), proposer, PlannerConfig(), seed=0)
    planner = LazyPlanner.from_task(task)
    first = planner.plan(scene.object_starts()[0], scene.robot_starts_array)
    assert first.solved and len(first.transitions) >= 3
    mid = first.transitions[1]
    u = mid.edge[0]
    cached = planner.tree_eval[u].transition
    planner.verifier.reroute = lambda trans, q_R: None  # every cached push is now unreachable
    calls = task.stats.verify_calls
    moved = mid.robot_start + np.array([0.0, 0.3])  # robots elsewhere: D_T has no entry
    planner.plan(mid.q_from, moved)
    assert u not in planner.tree_eval or planner.tree_eval[u].transition is not cached
    assert planner.failures.get(mid.edge, 0) >= 1
    assert task.stats.verify_calls > calls  # verified afresh


def test_lazy_reverifies_above_a_cut_in_the_cached_chain(proposer):
    """Tree_eval entries are dropped when their pushes fail; a later plan that reaches the
    chain above such a cut verifies that part again instead of following it into the gap."""
    scene = scene_from_dict(small_scene())
    task = ManipulationTask(scene, 0, scene.object_starts(), proposer, PlannerConfig(), seed=0)
    planner = LazyPlanner.from_task(task)
    first = planner.plan(scene.object_starts()[0], scene.robot_starts_array)
    assert first.solved and len(first.transitions) >= 4
    cut = first.transitions[-2].edge[0]
    del planner.tree_eval[cut]  # as report_failure or a failed re-route does
    calls = task.stats.verify_calls
    mid = first.transitions[1]
    again = planner.plan(mid.q_from, mid.robot_start)
    assert again.solved and np.allclose(again.transitions[-1].q_to, task.goal)
    assert task.stats.verify_calls > calls
    assert all(np.allclose(a.q_to, b.q_from)
               for a, b in zip(again.transitions[:-1], again.transitions[1:], strict=True))
