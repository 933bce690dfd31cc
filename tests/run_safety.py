"""Test helper: a run's recording re-checked by ``lamp.record.audit`` (independent of the
planner): robots clear of each other and of obstacles, objects clear of each other, of
obstacles and of the border, within contact tolerance; and, for a concurrent run whose
pushes are tracked exactly, every pushed object within the reach the fleet's admission
takes it to have (``lamp.record.push_reach`` against ``lamp.fleet.spacetime``)."""

from __future__ import annotations

from lamp.fleet.spacetime import PUSH_LEAD, PUSH_SPEEDUP
from lamp.record.audit import ReachBound, audit_recording

#: The bound ``lamp check`` judges concurrent runs by.
BOUND = ReachBound(PUSH_SPEEDUP, PUSH_LEAD)


def assert_safe(result) -> None:
    """Fail with the checker's summary unless ``result``'s recording is safe."""
    audit = audit_recording(result.recording, BOUND)
    assert audit.ok, audit.summary()
