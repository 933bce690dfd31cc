"""A recorded run re-checked as a whole, without the planner: did anything collide
(:mod:`lamp.record.safety`), and did pushed objects stay within the reach that a concurrent
fleet's admission takes them to have (:mod:`lamp.record.push_reach`)?

The reach is judged only where pushes are the only thing that moves objects and the run
kept each robot's sub-team: a concurrent run (its recording has ``robot_team``) without
sensing or actuation noise and without push knocks (:func:`reach_not_judged`; the fleet
cuts nothing by the reach in those runs either). Everywhere else the lead is measured and
reported, not judged. The bound (speedup, lead) is the caller's: ``lamp check`` passes
the fleet's own (``lamp.fleet.spacetime.PUSH_SPEEDUP`` and ``PUSH_LEAD``).

Guarantee: :attr:`RunAudit.ok` is false exactly when the safety report has a violation or
the judged lead exceeds the bound (``tests/test_fleet_run.py``: a clean run, the same run
with an object shoved, knocked, and a sequential run).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lamp.record.format import JSON_NAME, Recording, load_recording
from lamp.record.push_reach import ReachReport, push_reach
from lamp.record.safety import SafetyReport, check_recording, recorded_teams

__all__ = ["ReachBound", "RunAudit", "audit_recording", "audit_run_dir", "reach_not_judged",
           "run_dirs"]

#: Disturbances under which something besides the pushers moves objects (or the
#: recorded motion is not what the fleet tracked).
UNTRACKED = ("sensing_noise", "actuation_noise", "push_disturbance")


@dataclass(frozen=True)
class ReachBound:
    """A pushed object's points move at most ``speedup`` times as far as the farthest
    robot of its sub-team plus ``lead`` (m), over rows up to ``horizon`` apart."""

    speedup: float
    lead: float
    horizon: int = 400

    def __post_init__(self) -> None:
        if not self.speedup > 0:
            raise ValueError(f"speedup: positive, got {self.speedup!r}")
        if not self.lead >= 0:
            raise ValueError(f"lead: 0 or more metres, got {self.lead!r}")
        if not (isinstance(self.horizon, int) and self.horizon >= 1):
            raise ValueError(f"horizon: a whole number of rows >= 1, got {self.horizon!r}")


def reach_not_judged(recording: Recording) -> str:
    """Why the push lead of ``recording`` is not judged ("" when it is)."""
    if "robot_team" not in recording.arrays:
        return "sequential run"
    disturbed = recording.result.get("disturbances") or {}
    on = [k for k in UNTRACKED if disturbed.get(k)]
    return f"disturbed by {', '.join(on)}" if on else ""


@dataclass(frozen=True)
class RunAudit:
    """What :func:`audit_recording` found for one run: the safety report, the measured
    reach (None when not measured), why its lead is not judged ("" when it is), and the
    bound it was judged against."""

    safety: SafetyReport
    reach: ReachReport | None
    not_judged: str
    bound: ReachBound

    @property
    def lead_ok(self) -> bool:
        """The lead is within the bound, or not judged."""
        return bool(self.not_judged) or self.reach is None or self.reach.holds(self.bound.lead)

    @property
    def ok(self) -> bool:
        return self.safety.ok and self.lead_ok

    def summary(self) -> str:
        """The safety report's table, then a line for the push lead."""
        return self.safety.summary() + "\n" + self.lead_line()

    def line(self) -> str:
        """One line: the rows, the collisions, the push lead."""
        s, r = self.safety, self.reach
        lead = ("not measured" if r is None else "none (nothing pushed)" if r.object < 0
                else f"{r.lead:.3f} m")
        judged = (f" (not judged: {self.not_judged})" if self.not_judged else
                  f" (bound {self.bound.lead:g} m)")
        return (f"{s.rows_checked} rows, {s.n_robots} robots, {s.n_objects} objects: "
                f"{len(s.violations)} collision(s); push lead {lead}"
                + ("" if r is None else judged))

    def lead_line(self) -> str:
        b = self.bound
        if self.reach is None:
            return f"push lead: not measured ({self.not_judged})"
        r = self.reach
        where = (f"object {r.object}, {r.time_s:.2f}-{r.until_s:.2f} s" if r.object >= 0
                 else "no pair of rows")
        verdict = (f"not judged: {self.not_judged}" if self.not_judged else
                   "OK" if self.lead_ok else "VIOLATION")
        return (f"push lead: {r.lead:.3f} m ({where}); bound {b.speedup:g} x the pushers' "
                f"way + {b.lead:g} m over {b.horizon} rows: {verdict}")

    def to_dict(self) -> dict[str, Any]:
        s, r = self.safety, self.reach
        return {"ok": self.ok,
                "violations": [v.__dict__ for v in s.violations],
                "worst_depth_m": dict(s.worst_depth), "tol_m": dict(s.tol),
                "rows": s.rows_checked, "states": s.states_checked,
                "push_lead_m": None if r is None else r.lead,
                "push_lead_object": None if r is None else r.object,
                "push_lead_at_s": None if r is None else [r.time_s, r.until_s],
                "push_lead_judged": not self.not_judged, "push_lead_not_judged": self.not_judged,
                "push_bound": {"speedup": self.bound.speedup, "lead_m": self.bound.lead,
                               "horizon_rows": self.bound.horizon}}


def audit_recording(recording: Recording, bound: ReachBound, *,
                    tol: float | Mapping[str, float] | None = None,
                    reach: bool = True) -> RunAudit:
    """Re-check ``recording``: the safety check (``tol`` as ``check_recording`` takes it)
    and, unless ``reach`` is false, the push lead against ``bound``."""
    a = recording.arrays
    scene, teams = recording.scene_model(), recorded_teams(recording)
    safety = check_recording(scene, a["times"], a["robots"], a["objects"], tol=tol,
                             robot_team=teams)
    not_judged = reach_not_judged(recording)
    if not reach:
        return RunAudit(safety, None, not_judged or "skipped", bound)
    rep = push_reach(scene, a["robots"], a["objects"], teams, a["times"], bound.speedup,
                     bound.horizon)
    return RunAudit(safety, rep, not_judged, bound)


def run_dirs(path: str | Path) -> list[Path]:
    """The run folders at or below ``path``: ``path`` itself when it holds a recording, else
    every folder below it that does (a ``lamp bench --record`` folder), sorted."""
    path = Path(path)
    if (path / JSON_NAME).is_file() or path.suffix == ".json":
        return [path]
    return sorted({p.parent for p in path.rglob(JSON_NAME)})


def audit_run_dir(path: str | Path, bound: ReachBound, **kwargs: Any) -> RunAudit:
    """:func:`audit_recording` of the recording in run folder ``path``."""
    return audit_recording(load_recording(path), bound, **kwargs)
