"""Success is judged on the final object poses (``pipeline.execute.still_placed``): an
object placed and later pushed off its goal fails; nothing else changes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.contract.goals import SUCCESS_ORIENTATION_TOL, SUCCESS_POSITION_TOL, within_goal
from lamp.contract.result import ObjectResult
from lamp.contract.runner import ObjectOutcome
from lamp.pipeline.execute import KNOCKED, still_placed
from lamp.scene import scene_from_dict

BOX = {"type": "rectangle", "size": [0.4, 0.3]}
SCENE = scene_from_dict({
    "format": "lamp-scene/1", "name": "two", "workspace": [6.0, 4.0],
    "robots": {"starts": [[0.3, 0.3], [0.3, 0.8]]},
    "objects": [{**BOX, "start": [1.0, 1.0, 0.0], "goal": [4.0, 1.0, 0.0]},
                {**BOX, "start": [1.0, 3.0, 0.0], "goal": [4.0, 3.0, 0.5]}]})


def _outcome(k: int, pose, success: bool, reason: str = "") -> ObjectOutcome:
    goal = SCENE.objects[k].goal
    return ObjectOutcome(ObjectResult(
        success=success, final_pose=[float(v) for v in pose], goal=list(goal),
        position_error=0.0, orientation_error=0.0, left_workspace=False, segments=3,
        full_horizon_plan=True, failure_reason=reason, replans=0, planning_time_s=1.0),
        planning_time_s=[0.5, 0.5], makespan=100)


@settings(max_examples=80)
@given(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.4, 0.4), st.booleans())
def test_a_placed_object_fails_exactly_when_its_final_pose_is_off_its_goal(dx, dy, dt,
                                                                           placed) -> None:
    """Object 0 ended its loop at its goal (or failed short of it); at the run's end it
    stands displaced by (dx, dy, dt). Placed: it still succeeds exactly when the final
    pose is within the tolerances (then its outcome is the same object, untouched), else
    it fails as pushed off, its final pose and errors those at the end, its segments and
    times kept. A failed object stays failed with its own reason. Object 1, untouched,
    is kept as it is."""
    goal = np.array(SCENE.objects[0].goal, float)
    end = goal + [dx, dy, dt]
    first = _outcome(0, goal, True) if placed else _outcome(0, goal + [1, 0, 0], False,
                                                                "ran out")
    second = _outcome(1, SCENE.objects[1].goal, True)
    got = still_placed(SCENE, [first, second], np.array([end, SCENE.objects[1].goal]))
    assert got[1] is second
    inside = within_goal(end, goal, SUCCESS_POSITION_TOL, SUCCESS_ORIENTATION_TOL)
    if not placed or inside:
        assert got[0] is first
    else:
        r = got[0].result
        assert not r.success and r.failure_reason == KNOCKED
        assert np.allclose(r.final_pose, end)
        assert abs(r.position_error - np.hypot(dx, dy)) < 1e-9
        assert r.segments == 3 and got[0].planning_time_s == [0.5, 0.5]
        assert got[0].makespan == 100
        assert replace(r, success=True, failure_reason="", final_pose=first.result.final_pose,
                       position_error=0.0, orientation_error=0.0) == first.result
