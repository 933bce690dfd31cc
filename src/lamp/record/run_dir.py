"""A run folder's outputs, and clearing what an earlier run left there.

``lamp run`` / ``lamp demo`` write :data:`RUN_OUTPUTS` (some of them) into their folder. A
new run first removes every one of those files that it will not write itself (so an old
``run.gif`` never sits beside a new ``result.json``), then writes each output atomically,
``result.json`` last: a folder holding a ``result.json`` holds that run's complete outputs.
Files of other names are left alone.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from lamp.record.format import JSON_NAME, NPZ_NAME

RESULT_NAME = "result.json"
GIF_NAME = "run.gif"
HTML_NAME = "replay.html"
#: Every file a run may write into its folder (and so may remove as stale).
RUN_OUTPUTS = (RESULT_NAME, NPZ_NAME, JSON_NAME, GIF_NAME, HTML_NAME)


def clear_stale(run_dir: str | Path, keep: Iterable[str]) -> list[Path]:
    """Remove the :data:`RUN_OUTPUTS` in ``run_dir`` not named in ``keep`` (``result.json``
    always, first: it marks a complete run); returns the removed paths."""
    run_dir = Path(run_dir)
    keep = set(keep)
    removed = []
    for name in RUN_OUTPUTS:
        path = run_dir / name
        if (name == RESULT_NAME or name not in keep) and path.is_file():
            path.unlink()
            removed.append(path)
    return removed
