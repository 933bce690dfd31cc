"""LAMP-Lazy (paper Alg. 2): D* Lite over object poses, lazy verification, cached transitions.

D* Lite plans object-only paths on the lattice (``lamp.search``), rooted at the goal, so a
moving start is cheap to repair. ``Plan`` (Alg. 2 lines 8-42) verifies the returned path
edge by edge until it meets a pose already in ``Tree_eval`` (transitions verified on an
earlier full path to the goal); a failed edge is penalised in D* Lite (``UpdateChange``)
and the search repeats. The per-node caches D_T map robot configurations to complete robot
trajectories, so replanning after drift mostly reuses verified pushes and only re-routes
the robots (``Reassign`` and Gspi, lines 27-33).

Departure: when re-routing a cached push fails, the paper only raises the edge's cost (line
31: UpdateChange) and keeps the ``Tree_eval`` entry, so every later plan through that pose meets the
same unreachable push again (in a tight spot, until the plan iterations run out). Here the
entry is dropped as well: the next plan through the pose verifies the motion afresh (with
the next attempt's model samples, ``failures`` counts them) or goes another way.

Departure: when an edge fails, line 19 discards Tree_new, and the paper's next iteration
verifies the new path's prefix afresh although it is mostly the old one: on a 15 m haul
of 150 edges, 38 failures spent 4,000 Verify calls, 3,962 of them repeats. Here the
pushes Verify found stay known for the rest of the ``plan`` call, keyed by the edge, its
failures so far (the model samples of the attempt) and the robots' exact start, and
are taken again without a Verify call (``stats.verify_reused``). Tree_new is still
discarded: nothing reaches Tree_eval before a full path is verified, and the plan found
is the paper's, only cheaper.

Departure: a goal that no gap leads to (``lamp.search.connectivity``: the disk inscribed in
the footprint cannot get there in the plane) ends ``plan`` at once with ``SEPARATED``,
where the paper's search would exhaust the lattice to prove it (and ours then refine it
over ever larger windows): a fleet object walled in by others waits cheaply.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Hashable
from dataclasses import dataclass, field

import numpy as np

from lamp.contract.plan import Plan, PlanStatus
from lamp.contract.robots import robots_match
from lamp.contract.transition import Transition
from lamp.planners.config import PlannerConfig
from lamp.planners.recovery import recovery_push
from lamp.planners.task import ManipulationTask
from lamp.planners.verifier import Verifier
from lamp.search.connectivity import PlaneConnectivity
from lamp.search.dstar_lite import DStarLite, SearchStatus
from lamp.search.lattice import ObjectLattice
from lamp.search.refined_lattice import RefinedLattice

Node = Hashable


@dataclass
class TreeEntry:
    """``Tree_eval[q_O]`` = (q_O^next, C_R, T_manip, D_T) (Alg. 2 line 23)."""

    next_node: Node
    transition: Transition  # carries C_R and T_manip; its robots' start is one D_T key
    cache: list[tuple[np.ndarray, Transition]] = field(default_factory=list)  # D_T

    def lookup(self, q_R: np.ndarray, tolerance: float) -> Transition | None:
        """D_T[q_R]: a cached T_R whose robots started within ``tolerance`` of ``q_R``."""
        for key, trans in self.cache:
            if robots_match(key, q_R, tolerance):
                return trans
        return None


#: A continuous pose this close to a lattice node (heuristic metric) is that node.
SNAP_DISTANCE = 1e-3
#: Failed plan iterations in one ``plan`` call after which a recovery push is tried.
RECOVER_AFTER = 40
#: Recovery pushes one planner makes at most (an infeasible task must not wander).
MAX_RECOVERIES = 8
#: Only an object closer than this (m) to an obstacle counts as pinned.
RECOVERY_CLEARANCE = 0.02
#: Footprint shrinkage tried, in order, when a drifted pose touches an obstacle so that no
#: connecting motion is free at zero tolerance (the object may always move away from it).
JOIN_TOLERANCES = (0.0, 0.01, 0.02)


def goal_lattice(task: ManipulationTask) -> ObjectLattice:
    """The object lattice both LAMP planners search: anchored at the object's goal, with
    the task's object space and the configured step and heading count, and the object's
    start as the heuristic's landmark."""
    cfg = task.config
    return RefinedLattice(
        task.object_space, task.goal, step=cfg.lattice.lattice_step, n_headings=cfg.lattice.n_headings,
        landmark=task.object_poses[task.index][:2], exact=task.exact_space,
        succ_kept=cfg.loop.successor_cache_nodes,
    )


def join_lattice(lattice: ObjectLattice, q_O: np.ndarray) -> tuple[Node, list | None]:
    """The search vertex for the object at ``q_O``: a lattice node when ``q_O`` is on one,
    otherwise a virtual node (the pose tuple) with its connecting edges."""
    near = lattice.nearest_nodes(q_O, SNAP_DISTANCE)
    if near:
        return near[0][0], None
    for tol in JOIN_TOLERANCES:
        try:
            edges = lattice.start_connections(q_O, tolerance=tol)
        except ValueError:  # a footprint this thin vanishes when shrunk by tol
            break
        if edges:
            return tuple(float(v) for v in q_O), edges
    return tuple(float(v) for v in q_O), []


class LazyPlanner:
    """LAMP-Lazy for one object (Alg. 2). ``plan`` is called first and after every drift."""

    def __init__(self, lattice: ObjectLattice, verifier: Verifier, config: PlannerConfig) -> None:
        self.lattice = lattice
        self.verifier = verifier
        self.config = config
        self._plane: PlaneConnectivity | None = None
        self.clear()

    @classmethod
    def from_task(cls, task: ManipulationTask) -> LazyPlanner:
        """The planner for ``task``'s object: its goal lattice, verifier and config."""
        return cls(goal_lattice(task), task.verifier, task.config)

    def clear(self) -> None:
        """A fresh D* Lite search, an empty Tree_eval and no penalties."""
        self.dstar = DStarLite(self.lattice)
        self.dstar.initialize(self.lattice.goal_node)  # line 1: Initialize
        self.tree_eval: dict[Node, TreeEntry] = {}
        self.failures: dict[tuple[Node, Node], int] = {}
        self.penalised: list[tuple[np.ndarray, np.ndarray]] = []
        self.recoveries = 0
        self.calls = 0

    @property
    def plane(self) -> PlaneConnectivity:
        """The plane's verdict on whether the object can reach its goal at all
        (``lamp.search.connectivity``), for the footprint shrunk as far as a tolerant
        join shrinks it; built on first use."""
        if self._plane is None:
            self._plane = PlaneConnectivity(self.lattice.space, slack=max(JOIN_TOLERANCES))
        return self._plane

    def _recover(self, q_O: np.ndarray, q_R: np.ndarray, failed: Plan) -> Plan:
        """Departure: before giving up (or after ``RECOVER_AFTER`` failed iterations), when
        the object is pinned (clearance below ``RECOVERY_CLEARANCE``), try one recovery push (``lamp.planners.recovery``) that frees a pinned or wedged
        object; the loop executes it and plans again. ``failed`` is returned otherwise."""
        if (self.recoveries >= MAX_RECOVERIES
                or float(self.lattice.space.clearance(np.asarray(q_O, float))) >= RECOVERY_CLEARANCE):
            return failed  # not pinned: a push away from the walls would only wander
        trans = recovery_push(self.lattice, self.verifier, np.asarray(q_O, float),
                              np.asarray(q_R, float), attempt=self.recoveries)
        if trans is None:
            return failed
        self.recoveries += 1
        return Plan(PlanStatus.SOLVED, [trans], [(trans.q_from[:2].copy(), trans.q_to[:2].copy())],
                    list(self.penalised), partial=True)

    def _refine(self, q_O: np.ndarray) -> bool:
        """Departure: when the lattice has no path (or no edge from the object's pose), add
        off-lattice poses through the narrow passages around the object and its goal
        (``RefinedLattice.refine``) and restart D* Lite on the refined graph, keeping the
        penalties; False when nothing could be added."""
        refine = getattr(self.lattice, "refine", None)
        if refine is None or refine(np.asarray(q_O, float)) == 0:
            return False
        self.dstar = DStarLite(self.lattice)
        self.dstar.initialize(self.lattice.goal_node)
        for (u, v), n in self.failures.items():
            if self.lattice.is_node(u):
                with contextlib.suppress(ValueError):
                    self.dstar.penalize(u, v, n * self.config.lazy.edge_penalty)
        return True

    def _penalise(self, u: Node, v: Node) -> None:
        """``UpdateChange`` (lines 18 and 31): raise the cost of an edge whose verification failed."""
        n = self.failures.get((u, v), 0) + 1
        self.failures[(u, v)] = n
        self.dstar.penalize(u, v, self.config.lazy.edge_penalty)
        self.penalised.append((self.lattice.pose(u)[:2].copy(), self.lattice.pose(v)[:2].copy()))

    def report_failure(self, trans: Transition) -> None:
        """Execution showed that ``trans`` does not move the object (it stalled): forget
        it in Tree_eval and penalise its edge, so that the next Plan verifies the motion
        again with fresh model samples or takes another route."""
        if trans.edge is None:
            return
        u, v = trans.edge
        entry = self.tree_eval.get(u) if self.lattice.is_node(u) else None
        if entry is not None and entry.next_node == v:
            del self.tree_eval[u]
        with contextlib.suppress(ValueError):  # an earlier virtual start's edge: counted only
            self._penalise(u, v)

    def plan(self, q_O_now: np.ndarray, q_R_now: np.ndarray, deadline: float | None = None) -> Plan:
        """``Plan`` (Alg. 2 lines 8-42): a full-horizon plan from the current state.

        Departure: the paper's loop (lines 10-40) runs until a plan is found; here it runs at
        most ``max_plan_iterations`` times and makes at most ``max_verify_calls`` Verify
        calls (and ``lazy_verify_calls`` over all the object's calls), and D* Lite expands
        at most ``lazy_expansions`` vertices over all the object's calls (each
        ``BUDGET_EXHAUSTED``, ``Plan.limit`` naming the count): counts, so the result does
        not depend on the machine's speed; ``deadline`` (``TIME_LIMIT``) is only an outer
        cap.
        """
        self.calls += 1
        stats = self.verifier.stats
        # departure: a goal no gap leads to is refused before any search (an exhaustive
        # search, then refinement over ever larger windows, would prove it at length)
        if self.plane.separated(q_O_now, self.lattice.pose(self.lattice.goal_node)):
            return self._recover(q_O_now, q_R_now, Plan.failed(PlanStatus.SEPARATED,
                                                               self.penalised))
        per_call = stats.verify_calls + self.config.lazy.max_verify_calls
        verify_cap = (per_call, "max_verify_calls")
        if self.config.lazy_verify_calls < per_call:  # the object's budget ends it first
            verify_cap = (self.config.lazy_verify_calls, "lazy_max_object_verify")
        expanded_before = stats.search_expansions
        try:
            return self._plan(q_O_now, q_R_now, deadline, verify_cap)
        finally:
            stats.max_plan_expansions = max(stats.max_plan_expansions,
                                            stats.search_expansions - expanded_before)
            self.dstar.pack()  # until the next call: its segments run meanwhile

    def _plan(self, q_O_now: np.ndarray, q_R_now: np.ndarray, deadline: float | None,
              verify_cap: tuple[int, str]) -> Plan:
        """:meth:`plan`'s loop (lines 10-42), its Verify calls capped at ``verify_cap``
        (the count, and the name of the budget that sets it)."""
        cfg = self.config
        goal = self.lattice.goal_node
        stats = self.verifier.stats
        # the pushes Verify found in this call: (edge, its failures so far, robots' start)
        answers: dict[tuple[Node, Node, int, bytes], Transition] = {}
        for iteration in range(cfg.lazy.max_plan_iterations):
            if iteration == RECOVER_AFTER and self.calls > 1:  # a replan that keeps failing
                rescue = self._recover(q_O_now, q_R_now, Plan.failed(PlanStatus.NO_PATH))
                if rescue.solved:
                    return rescue
            if stats.verify_calls >= verify_cap[0]:
                return self._recover(q_O_now, q_R_now, Plan.failed(
                    PlanStatus.BUDGET_EXHAUSTED, self.penalised, verify_cap[1]))
            if deadline is not None and time.perf_counter() > deadline:
                return Plan.failed(PlanStatus.TIME_LIMIT, self.penalised, "deadline")
            start, edges = join_lattice(self.lattice, np.asarray(q_O_now, float))
            if edges == []:
                if self._refine(q_O_now):
                    continue
                return self._recover(q_O_now, q_R_now,
                                     Plan.failed(PlanStatus.START_BLOCKED, self.penalised))
            left = self.config.lazy_expansions - stats.search_expansions
            if left > 0:
                self.dstar.max_expansions = left
                path = self.dstar.plan_shortest_path(start, edges)  # line 11: PlanShortestPath
                stats.search_expansions += self.dstar.stats.last_expansions
            if left <= 0 or self.dstar.status is SearchStatus.EXPANSION_LIMIT:
                self.dstar.release()  # its budget is spent: no later call searches again
                return self._recover(q_O_now, q_R_now, Plan.failed(
                    PlanStatus.BUDGET_EXHAUSTED, self.penalised, "lazy_max_expansions"))
            if not path:
                if self._refine(q_O_now):
                    continue
                return self._recover(q_O_now, q_R_now,
                                     Plan.failed(PlanStatus.NO_PATH, self.penalised))
            transitions: list[Transition] = []
            tree_new: dict[Node, TreeEntry] = {}
            q_R = np.asarray(q_R_now, float)
            curr = path[0]
            failed = False
            for nxt in path[1:]:  # line 13: each q_next on P_O
                if self.lattice.is_node(curr) and curr in self.tree_eval:  # line 14: in Tree_eval, break
                    break
                attempt = self.failures.get((curr, nxt), 0)
                key = (curr, nxt, attempt, q_R.tobytes())
                trans = answers.get(key)  # departure: a push Tree_new held before line 19
                if trans is not None:
                    stats.verify_reused += 1
                elif stats.verify_calls >= verify_cap[0]:
                    return self._recover(q_O_now, q_R_now, Plan.failed(
                        PlanStatus.BUDGET_EXHAUSTED, self.penalised, verify_cap[1]))
                else:  # line 16: Verify
                    trans = self.verifier.verify(self.lattice.pose(curr), self.lattice.pose(nxt),
                                                 q_R, attempt)
                    if trans is not None:
                        answers[key] = trans
                if trans is None:  # lines 17-20: no C_R, UpdateChange
                    self._penalise(curr, nxt)
                    failed = True
                    break
                trans.edge = (curr, nxt)
                transitions.append(trans)  # line 21: T_R = T_move + T_manip
                entry = TreeEntry(nxt, trans, [(q_R.copy(), trans)])
                if self.lattice.is_node(curr):  # virtual starts are never reused
                    tree_new[curr] = entry  # line 23: Tree_new
                curr, q_R = nxt, trans.robot_end  # line 24: q_curr = q_next, T_R.last()
            if failed:
                continue
            if (curr != goal and self.lattice.is_node(curr) and curr in self.tree_eval
                    and not self._follow_tree(curr, q_R, transitions)):  # lines 25-40: Tree_eval
                continue
            self.tree_eval.update(tree_new)  # line 41: Tree_eval = Tree_new + Tree_eval
            verified = [(t.q_from[:2].copy(), t.q_to[:2].copy()) for t in transitions]
            if not transitions:  # already at the goal node
                return Plan.failed(PlanStatus.NO_PATH, self.penalised)
            return Plan(PlanStatus.SOLVED, transitions, verified, list(self.penalised))
        return self._recover(q_O_now, q_R_now, Plan.failed(
            PlanStatus.BUDGET_EXHAUSTED, self.penalised, "max_plan_iterations"))


    def _follow_tree(self, curr: Node, q_R: np.ndarray, transitions: list[Transition]) -> bool:
        """Alg. 2 lines 25-40 (Tree_eval): from ``curr`` to the goal along the verified
        tree, appending each push to ``transitions``: a cached T_R for robots at ``q_R``
        (line 38: reuse cached) or new approach paths (lines 27-35: Reassign, Gspi).
        False when the chain is cut (a push forgotten below, or one the robots cannot
        reach from here, then forgotten and penalised): the caller plans again."""
        goal = self.lattice.goal_node
        tol = self.config.lattice.robot_match_tolerance
        walked: list[Node] = []
        while curr != goal:
            entry = self.tree_eval.get(curr)
            if entry is None:  # the chain was cut below (a forgotten push): the
                for n in walked:  # part above it is verified afresh next iteration
                    self.tree_eval.pop(n, None)
                return False
            walked.append(curr)
            trans = entry.lookup(q_R, tol)  # line 38: reuse cached
            if trans is None:  # lines 27-35: Reassign, Gspi: new T_move for these robots
                trans = self.verifier.reroute(entry.transition, q_R)
                if trans is None:
                    # departure: the cached push cannot be reached from here, so
                    # it is forgotten (not only penalised): the next iteration
                    # verifies this motion afresh, with new model samples
                    del self.tree_eval[curr]
                    self._penalise(curr, entry.next_node)
                    return False
                entry.cache.append((q_R.copy(), trans))  # line 35: cache
            else:
                self.verifier.stats.cache_hits += 1
            transitions.append(trans)
            curr, q_R = entry.next_node, trans.robot_end
        return True
