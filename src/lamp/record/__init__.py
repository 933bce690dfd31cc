"""Recorded runs (format ``lamp-recording/1``): build, save, load; numpy is all it needs.

- ``Recorder``: the per-segment observer that builds a ``Recording`` during a run;
- ``save_recording(recording, run_dir)`` / ``load_recording(run_dir)``: the two files
  ``recording.npz`` + ``recording.json`` (``docs/recording-format.md``).

Rendering a recording (GIF, MP4, PNG, HTML) is ``lamp.viz.replay``.
"""

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

__all__ = [
    "FORMAT",
    "JSON_NAME",
    "NPZ_NAME",
    "OUTCOMES",
    "Recorder",
    "Recording",
    "RecordingError",
    "load_recording",
    "save_recording",
]
