"""The contract between an object planner and the closed loop that executes its plans.

An :class:`ObjectPlanner` plans the motion of one object (LAMP-Lazy, LAMP-A*, the GCo
baselines). ``plan`` always returns a :class:`Plan` whose :class:`PlanStatus` says how the
call ended, so the loop never guesses a reason from the clock; ``report_failure`` tells
the planner that an executed transition did not move the object (it stalled); ``clear``
forgets everything learnt (caches, penalties) so the planner can start over.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from lamp.contract.transition import Transition

__all__ = ["OBJECT_BUDGETS", "LoopPolicy", "ObjectPlanner", "Plan", "PlanStatus"]

Edge = tuple[np.ndarray, np.ndarray]


class PlanStatus(str, Enum):
    """How one ``ObjectPlanner.plan`` call ended; ``reason`` is the result.json wording."""

    SOLVED = "solved"
    #: The object's pose cannot be joined to the planner's lattice (no free connecting move).
    START_BLOCKED = "start_blocked"
    #: No object route to the goal remains (every route is blocked or was exhausted).
    NO_PATH = "no_path"
    #: Proven before any search: no gap lets the object through to its goal
    #: (``lamp.search.connectivity``).
    SEPARATED = "separated"
    #: A deterministic count ran out (plan iterations, Verify calls, search expansions):
    #: ``Plan.limit`` names it.
    BUDGET_EXHAUSTED = "budget_exhausted"
    #: The wall-clock deadline passed.
    TIME_LIMIT = "time_limit"
    #: A single-step planner's chosen push cannot be reached by the robots (GCo).
    PUSH_UNREACHABLE = "push_unreachable"

    @property
    def reason(self) -> str:
        return _REASONS[self]


_REASONS = {
    PlanStatus.SOLVED: "",
    PlanStatus.START_BLOCKED: "no plan found: the object's pose cannot join the lattice",
    PlanStatus.NO_PATH: "no plan found",
    PlanStatus.SEPARATED: "no plan found: no gap lets the object through to its goal",
    PlanStatus.BUDGET_EXHAUSTED: "no plan found: a search budget exhausted",
    PlanStatus.TIME_LIMIT: "planning time limit",
    PlanStatus.PUSH_UNREACHABLE: "robots cannot reach the push",
}


#: The counts that bound an object over all its plan calls, and all its loops
#: (``planners.series``): once one ran out, no later call can plan, so the closed loop
#: ends for good (``Plan.spent``).
OBJECT_BUDGETS = frozenset({"lazy_max_object_verify"})


@dataclass
class Plan:
    """A plan for one object: transitions to execute in order (all of them verified, for
    the LAMP planners) and, for display, the edges verified and penalised so far.

    ``status`` is ``SOLVED`` exactly when there are transitions to execute.
    """

    status: PlanStatus
    transitions: list[Transition] = field(default_factory=list)
    verified_edges: list[Edge] = field(default_factory=list)
    penalised_edges: list[Edge] = field(default_factory=list)
    #: Which limit ended a ``BUDGET_EXHAUSTED`` or ``TIME_LIMIT`` call: the name of the
    #: ``PlannerConfig`` count that ran out (``max_plan_iterations``, ``max_verify_calls``,
    #: ``astar_max_expansions``, ``lazy_max_expansions``, ``lazy_max_object_verify``) or
    #: ``"deadline"`` (wall clock); "" otherwise.
    limit: str = ""
    #: The transitions do not reach the goal (a recovery push): the loop plans again
    #: after them, and the object's plan does not count as full-horizon.
    partial: bool = False

    def __post_init__(self) -> None:
        if (self.status is PlanStatus.SOLVED) != bool(self.transitions):
            raise ValueError(f"a {self.status.value} plan with {len(self.transitions)} "
                             "transitions: SOLVED plans, and only they, have transitions")

    @property
    def reason(self) -> str:
        """The result.json wording of how the call ended, naming the limit that fired."""
        if self.status is PlanStatus.BUDGET_EXHAUSTED and self.limit:
            return f"no plan found: {self.limit} exhausted"
        return self.status.reason

    @property
    def solved(self) -> bool:
        return self.status is PlanStatus.SOLVED

    @property
    def spent(self) -> bool:
        """Whether the call ended on one of the object's budgets (``OBJECT_BUDGETS``)."""
        return self.status is PlanStatus.BUDGET_EXHAUSTED and self.limit in OBJECT_BUDGETS

    @property
    def object_path(self) -> np.ndarray:
        """(len(transitions) + 1, 3) object poses the plan passes through."""
        if not self.transitions:
            return np.zeros((0, 3))
        return np.array([self.transitions[0].q_from] + [t.q_to for t in self.transitions])

    @staticmethod
    def failed(status: PlanStatus, penalised: list[Edge] | None = None, limit: str = "") -> Plan:
        return Plan(status, [], [], list(penalised or []), limit)


class ObjectPlanner(Protocol):
    """Plans the motion of one object of a ``ManipulationTask``."""

    def plan(self, q_O: np.ndarray, q_R: np.ndarray, deadline: float | None = None) -> Plan:
        """A plan from object pose ``q_O`` (3,) and robots ``q_R`` (N, 2); ``deadline`` is a
        ``time.perf_counter()`` instant after which the call gives up (``TIME_LIMIT``)."""
        ...

    def report_failure(self, transition: Transition) -> None:
        """An executed ``transition`` barely moved the object: do not trust it again."""
        ...

    def clear(self) -> None:
        """Forget caches and penalties: the next ``plan`` starts from scratch."""
        ...


@dataclass(frozen=True)
class LoopPolicy:
    """When the closed loop (``lamp.planners.closed_loop.run_object``) calls ``plan`` again."""

    #: Replan on Drift: the object missed its planned pose after a segment (Alg. 2 line 6).
    replan_on_drift: bool
    #: Replan when the plan is used up but the object is not at its goal.
    replan_when_done: bool
    #: Plans yield a full horizon (LAMP); GCo's one-step "plans" do not.
    full_horizon: bool = True
    #: A failed plan call ends the object (LAMP) or only wastes one iteration (GCo).
    failure_is_final: bool = True
    #: A push that executed but barely moved the object is reported to the planner
    #: (``report_failure``) and the rest of the plan dropped (LAMP-Lazy).
    replan_on_stall: bool = False
