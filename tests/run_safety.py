"""Test helper: a run's recording re-checked by ``lamp.record.safety`` (independent of the
planner): robots clear of each other and of obstacles, objects clear of each other, of
obstacles and of the border, within contact tolerance."""

from __future__ import annotations

from lamp.record.safety import check_recording, recorded_teams


def assert_safe(result) -> None:
    """Fail with the checker's summary unless ``result``'s recording is safe."""
    rec = result.recording
    report = check_recording(rec.scene_model(), rec.arrays["times"], rec.arrays["robots"],
                             rec.arrays["objects"], robot_team=recorded_teams(rec))
    assert report.ok, report.summary()
