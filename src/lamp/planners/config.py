"""Tunable parameters of the LAMP planners and the closed loop, with their defaults."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import Any, Literal

#: The names of the built-in planners (``lamp run --planner``, ``lamp.solve``); the
#: registry (``lamp.planners.registry``) holds what each one is.
PlannerName = Literal["lazy", "astar", "astar-replan", "gco-ori", "gco-var", "mapush"]
#: Cumulative planning limit per object (s) of a planner that does not set its own
#: (``PlannerSpec.planning_limit``; LAMP-A* keeps the paper's 500 s).
DEFAULT_PLANNING_LIMIT = 300.0


def __getattr__(name: str) -> Any:
    if name == "PLANNER_DESCRIPTIONS":  # name -> description, read from the registry
        from lamp.planners import registry

        return {s.name: s.description for s in registry.specs()}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def default_planning_limit(planner: str) -> float:
    """The cumulative planning limit per object that ``planner`` runs under by default."""
    from lamp.planners import registry

    return registry.get(planner).planning_limit


def planning_limit_help() -> str:
    """The per-planner defaults in words, e.g. ``300 s; 500 s for astar, astar-replan``."""
    from lamp.planners import registry

    by_value: dict[float, list[str]] = {}
    for spec in registry.specs():
        if spec.planning_limit != DEFAULT_PLANNING_LIMIT:
            by_value.setdefault(spec.planning_limit, []).append(spec.name)
    return f"{DEFAULT_PLANNING_LIMIT:g} s" + "".join(
        f"; {v:g} s for {', '.join(names)}" for v, names in by_value.items())


#: LAMP-A*'s default expansion budget per second of planning limit. It expands 9-12
#: states/s on the suite mazes with the learned model (2 cores), so at 8 the count ends a
#: search at about 3/4 of the wall-clock limit (maze-03 at 20 s: 160 expansions in 15 s).
#: With the first 4 scenes per family and a 20 s limit it plans 15 of 16, as the wall-clock
#: limit did (at 4: 14 of 16; `benchmarks/bench_lamp_astar.py --scenes 4 --limit 20`).
ASTAR_EXPANSION_RATE = 8.0


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
    #: Wall-clock cap of one Gspi call inside Verify (seconds): an outer cap only. Gspi
    #: stops on counts first (its step budget and stall count, ``lamp.mrmp.plan_paths``),
    #: so the result does not depend on the machine's load; the cap fires only on a
    #: machine some 10x slower than the one this was tuned on (``TaskStats.gspi_timeouts``
    #: counts the calls it ended).
    gspi_time_limit: float = 10.0
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
    #: Most states LAMP-A* expands per object, over all its ``plan`` calls
    #: (``BUDGET_EXHAUSTED``): the deterministic limit of the search, of which the
    #: cumulative planning time limit is only the outer cap. None: ``ASTAR_EXPANSION_RATE``
    #: per second of ``planning_time_limit`` (4000 for the paper's 500 s).
    astar_max_expansions: int | None = None
    #: Cumulative planning limit per object (s): the paper's 500 s for LAMP-A*. Wall
    #: clock, so an outer cap: the counts (plan iterations, Verify calls, expansions)
    #: end a search first on an unloaded machine.
    planning_time_limit: float = 500.0
    #: Robot configurations closer than this (m, per robot) count as the same (D_T keys).
    robot_match_tolerance: float = 0.05
    #: How far inside the nominal contact distance a contact may lie (m).
    contact_tolerance: float = 0.006
    #: Largest number of D* Lite replans inside one Plan call before giving up.
    max_plan_iterations: int = 400
    #: Most Verify calls in one LAMP-Lazy Plan call (``BUDGET_EXHAUSTED``).
    max_verify_calls: int = 4000

    def __post_init__(self) -> None:
        for name in ("max_plan_iterations", "max_verify_calls", "astar_max_expansions",
                     "max_segments"):
            value = getattr(self, name)
            if value is None and name in ("astar_max_expansions", "max_segments"):
                continue
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
                raise ValueError(f"PlannerConfig.{name}: a positive integer, got {value!r}")
        for name in ("gspi_time_limit", "planning_time_limit"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and value > 0):
                raise ValueError(f"PlannerConfig.{name}: positive seconds, got {value!r}")
        for name in ("long_push_length", "continuous_push_gap"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ValueError(f"PlannerConfig.{name}: a length >= 0 m, got {value!r}")

    @property
    def astar_expansions(self) -> int:
        """LAMP-A*'s expansion budget per object (``astar_max_expansions`` or its default)."""
        if self.astar_max_expansions is not None:
            return self.astar_max_expansions
        if not math.isfinite(self.planning_time_limit):
            return sys.maxsize
        return max(1, round(ASTAR_EXPANSION_RATE * self.planning_time_limit))
