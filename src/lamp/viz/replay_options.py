"""What a replay is drawn with: the options every output checks, the shared colours and the caption.

:class:`RenderOptions` validates itself on construction (ValueError naming the field);
:func:`outcome_text` is the one-line verdict every output (raster frames, HTML viewer) shows.
Shared by ``lamp.viz.replay`` and ``lamp.viz.replay_html`` so neither imports the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from lamp.record.format import Recording

CONTACT_COLOR = "black"
TRAIL_COLOR = "#6f9be8"
#: With no ``speed`` given, videos last at most this many seconds (before the final hold).
AUTO_SECONDS = 20.0


@dataclass(frozen=True)
class RenderOptions:
    """How to draw a recording; every field is checked on construction (ValueError naming it).

    ``size``: pixels of the picture's longer side; ``fps``: frames per video second;
    ``speed``: simulated seconds per video second (None: fast enough that the video lasts
    at most :data:`AUTO_SECONDS`, never slower than real time); ``trail_s``: robot trail length
    in simulated seconds; ``min_robot_px``: smallest robot radius drawn, in pixels;
    ``follow``: width in metres of a camera window centred on the moved object (None: the
    whole workspace); ``at``: for a PNG, the segment whose end is drawn, 0-based as in the
    arrays (``lamp render --at`` counts from 1; None: the final state).
    """

    size: int = 640
    fps: float = 15.0
    speed: float | None = None
    trail_s: float = 4.0
    min_robot_px: float = 3.0
    follow: float | None = None
    at: int | None = None

    def __post_init__(self) -> None:
        checks = [
            ("size", isinstance(self.size, int) and 120 <= self.size <= 4096, "an integer in [120, 4096]"),
            ("fps", _finite(self.fps) and 0 < self.fps <= 60, "in (0, 60]"),
            ("speed", self.speed is None or (_finite(self.speed) and self.speed > 0), "> 0"),
            ("trail_s", _finite(self.trail_s) and self.trail_s >= 0, ">= 0"),
            ("min_robot_px", _finite(self.min_robot_px) and self.min_robot_px >= 0, ">= 0"),
            ("follow", self.follow is None or (_finite(self.follow) and self.follow > 0), "> 0"),
            ("at", self.at is None or (isinstance(self.at, int) and self.at >= 0), "an integer >= 0"),
        ]
        for name, ok, want in checks:
            if not ok:
                raise ValueError(f"{name}: must be {want}, got {getattr(self, name)!r}")


def _finite(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def outcome_text(recording: Recording) -> str:
    """The run's verdict in one line: success or failed, objects done, the first failure reason."""
    result = recording.result
    objects = result.get("objects", [])
    done = sum(1 for o in objects if o.get("success"))
    verdict = "success" if recording.success else "failed"
    reasons = [o.get("failure_reason", "") for o in objects if o.get("failure_reason")]
    return f"{verdict} ({done}/{len(objects)} objects)" + (f": {reasons[0]}" if reasons else "")
