"""Tunable parameters of the LAMP planners and the closed loop, with their defaults."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

#: The planner names (``lamp run --planner``, ``lamp.solve``) and what each stands for.
PLANNER_DESCRIPTIONS = {
    "lazy": "LAMP-Lazy (default)",
    "astar": "LAMP-A*, open loop",
    "astar-replan": "LAMP-A*, replanning on drift",
    "gco-ori": "GCo with its 0.2 m buffer",
    "gco-var": "GCo with zero buffer",
    "mapush": "MAPush-style RL baseline (lattice subgoals + PPO pushing policy)",
}
PlannerName = Literal["lazy", "astar", "astar-replan", "gco-ori", "gco-var", "mapush"]
#: Default cumulative planning limit per object (s): the paper's 500 s for LAMP-A*,
#: ``DEFAULT_PLANNING_LIMIT`` for every other planner.
DEFAULT_PLANNING_LIMIT = 300.0
PLANNING_LIMIT_OVERRIDES = {"astar": 500.0, "astar-replan": 500.0}


def default_planning_limit(planner: str) -> float:
    """The cumulative planning limit per object that ``planner`` runs under by default."""
    return PLANNING_LIMIT_OVERRIDES.get(planner, DEFAULT_PLANNING_LIMIT)


def planning_limit_help() -> str:
    """The per-planner defaults in words, e.g. ``300 s; 500 s for astar, astar-replan``."""
    by_value: dict[float, list[str]] = {}
    for name, value in PLANNING_LIMIT_OVERRIDES.items():
        by_value.setdefault(value, []).append(name)
    return f"{DEFAULT_PLANNING_LIMIT:g} s; " + "; ".join(
        f"{v:g} s for {', '.join(names)}" for v, names in by_value.items())


#: The paper's limit: at most 100 executed segments ("execution iterations") per object.
#: ``lamp bench`` keeps it on the built-in paper suites.
PAPER_MAX_SEGMENTS = 100
#: When the limit scales with the task (``max_segments=None``, the default for user scenes):
#: segments allowed per metre of straight-line start-goal distance, ten per metre (one per
#: 0.1 m lattice step, though a long push covers many) times a detour factor of three.
SEGMENTS_PER_METRE = 30.0


def segment_limit(max_segments: int | None, distance: float) -> int:
    """The executed-segment limit for an object whose goal is ``distance`` m from its start:
    ``max_segments`` when set, else ``max(PAPER_MAX_SEGMENTS, ceil(SEGMENTS_PER_METRE *
    distance))``, so a large map never runs out of segments before the route does."""
    if max_segments is not None:
        return int(max_segments)
    return max(PAPER_MAX_SEGMENTS, math.ceil(SEGMENTS_PER_METRE * float(distance) - 1e-9))


@dataclass(frozen=True)
class PlannerConfig:
    """Parameters shared by LAMP-Lazy, LAMP-A* and the GCo baselines."""

    #: Candidates drawn from the manipulation model per call (K in Alg. 1 line 20).
    k: int = 16
    #: Largest robot budget tried by Verify (budgets run from min(N, this) down to 1).
    max_budget: int = 3
    #: Candidates per budget that are handed to Gspi before trying a smaller budget.
    gspi_attempts_per_budget: int = 3
    #: Wall-clock limit of one Gspi call (seconds).
    gspi_time_limit: float = 1.0
    #: Execution drift that triggers replanning (Alg. 2 line 6): metres / radians.
    drift_position: float = 0.05
    drift_orientation: float = 0.1
    #: The closed loop stops pushing once the object is this close to its goal
    #: (tighter than the success tolerance of 0.1 m / 0.1 rad, to keep a margin).
    stop_position: float = 0.05
    stop_orientation: float = 0.07
    #: At most this many executed segments per object; None scales the limit with the task
    #: (``segment_limit``), the paper benchmark sets ``PAPER_MAX_SEGMENTS``.
    max_segments: int | None = None
    #: Long pushes (``lamp.planners.long_push``): consecutive transitions whose approach
    #: moves no robot more than ``continuous_push_gap`` (m) execute as one segment, up to
    #: ``long_push_length`` m of planned object motion; 0 executes every transition alone.
    long_push_length: float = 1.0
    continuous_push_gap: float = 0.02
    #: Object lattice: translation step (m) and heading bins.
    lattice_step: float = 0.1
    n_headings: int = 16
    #: Cost added to an edge whose verification failed (Alg. 2 lines 18 and 31, UpdateChange).
    edge_penalty: float = 10.0
    #: Penalty added to a re-inserted LAMP-A* state (Alg. 1 line 16, Open.re-add): the paper's 1e4.
    astar_reinsert_penalty: float = 1e4
    #: Weight on LAMP-A*'s heuristic (weighted A*; the paper's plain A* is 1). Edge costs
    #: are robot travel, pushes plus repositioning, about 3-7x the object's travel that
    #: the heuristic measures, so at weight 1 the search fills long f-plateaus of robot
    #: states; 4 keeps it directed (within 4x of optimal, were states not capped). On 18 suite
    #: scenes (first 6 Random, 4 each of the others), 20 s limit, capped: weight 4 planned
    #: 17 of 18; weight 2 (uncapped) 3 of the 6 Random.
    astar_heuristic_weight: float = 4.0
    #: Most robot configurations LAMP-A* keeps per object node (None: unbounded, as in
    #: the paper). Robot positions are continuous, so without a cap every lattice node in
    #: a dead end holds dozens of states that must all be expanded before the search
    #: backs out; 2 keeps two ways of standing around each object pose.
    astar_states_per_node: int | None = 2
    #: Cumulative planning limit per object (s): the paper's 500 s for LAMP-A*.
    planning_time_limit: float = 500.0
    #: Robot configurations closer than this (m, per robot) count as the same (D_T keys).
    robot_match_tolerance: float = 0.05
    #: How far inside the nominal contact distance a contact may lie (m).
    contact_tolerance: float = 0.006
    #: Largest number of D* Lite replans inside one Plan call before giving up.
    max_plan_iterations: int = 400

    def __post_init__(self) -> None:
        if self.max_segments is not None and (isinstance(self.max_segments, bool)
                                              or int(self.max_segments) != self.max_segments
                                              or self.max_segments < 1):
            raise ValueError(f"max_segments must be a positive integer or None, got "
                             f"{self.max_segments!r}")
        if not (math.isfinite(self.long_push_length) and self.long_push_length >= 0):
            raise ValueError(f"long_push_length must be >= 0, got {self.long_push_length!r}")
        if not (math.isfinite(self.continuous_push_gap) and self.continuous_push_gap >= 0):
            raise ValueError(f"continuous_push_gap must be >= 0, got {self.continuous_push_gap!r}")
