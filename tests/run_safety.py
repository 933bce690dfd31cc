"""Test helper: a run's recording re-checked by ``lamp.record.safety`` (independent of the
planner): robots clear of each other and of obstacles, objects clear of each other, of
obstacles and of the border, within contact tolerance; and, for a concurrent run whose
pushes are tracked exactly, every pushed object within the reach the fleet's admission
takes it to have (``lamp.record.push_reach`` against ``lamp.fleet.spacetime``)."""

from __future__ import annotations

from lamp.fleet.spacetime import PUSH_LEAD, PUSH_SPEEDUP
from lamp.record.push_reach import push_reach
from lamp.record.safety import check_recording, recorded_teams

#: Rows compared apart at most (a segment's push is seldom longer).
REACH_HORIZON = 400


def assert_safe(result) -> None:
    """Fail with the checker's summary unless ``result``'s recording is safe."""
    rec = result.recording
    a = rec.arrays
    report = check_recording(rec.scene_model(), a["times"], a["robots"], a["objects"],
                             robot_team=recorded_teams(rec))
    assert report.ok, report.summary()
    d = result.disturbances
    if "robot_team" in a and not any(d.get(k) for k in ("sensing_noise", "actuation_noise",
                                                         "push_disturbance")):
        reach = push_reach(rec.scene_model(), a["robots"], a["objects"], a["robot_team"],
                           a["times"], PUSH_SPEEDUP, REACH_HORIZON)
        assert reach.holds(PUSH_LEAD), reach
