"""Tunable parameters of the LAMP planners and the closed loop, declared with their defaults,
documentation and valid ranges (``lamp.contract.params``)."""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from lamp.contract.params import check_fields, group, infos, param, replaced

#: Cumulative planning limit per object (s) of a planner that does not set its own
#: (``PlannerSpec.planning_limit``; LAMP-A* keeps the paper's 500 s).
DEFAULT_PLANNING_LIMIT = 300.0


#: LAMP-A*'s default expansion budget per second of planning limit. It expands 9-12
#: states/s on the suite mazes with the learned model (2 cores), so at 8 the count ends a
#: search at about 3/4 of the wall-clock limit (maze-03 at 20 s: 160 expansions in 15 s).
#: With the first 4 scenes per family and a 20 s limit it plans 15 of 16, as the wall-clock
#: limit did (at 4: 14 of 16; `benchmarks/bench_lamp_astar.py --scenes 4 --limit 20`).
ASTAR_EXPANSION_RATE = 8.0
#: LAMP-Lazy's default D* Lite expansion budget per second of planning limit (300 k for
#: the default 300 s). A search that floods the lattice (every failed Verify near a tight
#: goal adds ``edge_penalty`` to an edge, and D* Lite re-expands everything cheaper than
#: the detour: 40-200 k vertices per replan, ``fleet-11`` under ``noise-high``) expands
#: 1.2 M vertices in the 300 s, the clock deciding; D* Lite runs about 8-10 k vertices/s
#: there (AMD EPYC VM), so at 1000 the count ends it after some 30-40 s of search. An
#: ordinary run needs far less (``stats.search_expansions``): at most 9.3 k for a paper
#: benchmark scene (``maze-16``) and 151 k for a whole ``fleet`` run (``fleet-20``, 10
#: objects), the same runs to the millisecond with the budget as without.
LAZY_EXPANSION_RATE = 1000.0
#: LAMP-Lazy's default Verify-call budget per object, over all its plan calls, per second
#: of planning limit (24 k for the default 300 s: six plan calls that each spend their
#: whole ``max_verify_calls``). A plan call that fails that way makes about 120 Verify
#: calls/s (the 40 x 30 m long-haul depot, 72 robots: 4,000 in 33 s), so the count ends
#: such an object at about 1/3 of the wall-clock limit, before the clock on a loaded
#: machine. Ordinary objects need far less: at most 3.5 k (``warehouse-xl``), 30-50 calls
#: per second of a whole fleet run's planning.
LAZY_VERIFY_RATE = 80.0


#: The paper's limit: at most 100 executed segments ("execution iterations") per object.
#: ``lamp bench`` keeps it on the built-in paper suites.
PAPER_MAX_SEGMENTS = 100
#: When the limit scales with the task (``max_segments=None``, the default for user scenes):
#: segments allowed per metre of the object's route from start to goal (the longer of the
#: straight line and the shortest route around the map's obstacles,
#: ``lamp.planners.task.route_distance``), ten per metre (one per 0.1 m lattice step,
#: though a long push covers many) times a factor of three for detours and pushes that
#: drift. (Per metre of straight line alone, a maze ran out: ``maze-31-4``'s object 4, a
#: 6.1 m straight line and a 25 m route, stopped 4.7 m short at its 182nd segment.)
SEGMENTS_PER_METRE = 30.0

def segment_limit(max_segments: int | None, distance: float | Callable[[], float]) -> int:
    """The executed-segment limit for an object whose route to its goal is ``distance`` m
    long (a number, or a function asked only when the limit scales): ``max_segments``
    when set, else ``max(PAPER_MAX_SEGMENTS, ceil(SEGMENTS_PER_METRE * distance))``, so
    a large map or a winding route never runs out of segments before the route does."""
    if max_segments is not None:
        return int(max_segments)
    if callable(distance):
        distance = distance()
    return max(PAPER_MAX_SEGMENTS, math.ceil(SEGMENTS_PER_METRE * float(distance) - 1e-9))


@dataclass(frozen=True)
class LoopConfig:
    """The closed loop's parameters (Alg. 2): limits, drift, stopping, long pushes, sensing."""

    #: Wall clock, so an outer cap: the counts (plan iterations, Verify calls, expansions)
    #: end a search first on an unloaded machine.
    planning_time_limit: float = param(500.0, "Cumulative planning limit per object (s), an "
                                       "outer cap (the paper's 500 s for LAMP-A*).",
                                       low=0.0, low_open=True, unbounded=True)
    max_segments: int | None = param(None, "Executed segments allowed per object; none "
                                     "scales the limit with the task (segment_limit); the "
                                     "paper benchmark sets 100.", kind=int, low=1,
                                     optional=True)
    drift_position: float = param(0.05, "Position drift that triggers replanning (m): "
                                  "Drift in Alg. 2 line 6.", low=0.0, low_open=True)
    drift_orientation: float = param(0.1, "Execution drift that triggers replanning, "
                                     "orientation (rad).", low=0.0, low_open=True)
    #: Tighter than the success tolerance of 0.1 m / 0.1 rad, to keep a margin.
    stop_position: float = param(0.05, "The loop stops pushing this close to the goal (m).",
                                 low=0.0, low_open=True)
    stop_orientation: float = param(0.07, "The loop stops pushing this close to the goal "
                                    "heading (rad).", low=0.0, low_open=True)
    #: Long pushes (``lamp.planners.long_push``): consecutive transitions whose approach
    #: moves no robot more than ``continuous_push_gap`` (m) execute as one segment, up to
    #: ``long_push_length`` m of planned object motion; 0 executes every transition alone.
    long_push_length: float = param(1.0, "Planned object motion executed as one long push "
                                    "at most (m); 0: every transition alone.", low=0.0)
    #: A bound on the turn left unobserved: a turn in place moves the origin by nothing, so
    #: ``long_push_length`` alone let three 0.39 rad turns run as one push. 0.4 rad is one
    #: heading bin of the default lattice (0.393 rad) plus slack: a long push turns the
    #: object by at most one bin.
    long_push_turn: float = param(0.4, "Planned object turn executed as one long push at "
                                  "most (rad, summed over its parts).", low=0.0)
    continuous_push_gap: float = param(0.02, "Approach moves up to this (m) continue a long "
                                       "push.", low=0.0)
    #: What the loop knows of its object sensor: a noisy reading moves the observed pose
    #: without the object moving, so drift and stall tests keep above the noise (a loop
    #: that replans on noise alone thrashes). The pipeline sets it from the run's
    #: ``--sensing-noise`` unless given.
    sensing_sigma: float = param(0.0, "Standard deviation of the object sensor (m; heading "
                                 "sigma / 0.2 rad); drift below 3 sigma of the averaged "
                                 "reading is not drift.", low=0.0)
    sensing_readings: int = param(4, "Readings of a settled object averaged after each "
                                  "segment when sensing_sigma > 0.", low=1)
    #: Memory, not results: an evicted space is rebuilt the same. The fleet schedule
    #: shares ``lamp.fleet.config.SPACE_CACHE_MB`` among the objects moving at once.
    space_cache_mb: float = param(96.0, "Robot configuration spaces (MB) one object's task "
                                  "keeps cached; a speed / memory trade, the results do "
                                  "not depend on it.", low=1.0)
    #: Memory, not results, as ``space_cache_mb``; the fleet schedule's objects keep none
    #: (``lamp.fleet.objects``).
    successor_cache_nodes: int = param(20_000, "Successor lists (about 1.5 kB each) one "
                                       "object's lattice keeps; a speed / memory trade, "
                                       "the results do not depend on it; 0: none.", low=0)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class VerifyConfig:
    """Verify's parameters: candidates drawn, budgets, Gspi, contact tolerance."""

    k: int = param(16, "Candidates drawn per call: "
                   "K of the manipulation model in Alg. 1 line 20.", low=1)
    max_budget: int = param(3, "Largest robot budget tried by Verify (budgets run from "
                            "min(N, this) down to 1).", low=1)
    gspi_attempts_per_budget: int = param(3, "Candidates per budget handed to Gspi before a "
                                          "smaller budget is tried.", low=1)
    #: An outer cap only: Gspi stops on counts first (its step budget and stall count,
    #: ``lamp.mrmp.plan_paths``), so the result does not depend on the machine's load; the
    #: cap fires only on a machine some 10x slower than the one this was tuned on
    #: (``TaskStats.gspi_timeouts`` counts the calls it ended).
    gspi_time_limit: float = param(10.0, "Wall-clock cap of one Gspi call inside Verify (s), "
                                   "an outer cap only.", low=0.0, low_open=True, unbounded=True)
    contact_tolerance: float = param(0.006, "How far inside the nominal contact distance a "
                                     "contact may lie (m).", low=0.0)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class LatticeConfig:
    """The object lattice's parameters: its steps and how robot configurations match."""

    lattice_step: float = param(0.1, "Object lattice translation step (m).", low=0.0,
                                low_open=True)
    n_headings: int = param(16, "Object lattice heading bins.", low=1)
    robot_match_tolerance: float = param(0.05, "Robot configurations closer than this (m, "
                                         "per robot) count as the same (D_T keys).",
                                         low=0.0, low_open=True)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class LazyConfig:
    """LAMP-Lazy's own parameters (Alg. 2's D* Lite search)."""

    edge_penalty: float = param(10.0, "Cost added to an edge whose verification failed: "
                                "UpdateChange in Alg. 2 lines 18 and 31.", low=0.0)
    max_plan_iterations: int = param(400, "Most D* Lite replans inside one LAMP-Lazy Plan "
                                     "call.", low=1)
    max_verify_calls: int = param(4000, "Most Verify calls in one LAMP-Lazy Plan call.", low=1)
    lazy_max_object_verify: int | None = param(None, "Most Verify calls LAMP-Lazy makes per "
                                               "object, over all its plan calls; none: "
                                               "LAZY_VERIFY_RATE per second of "
                                               "planning_time_limit.", kind=int, low=1,
                                               optional=True)
    lazy_max_expansions: int | None = param(None, "Most D* Lite expansions LAMP-Lazy makes "
                                            "per object, over all its plan calls; none: "
                                            "LAZY_EXPANSION_RATE per second of "
                                            "planning_time_limit.", kind=int, low=1,
                                            optional=True)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class AStarConfig:
    """LAMP-A*'s own parameters (Alg. 1)."""

    astar_reinsert_penalty: float = param(1e4, "Penalty of a LAMP-A* state put back in Open: "
                                          "Open.re-add in Alg. 1 line 16 (the paper's 1e4).",
                                          low=0.0)
    #: Edge costs are robot travel, pushes plus repositioning, about 3-7x the object's
    #: travel that the heuristic measures, so at weight 1 the search fills long
    #: f-plateaus of robot states; 4 keeps it directed (within 4x of optimal, were states
    #: not capped). On 18 suite scenes (first 6 Random, 4 each of the others), 20 s
    #: limit, capped: weight 4 planned 17 of 18; weight 2 (uncapped) 3 of the 6 Random.
    astar_heuristic_weight: float = param(4.0, "Weight on LAMP-A*'s heuristic (weighted A*; "
                                          "the paper's plain A* is 1).", low=1.0)
    #: Robot positions are continuous, so without a cap every lattice node in a dead end
    #: holds dozens of states that must all be expanded before the search backs out; 2
    #: keeps two ways of standing around each object pose.
    astar_states_per_node: int | None = param(2, "Most robot configurations LAMP-A* keeps "
                                              "per object node (none: unbounded, as in the "
                                              "paper).", low=1, optional=True)
    astar_max_expansions: int | None = param(None, "Most states LAMP-A* expands per object, "
                                             "over all its plan calls; none: "
                                             "ASTAR_EXPANSION_RATE per second of "
                                             "planning_time_limit.", kind=int, low=1,
                                             optional=True)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass(frozen=True)
class PlannerConfig:
    """The parameters of LAMP-Lazy, LAMP-A*, the GCo baselines and the closed loop, in the
    groups their owners read: ``loop`` (the closed loop), ``verify`` (Verify), ``lattice``
    (the object lattice), ``lazy`` (LAMP-Lazy's search) and ``astar`` (LAMP-A*'s). Each
    parameter is declared once, with its documentation and valid range
    (``lamp.contract.params``; validated on construction), and named by itself: which
    planner reads which is declared in the planner registry (``PlannerSpec.params``);
    ``lamp run --planner P --help-params`` lists them, ``--param P.NAME=VALUE`` sets them,
    :meth:`of` and :meth:`but` build sets by name."""

    loop: LoopConfig = group(LoopConfig)
    verify: VerifyConfig = group(VerifyConfig)
    lattice: LatticeConfig = group(LatticeConfig)
    lazy: LazyConfig = group(LazyConfig)
    astar: AStarConfig = group(AStarConfig)

    @classmethod
    def of(cls, **values: Any) -> PlannerConfig:
        """The defaults with ``values`` (parameter name -> value) set, each in its group."""
        return replaced(cls(), **values)

    def but(self, **values: Any) -> PlannerConfig:
        """This set with ``values`` (parameter name -> value) set, each in its group."""
        return replaced(self, **values)

    @property
    def astar_expansions(self) -> int:
        """LAMP-A*'s expansion budget per object (``astar_max_expansions`` or its default:
        ``ASTAR_EXPANSION_RATE`` per second of the loop's planning limit)."""
        return _budget(self.astar.astar_max_expansions, ASTAR_EXPANSION_RATE,
                       self.loop.planning_time_limit)

    @property
    def lazy_expansions(self) -> int:
        """LAMP-Lazy's D* Lite expansion budget per object (``lazy_max_expansions`` or its
        default: ``LAZY_EXPANSION_RATE`` per second of the loop's planning limit)."""
        return _budget(self.lazy.lazy_max_expansions, LAZY_EXPANSION_RATE,
                       self.loop.planning_time_limit)

    @property
    def lazy_verify_calls(self) -> int:
        """LAMP-Lazy's Verify-call budget per object (``lazy_max_object_verify`` or its
        default: ``LAZY_VERIFY_RATE`` per second of the loop's planning limit)."""
        return _budget(self.lazy.lazy_max_object_verify, LAZY_VERIFY_RATE,
                       self.loop.planning_time_limit)


def _budget(given: int | None, rate: float, seconds: float) -> int:
    if given is not None:
        return given
    if not math.isfinite(seconds):
        return sys.maxsize
    return max(1, round(rate * seconds))


#: Which parameters each consumer reads (its group's); a planner declares the union of
#: the groups it reads (``PlannerSpec.params``).
LOOP_PARAMS = tuple(infos(LoopConfig))
VERIFY_PARAMS = tuple(infos(VerifyConfig))
LATTICE_PARAMS = tuple(infos(LatticeConfig))
LAZY_PARAMS = tuple(infos(LazyConfig))
ASTAR_PARAMS = tuple(infos(AStarConfig))
