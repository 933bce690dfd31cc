"""Simulated time against wall time: the pace of ``lamp serve --realtime F``.

A :class:`Pace` holds an anchor, a pair (wall time, simulated time) that were the same
instant; from it on, simulated time runs ``factor`` simulated seconds per wall second.
The simulation may lag (its planners take wall time while simulated time stands still):
:meth:`Pace.anchor` then moves the anchor to now, so the simulation never races to catch
up; it never runs ahead of the pace either (the feed sleeps until :meth:`Pace.wall_at`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

__all__ = ["Pace"]


class Pace:
    """Simulated seconds per wall second ``factor`` (> 0), wall time read from ``wall``
    (seconds, monotonic)."""

    def __init__(self, factor: float, wall: Callable[[], float] = time.monotonic) -> None:
        if not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"factor: a finite number > 0, got {factor!r}")
        self.factor = float(factor)
        self.wall = wall
        self._anchor: tuple[float, float] | None = None  # (wall, simulated)

    def anchor(self, sim_now: float) -> None:
        """The simulation stands at ``sim_now``: if the pace would put it later (it lags,
        or no anchor yet), the anchor moves to (now, ``sim_now``); if the pace puts it
        earlier (it is ahead), the anchor stays and the caller waits."""
        w = self.wall()
        if self._anchor is None or self.sim_at(w) > sim_now:
            self._anchor = (w, float(sim_now))

    def sim_at(self, wall: float) -> float:
        """The simulated time the pace gives wall time ``wall`` (needs an anchor)."""
        w0, s0 = self._require()
        return s0 + (wall - w0) * self.factor

    def wall_at(self, sim: float) -> float:
        """The wall time at which the pace reaches simulated time ``sim``."""
        w0, s0 = self._require()
        return w0 + (sim - s0) / self.factor

    def now(self) -> float:
        """The simulated time the pace gives the wall clock now."""
        return self.sim_at(self.wall())

    def _require(self) -> tuple[float, float]:
        if self._anchor is None:
            raise RuntimeError("Pace: anchor() first")
        return self._anchor
