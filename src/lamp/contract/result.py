"""Run results: what ``lamp run`` writes as ``result.json`` (``docs/recording-format.md``
and the README's result.json section list the keys).

``RunResult.to_dict()`` carries the documented keys plus a few extras (``stats``...).
``makespan`` counts the synchronised rows of all executed robot trajectories (one row is a
waypoint of at most ``lamp.contract.trajectory.MAX_STEP`` m); ``makespan_s`` is the run's
simulated time, equal to the recording's last time.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np


@dataclass
class ObjectResult:
    """The outcome of moving one object (one entry of result.json's ``objects``)."""

    success: bool
    final_pose: list[float]
    goal: list[float]
    position_error: float
    orientation_error: float
    left_workspace: bool
    segments: int
    full_horizon_plan: bool
    failure_reason: str = ""
    replans: int = 0
    planning_time_s: float = 0.0
    #: What its planning counted (``TaskStats``): Verify calls and search expansions, over
    #: all its plan calls (``lazy_max_object_verify`` bounds the Verify calls).
    verify_calls: int = 0
    search_expansions: int = 0

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(repr=False)
class RunResult:
    """The outcome of one (scene, planner, seed) run.

    Planning time: ``planning_time_s`` holds the time spent before each executed segment;
    ``unexecuted_planning_time_s`` the planning after an object's last executed segment
    (a failed final search, say). ``total_planning_time_s`` counts both: all planning.
    ``planning_time_per_segment_s`` is total planning time over executed segments, the
    figure of ``lamp bench``'s report (``lamp.bench.report.scenario_planning_time``).
    Numba compilation is never planning time (``lamp.pipeline.warmup``).
    """

    scene: str
    planner: str
    seed: int
    objects: list[ObjectResult] = field(default_factory=list)
    planning_time_s: list[float] = field(default_factory=list)
    makespan: int = 0
    replans: int = 0
    wall_time_s: float = 0.0
    stats: dict[str, Any] = field(default_factory=dict)
    unexecuted_planning_time_s: float = 0.0
    #: Simulated seconds from the first segment's start to the last one's end: the
    #: recording's last time.
    makespan_s: float = 0.0
    #: The planner's declared parameters and their values (``PlannerSpec.params``).
    params: dict[str, Any] = field(default_factory=dict)
    #: The run's disturbances (``lamp.contract.disturb.Disturbances.to_dict``).
    disturbances: dict[str, Any] = field(default_factory=dict)
    #: A lower bound on any run's makespan of this scene [s]
    #: (``lamp.scene.bounds.makespan_lower_bound``); None where not computed.
    makespan_lower_bound_s: float | None = None
    #: A lifelong run's tasks (``fleet.tasks.TaskRecord.to_dict``) and figures
    #: (``fleet.tasks.lifelong_figures``); None for a run without tasks.
    tasks: list[dict[str, Any]] | None = None
    lifelong: dict[str, Any] | None = None
    #: The run's ``lamp.record.Recording`` (set by ``lamp.solve``); not part of result.json.
    recording: Any = field(default=None, repr=False, compare=False)

    @property
    def success(self) -> bool:
        """Every object placed and, in a lifelong run, every task done."""
        return (bool(self.objects) and all(o.success for o in self.objects)
                and all(t["status"] == "done" for t in self.tasks or ()))

    @property
    def segments(self) -> int:
        return len(self.planning_time_s)

    def add_object(self, obj: ObjectResult, planning_time_s: list[float], makespan: int) -> None:
        """Append the outcome of the next object: its result, the planning time of each of
        its executed segments and its makespan (the run's replans grow by the object's)."""
        self.objects.append(obj)
        self.planning_time_s.extend(planning_time_s)
        self.makespan += makespan
        self.replans += obj.replans

    @property
    def total_planning_time_s(self) -> float:
        """All planning: before executed segments plus after the last one."""
        return float(sum(self.planning_time_s)) + float(self.unexecuted_planning_time_s)

    @property
    def planning_time_per_segment_s(self) -> float | None:
        """Total planning time over executed segments (None without a segment)."""
        return self.total_planning_time_s / self.segments if self.segments else None

    def __repr__(self) -> str:
        solved = sum(o.success for o in self.objects)
        return (f"RunResult(scene={self.scene!r}, planner={self.planner!r}, seed={self.seed}, "
                f"success={self.success}, objects={solved}/{len(self.objects)} solved, "
                f"segments={self.segments}, "
                f"total_planning_time_s={self.total_planning_time_s:.3f}, "
                f"makespan={self.makespan})")

    def to_dict(self) -> dict[str, Any]:
        return {
            "scene": self.scene,
            "planner": self.planner,
            "seed": self.seed,
            "success": self.success,
            "objects": [o.to_dict() for o in self.objects],
            "segments": self.segments,
            "planning_time_s": [round(float(t), 6) for t in self.planning_time_s],
            "total_planning_time_s": round(self.total_planning_time_s, 6),
            "executed_planning_time_s": round(float(sum(self.planning_time_s)), 6),
            "unexecuted_planning_time_s": round(float(self.unexecuted_planning_time_s), 6),
            "planning_time_per_segment_s": (
                round(per, 6) if (per := self.planning_time_per_segment_s) is not None else None
            ),
            "median_planning_time_s": (
                round(float(np.median(self.planning_time_s)), 6) if self.planning_time_s else None
            ),
            "makespan": int(self.makespan),
            "makespan_s": round(float(self.makespan_s), 6),
            "makespan_lower_bound_s": (None if (b := self.makespan_lower_bound_s) is None
                                       else round(float(b), 6)),
            "makespan_over_bound": (round(float(self.makespan_s) / b, 4) if b else None),
            "replans": int(self.replans),
            "wall_time_s": round(float(self.wall_time_s), 3),
            "stats": self.stats,
            "params": dict(self.params),
            "disturbances": dict(self.disturbances),
            **({} if self.tasks is None else {"tasks": list(self.tasks),
                                              "lifelong": dict(self.lifelong or {})}),
        }
