"""The counters of one object's planning (:class:`TaskStats`), reported in result.json's
``stats``: its ``Verifier`` and proposal cache count into them, LAMP-Lazy adds its search
expansions, and the runner sums them over the objects."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["TaskStats"]


@dataclass
class TaskStats:
    """Counters reported in result.json's ``stats``."""

    verify_calls: int = 0
    verify_success: int = 0
    model_calls: int = 0
    gspi_calls: int = 0
    gspi_success: int = 0
    #: Gspi calls ended by the wall-clock cap ``gspi_time_limit`` (0 on an unloaded
    #: machine: then no result depended on the clock).
    gspi_timeouts: int = 0
    cache_hits: int = 0
    #: pushes LAMP-Lazy verified earlier in the same ``plan`` call, on a path that failed
    #: further on, and took again instead of calling Verify (``lazy`` module docstring)
    verify_reused: int = 0
    #: vertices LAMP-Lazy's D* Lite expanded (its budget: ``lazy_max_expansions``)
    search_expansions: int = 0
    #: the most of them in one LAMP-Lazy ``plan`` call (a maximum: ``add`` keeps the larger)
    max_plan_expansions: int = 0

    def add(self, other: TaskStats) -> None:
        for k, v in vars(other).items():
            setattr(self, k, max(getattr(self, k), v) if k.startswith("max_")
                    else getattr(self, k) + v)
