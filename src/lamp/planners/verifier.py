"""Verify, as a ``Verifier``: can the robots realise one object transition? (Alg. 1 lines 17-25)

A :class:`Verifier` is built from three narrow pieces and a few numbers:

- a manipulation model (``lamp.manip.proposals.ProposalModel``): motion -> K proposals,
  asked through its :class:`~lamp.planners.proposal_cache.ProposalCache`;
- a :class:`~lamp.planners.robot_routing.RobotValidity`: the robots' free space with the
  manipulated object at a given pose (free points, free segments, nearest free spot) over
  a window of the map, and without the object around it;
- a :class:`~lamp.planners.robot_routing.MultiRobotPlanner`: paths for all robots to
  goals in such a space (Gspi, ``GspiRouter``);
- its numbers: ``planners.config.VerifyConfig`` (``PlannerConfig.verify``).

It owns its proposal cache and its counters (``lamp.planners.task_stats.TaskStats``).
Planners hold a ``Verifier`` and never the task that built it (``ManipulationTask.verifier``).

``verify`` follows the algorithm (paper Sec. III-A-1): for each budget B = min(N,
max_budget) down to 1 (line 19), draw K proposals from the manipulation model (line 20),
drop those whose contacts or push paths collide with the obstacles, the border, the object
or each other (line 21, ``Collide``: ``lamp.planners.collide``), pair robots with contacts
by shortest distance (:func:`assign_to_contacts`) and send unpaired robots to waiting
spots out of the push's way (line 22, ``Reassign``), and ask the multi-robot planner
(Gspi) for approach paths T_move (line 23). The first success returns (line 24) the
transition T_R = T_move (+) T_manip (T_manip: :func:`push_paths`); otherwise ``verify``
returns None (line 25, failure). The GCo baselines take the unverified path instead: one
fresh model sample (``proposals.sample``), no ``Collide``, then ``route_push``.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from lamp.contract.trajectory import concat, hold, retime, straight_moves
from lamp.contract.transition import Transition
from lamp.geometry import se2
from lamp.geometry.shapes import signed_distance
from lamp.mrmp.gspi import GspiStatus
from lamp.planners.bystanders import (
    BYSTANDER_GAP,
    bystanders,
    route_movers,
    standing_on_goal,
)
from lamp.planners.collide import usable_mask
from lamp.planners.config import VerifyConfig
from lamp.planners.proposal_cache import ProposalCache
from lamp.planners.robot_routing import MultiRobotPlanner, RobotValidity, Window
from lamp.planners.task_stats import TaskStats
from lamp.scene.model import Shape

__all__ = ["Verifier", "assign_to_contacts", "push_paths"]

#: How far (m) the breadth-first search for a robot's waiting spot may go.
WAIT_SEARCH_RADIUS = 1.0
#: Multi-robot planner failures that a larger robot-space window may fix.
_WINDOW_BOUND = frozenset({GspiStatus.UNREACHABLE, GspiStatus.STALLED, GspiStatus.STEP_BUDGET})


def assign_to_contacts(q_R: np.ndarray, contacts: np.ndarray) -> tuple[np.ndarray, float]:
    """Optimal robot-to-contact pairing by Euclidean distance: (paired robot rows, total)."""
    cost = np.linalg.norm(q_R[:, None, :] - contacts[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    return rows, float(cost[rows, cols].sum())


def push_paths(end_of_move: np.ndarray, goal_of: np.ndarray, pushes_world: np.ndarray) -> np.ndarray:
    """T_manip for all N robots: robot at contact j follows push j, the others hold."""
    n = end_of_move.shape[0]
    h = pushes_world.shape[1]
    manip = hold(end_of_move, h)
    for i in range(n):
        j = int(goal_of[i])
        if 0 <= j < pushes_world.shape[0]:
            manip[i] = pushes_world[j]
            manip[i, 0] = end_of_move[i]
    return retime(manip)


class Verifier:
    """``Verify``, ``Reassign``, the approach and the re-route for one object, with its
    proposal cache and counters (``stats``)."""

    def __init__(self, model: Any, shape: Shape, robot_radius: float, n_robots: int,
                 robots: RobotValidity, route: MultiRobotPlanner, params: VerifyConfig,
                 seed: int = 0) -> None:
        self.shape = shape
        self.robot_radius = float(robot_radius)
        self.n_robots = int(n_robots)
        self.robots = robots
        self.route = route
        self.params = params
        self.stats = TaskStats()
        #: The model's proposals for this object, cached; counted in ``stats``.
        self.proposals = ProposalCache(model, shape, robot_radius, params.k,
                                       params.contact_tolerance, seed, self.stats)

    # ------------------------------------------------------------------ Collide
    def _usable_proposals(self, q_from: np.ndarray, q_R: np.ndarray, motion: np.ndarray,
                          budget: int, attempt: int) -> list[np.ndarray]:
        """Lines 20-21: the K proposals (C_R, T_manip) that pass ``Collide``, nearest to the robots first.

        Ordering by the optimal robot-to-contact distance is our addition: Gspi is tried on
        the candidates that need the shortest approach first, which shortens the makespan and
        keeps consecutive pushes in the same direction from reshuffling the robots.
        """
        cands = self.proposals.push_candidates(motion, budget, attempt)
        kept: list[tuple[float, int, np.ndarray]] = []
        for idx in np.flatnonzero(usable_mask(self.robots, q_from, cands)):
            pushes_local = cands.pushes_local[idx]
            contacts = se2.transform_points(q_from, pushes_local[:, 0])
            kept.append((assign_to_contacts(q_R, contacts)[1], int(idx), pushes_local))
        kept.sort(key=lambda item: (item[0], item[1]))
        return [p for _, _, p in kept]

    def _unreachable(self, q_from: np.ndarray, q_R: np.ndarray) -> Callable[[np.ndarray], bool]:
        """For push paths (B, H, 2, object frame at ``q_from``): whether the contacts cannot
        each get a robot of their own inside the robots' space (object at ``q_from``, the
        first window ``approach`` plans in): some free region of it holds more contacts
        than robots (Hall's condition; a robot reaches exactly the contacts of its region),
        so that no approach inside that window reaches them all. Always False for a space
        that cannot tell its regions apart.

        The answer is that window's, but it is first sought in the object's own window
        (``robots.window(q_from)``, the robots inside it): regions only merge as a window
        grows, so contacts that each get a robot there get one in the larger window too.
        The larger window's space (over the robots' whole spread: a map-sized field for a
        team spread over a large map) is built only for proposals that fail there."""
        def hall(space: Any, robots: np.ndarray) -> Callable[[np.ndarray], bool]:
            """Whether contacts each get a robot of ``robots`` in their region of ``space``."""
            components = getattr(space, "components", None)
            if components is None:
                return lambda contacts: True
            held = Counter(components(robots).tolist())
            return lambda contacts: all(n <= held.get(c, 0) for c, n in
                                        Counter(components(contacts).tolist()).items())

        own = hall(self.robots.robot_space_at(q_from, self.robots.window(q_from)),
                   q_R[self._near(q_from, q_R)])
        wide: list[Callable[[np.ndarray], bool]] = []  # built on first need

        def unreachable(pushes_local: np.ndarray) -> bool:
            contacts = se2.transform_points(q_from, np.asarray(pushes_local)[:, 0])
            if own(contacts):
                return False
            if not wide:
                wide.append(hall(self.robots.robot_space_at(
                    q_from, self.robots.window(q_from, q_R)), q_R))
            return not wide[0](contacts)
        return unreachable

    def _near(self, q_from: np.ndarray, q_R: np.ndarray) -> np.ndarray:
        """(N,) whether each robot stands in the object's own window at ``q_from``
        (``robots.window(q_from)``: its bounding box grown by the window margin)."""
        x0, y0, x1, y1 = self.robots.window(q_from)
        return (q_R[:, 0] >= x0) & (q_R[:, 0] <= x1) & (q_R[:, 1] >= y0) & (q_R[:, 1] <= y1)

    def _too_wide(self, window: Window) -> bool:
        """Whether ``window`` exceeds ``max_window_side``: ``approach`` grows no window
        past it."""
        x0, y0, x1, y1 = window
        return max(x1 - x0, y1 - y0) > self.robots.max_window_side

    def _window_final(self, q_from: np.ndarray, q_R: np.ndarray) -> bool:
        """Whether ``approach`` would plan only in the first window for robots at ``q_R``
        because the robots stand so far apart that the doubled one is too wide."""
        return self._too_wide(self.robots.window(q_from, q_R, 2.0))

    def can_reach(self, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
                  attempt: int = 0) -> bool:
        """Whether some proposal for ``q_from -> q_to`` (any budget) passes ``Collide`` with
        contacts the robots at ``q_R`` can reach (``_unreachable``): a cheap test (model
        samples and grid lookups, no Gspi) before a ``verify`` that would otherwise fail."""
        q_from, q_to = np.asarray(q_from, float), np.asarray(q_to, float)
        q_R = np.asarray(q_R, float)
        motion = se2.relative(q_from, q_to)
        unreachable = None
        for budget in range(min(self.n_robots, self.params.max_budget), 0, -1):
            for pushes_local in self._usable_proposals(q_from, q_R, motion, budget, attempt):
                unreachable = unreachable or self._unreachable(q_from, q_R)
                if not unreachable(pushes_local):
                    return True
        return False

    # ------------------------------------------------------------------ Reassign
    def reassign(self, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
                 contacts: np.ndarray, pushes_world: np.ndarray) -> np.ndarray:
        """``Reassign`` (Alg. 1 line 22): goals for all N robots.

        Robots are paired with contacts by shortest distance (an optimal assignment); every
        unpaired robot gets a waiting spot: the nearest collision-free place, found by a
        breadth-first search from where it stands, that keeps clear of the object's swept
        motion and of the push paths. Returns (N, 2) goals; rows 0..B-1 are the contacts.
        """
        n, b = q_R.shape[0], contacts.shape[0]
        goals = np.empty((n, 2))
        goals[:b] = contacts
        if b == n:
            return goals
        rows, _ = assign_to_contacts(q_R, contacts)
        paired = np.zeros(n, bool)
        paired[rows] = True
        unpaired = [i for i in range(n) if not paired[i]]
        r = self.robot_radius
        swept = se2.interpolate(q_from, q_to, np.linspace(0.0, 1.0, 5))
        keep_out = [pushes_world.reshape(-1, 2)]
        chosen: list[np.ndarray] = []

        def clear_of_push(points: np.ndarray) -> np.ndarray:
            ok = np.ones(points.shape[0], dtype=bool)
            for pose in swept:
                local = se2.inverse_transform_points(pose, points)
                ok &= signed_distance(self.shape, local) >= 2 * r
            for pts in keep_out + chosen:
                d = np.linalg.norm(points[:, None, :] - np.asarray(pts).reshape(-1, 2)[None],
                                   axis=2)
                ok &= d.min(axis=1) >= 3 * r
            return ok

        # departure: an unpaired robot clear of the push and far from the motion keeps
        # its place and is left out of the window (``lamp.planners.bystanders``)
        far = bystanders(lambda pts: self.robots.window(q_from, pts), q_R, paired,
                         ~paired & clear_of_push(q_R), 2 * r + BYSTANDER_GAP)
        space = self.robots.robot_space_at(q_from, self.robots.window(q_from, q_R[~far]))
        for slot, i in enumerate(unpaired):
            if far[i]:
                goals[b + slot] = q_R[i]
                continue
            spot = space.nearest_free(q_R[i], accept=clear_of_push,
                                      max_distance=WAIT_SEARCH_RADIUS)
            if spot is None:
                spot = q_R[i]
            goals[b + slot] = spot
            chosen.append(np.asarray(spot).reshape(1, 2))
        return goals

    def leave_contact(self, q_from: np.ndarray, q_R: np.ndarray) -> np.ndarray:
        """Short straight moves that take robots out of collision before they are routed.

        After a push the robots stand touching the object; drift can leave one a few mm
        inside its configuration-space obstacle. Such a robot first backs off to the nearest
        free configuration (a move of at most a few centimetres, away from the object).
        Departure: only robots in the object's own window (``robots.window(q_from)``: its
        bounding box grown by ``WINDOW_MARGIN``) are looked at; one beyond it took no
        part in the push and stays where it stands (a space over the whole team's spread
        cost a map-sized field per Verify on large maps).
        """
        near = self._near(q_from, q_R)
        space = self.robots.robot_space_at(q_from, self.robots.window(q_from, q_R[near]))
        ends = self._freed(space, q_R, near)
        return q_R[:, None, :].copy() if ends is None else straight_moves(q_R, ends)

    @staticmethod
    def _freed(space: Any, points: np.ndarray, which: np.ndarray) -> np.ndarray | None:
        """``points`` with each of ``which`` that is not free in ``space`` moved to its
        nearest free spot there (kept where none is found); None when all of them are
        free. ``leave_contact`` asks it in the object's own window; ``approach`` again in
        the routing space, for a robot routed from beyond that window that stands touching
        another body (a team that placed its object last, under actuation noise): Gspi
        would refuse its start on every call."""
        idx = np.flatnonzero(which)
        stuck = idx[~space.is_free(points[idx])] if len(idx) else idx
        if len(stuck) == 0:
            return None
        ends = points.copy()
        for i in stuck:
            spot = space.nearest_free(points[i])
            if spot is not None:
                ends[i] = spot
        return ends

    # ------------------------------------------------------------------ approach
    def approach(self, q_from: np.ndarray, q_R: np.ndarray,
                 goals: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """Gspi (Alg. 1 line 23): paths for all robots to ``goals``; (paths, goal_of) or None.

        The planner works in the robot space over ``robots.window(q_from, q_R)``; when it
        fails in a way a larger window may fix (a goal unreachable, a stall, the step budget;
        not the time limit nor an invalid start or goal) and the window does not hold the
        whole map, the window's margin and least side are doubled (up to
        ``robots.max_window_side``) and it tries again. Gspi ends on its step and stall
        counts; ``gspi_time_limit`` caps all the windows' calls together, as an outer
        wall-clock cap."""
        robots = self.robots
        backoff = self.leave_contact(q_from, q_R)
        starts = backoff[:, -1]
        self.stats.gspi_calls += 1
        t_end = time.perf_counter() + self.params.gspi_time_limit
        scale = 1.0
        own_goal = standing_on_goal(starts, goals)
        pad = 2 * self.robot_radius + BYSTANDER_GAP
        while True:
            # departure: robots standing on their goal far outside the window the others
            # need hold still and are left out of routing (``lamp.planners.bystanders``)
            held = bystanders(lambda pts, s=scale: robots.window(q_from, pts, s), q_R,
                              own_goal < 0, own_goal >= 0, pad)
            space = robots.robot_space_at(q_from, robots.window(q_from, q_R[~held], scale))
            freed = self._freed(space, starts, ~held)
            if freed is not None:
                backoff, starts = concat(backoff, straight_moves(starts, freed)), freed
            # Contacts deeper than the tolerance or robots left overlapping come back as a
            # failed plan (status INVALID_GOAL / INVALID_START), like any other infeasible
            # approach.
            plan = route_movers(self.route, q_from, starts, goals, own_goal, held, space,
                                max(1e-3, t_end - time.perf_counter()))
            if plan.success:
                break
            if plan.status is GspiStatus.TIME_LIMIT:
                self.stats.gspi_timeouts += 1
            wider = robots.window(q_from, q_R[~held], 2.0 * scale)
            if (space.covers_workspace or plan.status not in _WINDOW_BOUND
                    or self._too_wide(wider) or time.perf_counter() >= t_end):
                return None
            scale *= 2.0
        self.stats.gspi_success += 1
        return concat(backoff, plan.paths), np.asarray(plan.goal_of)

    def route_push(self, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
                   pushes_local: np.ndarray, *, edge: tuple | None = None,
                   deadline: float | None = None) -> Transition | None:
        """Robot trajectories for one chosen push (``Reassign`` and Gspi, lines 22-23), or None.

        The push paths ``pushes_local`` (object frame at ``q_from``) are placed in the world,
        the robots are paired with their contacts or sent to waiting spots (``Reassign``) and
        routed there (``approach``); the push itself follows. Shared by ``verify``,
        ``reroute`` and the GCo baselines. With a ``deadline`` (``time.perf_counter``
        seconds) that has passed after ``Reassign``, no route is planned and the answer is
        None.
        """
        pushes_world = se2.transform_points(q_from, pushes_local)
        contacts = pushes_world[:, 0]
        goals = self.reassign(q_from, q_to, q_R, contacts, pushes_world)
        if deadline is not None and time.perf_counter() > deadline:
            return None
        routed = self.approach(q_from, q_R, goals)
        if routed is None:
            return None
        move, goal_of = routed
        return Transition(
            q_from=q_from, q_to=q_to, contacts=contacts, pushes_local=pushes_local,
            move=move, manip=push_paths(move[:, -1], goal_of, pushes_world), edge=edge,
        )

    # ------------------------------------------------------------------ Verify
    def verify(self, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
               attempt: int = 0) -> Transition | None:
        """``Verify`` (Alg. 1 lines 17-25): robot trajectories that move the object
        ``q_from -> q_to``; counts ``stats.verify_calls`` and, on success, ``verify_success``."""
        self.stats.verify_calls += 1
        q_from = np.asarray(q_from, float)
        q_to = np.asarray(q_to, float)
        q_R = np.asarray(q_R, float)
        motion = se2.relative(q_from, q_to)
        top = min(self.n_robots, self.params.max_budget)
        # departure: when the first window is the only one (robots far apart),
        # proposals whose contacts cannot each get a robot in it are dropped
        # before any approach is planned: Gspi could only fail on them
        unreachable = (self._unreachable(q_from, q_R) if self._window_final(q_from, q_R)
                       else None)
        final = unreachable is not None
        for budget in range(top, 0, -1):  # line 19: budgets N down to 1
            queue = self._usable_proposals(q_from, q_R, motion, budget, attempt)
            if final:
                queue = [p for p in queue if not unreachable(p)]
            for _ in range(min(len(queue), self.params.gspi_attempts_per_budget)):
                pushes_local = queue.pop(0)
                trans = self.route_push(q_from, q_to, q_R, pushes_local)  # lines 22-23: Reassign, Gspi
                if trans is not None:  # line 24: T_move found, return it
                    self.stats.verify_success += 1
                    return trans
                if unreachable is None and queue:
                    # departure: after a failed approach, the candidates whose contacts
                    # the robots can reach go first (a stable sort: nearest first within
                    # each group); with every robot behind an object wedged in a passage,
                    # contacts beyond it are near as the crow flies but out of reach
                    unreachable = self._unreachable(q_from, q_R)
                if unreachable is not None:
                    queue.sort(key=unreachable)
        return None  # line 25: return failure

    def reroute(self, cached: Transition, q_R: np.ndarray) -> Transition | None:
        """Alg. 2 lines 27-33: reuse a verified push from new robot positions (new T_move only)."""
        q_R = np.asarray(q_R, float)
        return self.route_push(cached.q_from, cached.q_to, q_R, cached.pushes_local,
                               edge=cached.edge)
