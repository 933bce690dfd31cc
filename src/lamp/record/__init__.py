"""Recorded runs (format ``lamp-recording/1``): build, save, load; numpy is all it needs.

- ``Recorder``: the per-segment observer that builds a ``Recording`` during a run;
- ``save_recording(recording, run_dir)`` / ``load_recording(run_dir)``: the two files
  ``recording.npz`` + ``recording.json`` (``docs/recording-format.md``);
- ``check_recording`` / ``check_run_dir`` (``lamp.record.safety``, Shapely, loaded on first
  use): an independent re-check that nothing collided in a recorded run;
- ``audit_recording`` / ``audit_run_dir`` (``lamp.record.audit``, as ``lamp check``): that
  check and how far pushed objects ran ahead of their pushers (``lamp.record.push_reach``).

Rendering a recording (GIF, MP4, PNG, HTML) is ``lamp.viz.replay``.
"""

from typing import TYPE_CHECKING

from lamp.lazy_exports import lazy_getattr
from lamp.record.format import (
    FORMAT,
    JSON_NAME,
    NPZ_NAME,
    OUTCOMES,
    Recording,
    RecordingError,
    load_recording,
    save_recording,
)
from lamp.record.recorder import Recorder

if TYPE_CHECKING:
    from lamp.record.audit import ReachBound, RunAudit, audit_recording, audit_run_dir
    from lamp.record.safety import SafetyReport, Violation, check_recording, check_run_dir

#: The safety check's names, imported when first asked for (it loads Shapely).
_LAZY = dict.fromkeys(("SafetyReport", "Violation", "check_recording", "check_run_dir"),
                      "lamp.record.safety") | dict.fromkeys(
    ("ReachBound", "RunAudit", "audit_recording", "audit_run_dir"), "lamp.record.audit")
__getattr__ = lazy_getattr("lamp.record", _LAZY, globals())

__all__ = [
    "FORMAT",
    "JSON_NAME",
    "NPZ_NAME",
    "OUTCOMES",
    "Recorder",
    "Recording",
    "ReachBound",
    "RecordingError",
    "RunAudit",
    "SafetyReport",
    "Violation",
    "audit_recording",
    "audit_run_dir",
    "check_recording",
    "check_run_dir",
    "load_recording",
    "save_recording",
]
