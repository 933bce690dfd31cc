"""LAMP-A* (paper Alg. 1): A* over coupled object-robot states with eager verification.

A state is (q_O, q_R, parent): the object on a lattice node (or at its continuous start)
and the robots where the last verified push left them. Expanding a state verifies every
motion primitive with ``Verify`` (line 8); each success yields a successor whose edge carries the robot
trajectories T_R. States that match an explored (q_O, q_R) within a tolerance are merged
through ``UpdateCost`` (lines 26-37); the expanded state goes back into the open list with
a penalty (line 16) so that a later expansion can draw fresh model samples.

Edge costs are robot time: the steps of T_R times ``MAX_STEP`` (metres at the robot
speed). The heuristic is the object-only shortest-path cost to the goal over the same
lattice (``ReverseDistance``), in metres, times ``astar_heuristic_weight``: it sees the
obstacles, where the plain SE(2) metric would lead the search into dead ends, and states
from which the object cannot reach its goal at all are dropped.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from lamp.contract.plan import Plan, PlanStatus
from lamp.contract.robots import robot_state_key
from lamp.contract.trajectory import MAX_STEP
from lamp.contract.transition import Transition
from lamp.planners.config import PlannerConfig
from lamp.planners.lazy import goal_lattice, join_lattice
from lamp.planners.task import ManipulationTask
from lamp.planners.verifier import Verifier
from lamp.search.lattice import ObjectLattice
from lamp.search.reverse_distance import ReverseDistance


@dataclass(eq=False)
class SearchState:
    """``State(q_O, q_R, parent)`` of Alg. 1 with its cost and the edge that reached it."""

    node: object
    q_O: np.ndarray
    q_R: np.ndarray
    parent: SearchState | None
    cost: float
    edge: Transition | None = None
    children: list[tuple[SearchState, Transition]] = field(default_factory=list)
    expansions: int = 0


def edge_cost(trans: Transition) -> float:
    return trans.steps * MAX_STEP


class LampAStar:
    """LAMP-A* for one object. ``plan`` searches from scratch from the current state."""

    def __init__(self, lattice: ObjectLattice, verifier: Verifier, config: PlannerConfig) -> None:
        self.lattice = lattice
        self.verifier = verifier
        self.config = config
        self.to_goal = ReverseDistance(self.lattice, self.lattice.goal_node)
        self.clear()

    @classmethod
    def from_task(cls, task: ManipulationTask) -> LampAStar:
        """The planner for ``task``'s object: its goal lattice, verifier and config."""
        return cls(goal_lattice(task), task.verifier, task.config)

    def _robot_key(self, q_R: np.ndarray) -> tuple:
        """Explored-state key for robots: positions on a ``robot_match_tolerance`` grid, sorted
        (robots are anonymous, so permutations of one configuration are the same state)."""
        return robot_state_key(q_R, self.config.lattice.robot_match_tolerance)

    def _successors(self, state: SearchState) -> list[tuple[object, np.ndarray]]:
        if not self.lattice.is_node(state.node):  # the continuous start joins the lattice
            edges = self._start_edges
        else:
            edges = self.lattice.successors(state.node)
        return [(v, self.lattice.pose(v)) for v, _ in edges]

    def _h(self, state: SearchState) -> float:
        """Weighted object-only cost to the goal from the state's node (``inf``: no way)."""
        w = self.config.astar.astar_heuristic_weight
        if self.lattice.is_node(state.node):
            return w * self.to_goal.distance(state.node)
        return w * min((c + self.to_goal.distance(v) for v, c in self._start_edges), default=math.inf)

    def report_failure(self, trans: Transition) -> None:
        """Nothing to forget: every search starts afresh (LAMP-A* keeps no cache)."""

    def clear(self) -> None:
        """Restore the full expansion budget (``PlannerConfig.astar_expansions``); LAMP-A*
        keeps no cache."""
        #: States expanded so far by this object's searches (the budget is per object).
        self.expanded = 0

    def plan(self, q_O: np.ndarray, q_R: np.ndarray, deadline: float | None = None) -> Plan:
        """Alg. 1 from the current state. Departure: the paper's search runs until its time
        limit; here the searches of one object expand at most ``config.astar_expansions``
        states together (``BUDGET_EXHAUSTED``; a count, like the cumulative limit it stands
        for, so the result does not depend on the machine's speed) and ``deadline``
        (``TIME_LIMIT``) is only an outer cap."""
        cfg = self.config
        goal = self.lattice.goal_node
        start_node, self._start_edges = join_lattice(self.lattice, np.asarray(q_O, float))
        if self._start_edges == []:
            return Plan.failed(PlanStatus.START_BLOCKED)
        start = SearchState(start_node, np.asarray(q_O, float), np.asarray(q_R, float), None, 0.0)
        tie = itertools.count()
        # Open-list entries: (f, -g, insertion order, state). Among equal f the deeper state
        # goes first (a standard A* tie-break that avoids breadth-first plateaus).
        h_start = self._h(start)
        if h_start == math.inf:
            return Plan.failed(PlanStatus.NO_PATH)  # no object-only route: no plan either
        open_list: list = [(h_start, 0.0, next(tie), start)]  # line 2: Open.add(s_init)
        penalty: dict[int, float] = {}
        explored: dict[tuple, SearchState] = {(start_node, self._robot_key(start.q_R)): start}
        per_node: dict[object, int] = {}
        cap = cfg.astar.astar_states_per_node
        budget = cfg.astar_expansions
        while open_list:  # line 3: until the time limit is reached
            if deadline is not None and time.perf_counter() > deadline:
                return Plan.failed(PlanStatus.TIME_LIMIT, limit="deadline")
            f, _, _, s = heapq.heappop(open_list)  # line 4: Open.pop
            if f < s.cost + self._h(s) + penalty.get(id(s), 0.0) - 1e-9:
                continue  # stale entry: the state's cost or penalty changed since
            if s.node == goal:  # line 6: ReachGoal
                return self._backtrack(s)
            if self.expanded >= budget:  # departure: a count, not the clock
                return Plan.failed(PlanStatus.BUDGET_EXHAUSTED, limit="astar_max_expansions")
            self.expanded += 1
            for v, q_next in self._successors(s):  # line 7: each motion primitive
                if deadline is not None and time.perf_counter() > deadline:
                    return Plan.failed(PlanStatus.TIME_LIMIT, limit="deadline")
                trans = self.verifier.verify(s.q_O, q_next, s.q_R, attempt=s.expansions)  # line 8: Verify
                if trans is None:  # line 9: no C_R, continue
                    continue
                child = SearchState(v, q_next, trans.robot_end, s, s.cost + edge_cost(trans), trans)
                key = (v, self._robot_key(child.q_R))  # line 13: Explored
                prev = explored.get(key)
                if prev is not None:  # line 14: UpdateCost
                    self._update_cost(child, s, prev, trans, open_list, tie, penalty)
                elif cap is None or per_node.get(v, 0) < cap:  # line 15: AddChild, Open.add
                    h = self._h(child)
                    if h == math.inf:
                        continue  # the object cannot reach its goal from v
                    per_node[v] = per_node.get(v, 0) + 1
                    s.children.append((child, trans))
                    explored[key] = child
                    heapq.heappush(open_list, (child.cost + h, -child.cost, next(tie), child))
            s.expansions += 1  # line 16: Open.re-add with a penalty
            penalty[id(s)] = cfg.astar.astar_reinsert_penalty * s.expansions
            heapq.heappush(open_list, (s.cost + self._h(s) + penalty[id(s)], -s.cost, next(tie), s))
        return Plan.failed(PlanStatus.NO_PATH)

    def _update_cost(self, s: SearchState, s_curr: SearchState, s_prev: SearchState,
                     trans: Transition, open_list: list, tie, penalty: dict) -> None:
        """``UpdateCost`` (Alg. 1 lines 26-37): connect and propagate a cheaper path."""
        s_curr.children.append((s_prev, trans))  # line 27: AddChild
        if s.cost >= s_prev.cost:  # line 28: no cheaper cost
            return
        s_prev.cost, s_prev.parent, s_prev.edge = s.cost, s_curr, trans  # line 29: new cost and parent
        frontier = [(s_prev.cost, next(tie), s_prev)]  # line 30: Open_update
        while frontier:  # lines 31-37: Open_update, best-first by ascending cost
            _, _, top = heapq.heappop(frontier)
            heapq.heappush(open_list, (top.cost + self._h(top) + penalty.get(id(top), 0.0),
                                       -top.cost, next(tie), top))
            for child, edge in top.children:
                new_cost = top.cost + edge_cost(edge)
                if child.cost > new_cost + 1e-12:
                    child.cost, child.parent, child.edge = new_cost, top, edge
                    heapq.heappush(frontier, (child.cost, next(tie), child))

    @staticmethod
    def _backtrack(s: SearchState) -> Plan:
        """``BackTrack`` (line 6): the transitions from the start state to ``s``."""
        edges: list[Transition] = []
        while s.parent is not None:
            edges.append(s.edge)
            s = s.parent
        edges.reverse()
        verified = [(t.q_from[:2].copy(), t.q_to[:2].copy()) for t in edges]
        if not edges:  # the start already is the goal node
            return Plan.failed(PlanStatus.NO_PATH)
        return Plan(PlanStatus.SOLVED, edges, verified, [])
