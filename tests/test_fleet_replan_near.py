"""``fleet.objects.object_main`` with ``replan_near``: an object's loops plan around every
other robot (``plan_near`` = inf) until one of them found no plan (``NO_PLAN_YET``); from
then on only around the robots within ``replan_near`` of its team. A fake host and runner
stand in for the fleet and LAMP's loop: what is checked is the world each loop is given."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from lamp.contract.result import ObjectResult
from lamp.contract.runner import ALONE, LoopEnd, ObjectOutcome
from lamp.fleet import objects
from lamp.fleet.config import REPLAN_NEAR, FleetConfig
from lamp.fleet.stats import FleetStats
from lamp.planners.closed_loop import NO_PLAN_YET, WORLD_CHANGED
from lamp.planners.config import PlannerConfig
from lamp.scene.model import Circle, Scene, SceneObject

#: robot 0 is the team; robot 1 stands 1 m from it, robot 2 20 m away
ROBOTS = np.array([[1.0, 1.0], [2.0, 1.0], [21.0, 1.0]])
SCENE = Scene("replan-near", (24.0, 4.0), tuple(map(tuple, ROBOTS)),
              (SceneObject(Circle(0.2), (1.0, 2.0, 0.0), (3.0, 2.0, 0.0)),), ())


def _outcome(reason: str, end: LoopEnd) -> ObjectOutcome:
    done = end is LoopEnd.FINISHED
    return ObjectOutcome(ObjectResult(
        success=done, final_pose=[1.0, 2.0, 0.0], goal=[3.0, 2.0, 0.0], position_error=0.0,
        orientation_error=0.0, left_workspace=False, segments=0, full_horizon_plan=False,
        failure_reason=None if done else reason, replans=0, planning_time_s=0.0), end=end)


class Runner:
    """Ends its loops as ``ends`` says, noting the robots each loop's world holds."""

    def __init__(self, ends: list[tuple[str, LoopEnd]]) -> None:
        self.config, self.seed, self.ends, self.worlds = PlannerConfig.of(), 0, ends, []

    def loop(self, scene, k, view, config, observe, hooks):
        self.worlds.append(len(scene.obstacles))  # the other robots, as disks
        return _outcome(*self.ends[len(self.worlds) - 1])


class Host:
    def __init__(self) -> None:
        self.scene, self.stats = SCENE, FleetStats(SCENE.n_robots)
        self.executor = SimpleNamespace(object_poses=np.array([SCENE.objects[0].start]),
                                        true_object_poses=np.array([SCENE.objects[0].goal]),
                                        robot_positions=ROBOTS.copy())

    def moving(self) -> int:
        return 1

    def team_of(self, k: int) -> list[int]:
        return [0]

    def view(self, k: int):
        return SimpleNamespace(team=[0], team_changed=False, hooks=ALONE)

    def detour_of(self, k: int):
        return None

    def world_taken(self, k: int) -> None: ...

    def following(self, k: int) -> dict:
        return {}

    def mark_placed(self, k: int) -> bool:
        return False


@pytest.mark.parametrize("settings, want", [
    (FleetConfig(), [2, 2, 1, 1]),  # after the failed plan, only robot 1 (1 m away)
    (FleetConfig(replan_near=math.inf), [2, 2, 2, 2]),
    (FleetConfig(plan_near=0.5), [0, 0, 0, 0]),  # never more than plan_near
    (FleetConfig(replan_near=0.5), [2, 2, 0, 0]),
])
def test_loops_plan_near_once_a_plan_failed(monkeypatch, settings, want) -> None:
    monkeypatch.setattr(objects, "transit", lambda *a: (0, 0.0))  # the team is there
    runner = Runner([(WORLD_CHANGED, LoopEnd.WORLD_CHANGED), (NO_PLAN_YET, LoopEnd.WORLD_CHANGED),
                     (WORLD_CHANGED, LoopEnd.WORLD_CHANGED), ("", LoopEnd.FINISHED)])
    out = objects.object_main(runner, lambda e: None, settings)(Host(), 0)
    assert out.result.success and runner.worlds == want


def test_the_default_reach_after_a_failure_is_the_documented_constant() -> None:
    assert FleetConfig().replan_near == REPLAN_NEAR == 5.0
