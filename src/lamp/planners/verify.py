"""Verify: can the robots realise one object transition? (paper Sec. III-A-1, Alg. 1 lines 17-25)

Given the object at ``q_from``, a requested motion to ``q_to`` and the robots at ``q_R``:
for budgets B = min(N, max_budget) down to 1 (line 19), draw K proposals from the
manipulation model (line 20), drop those whose contacts or push paths collide with the
obstacles, the border, the object or each other (line 21, ``Collide``), pair robots with
contacts by shortest distance and send unpaired robots to waiting spots out of the push's
way (line 22, ``Reassign``), and ask Gspi for approach paths (line 23). The first success
returns the transition T_R = T_move (+) T_manip (line 24); otherwise failure (line 25).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from lamp.geometry import se2
from lamp.geometry.shapes import signed_distance
from lamp.mrmp import plan_paths
from lamp.mrmp.gspi import GspiStatus
from lamp.planners.task import WINDOW_MAX_SIDE, ManipulationTask, PushCandidates
from lamp.planners.trajectory import concat, hold, retime, straight_moves

#: How far (m) the breadth-first search for a robot's waiting spot may go.
WAIT_SEARCH_RADIUS = 1.0
#: Gspi failures that a larger robot-space window may fix.
_WINDOW_BOUND = frozenset({GspiStatus.UNREACHABLE, GspiStatus.STALLED, GspiStatus.STEP_BUDGET})


@dataclass
class Transition:
    """Verified robot trajectories for one object motion (an edge of LAMP's search)."""

    q_from: np.ndarray  # (3,) object pose before the push
    q_to: np.ndarray  # (3,) planned object pose after the push
    contacts: np.ndarray  # (B, 2) contact points, world frame
    pushes_local: np.ndarray  # (B, H, 2) push paths in the object frame at q_from
    move: np.ndarray  # (N, Tm, 2) approach: robots to contacts / waiting spots
    manip: np.ndarray  # (N, Tp, 2) push: contact robots follow pushes, others hold
    #: The search edge (u, v) this transition realises, when a planner tracks it.
    edge: tuple | None = None

    @property
    def robot_paths(self) -> np.ndarray:
        """T_R = T_move (+) T_manip: the synchronised paths to execute."""
        return concat(self.move, self.manip)

    @property
    def robot_start(self) -> np.ndarray:
        return self.move[:, 0]

    @property
    def robot_end(self) -> np.ndarray:
        return self.manip[:, -1]

    @property
    def steps(self) -> int:
        """Synchronised time steps of T_R (its makespan)."""
        return int(self.move.shape[1] + self.manip.shape[1] - 1)

    @property
    def budget(self) -> int:
        return int(self.contacts.shape[0])


def usable_mask(task: ManipulationTask, q_from: np.ndarray, cands: PushCandidates) -> np.ndarray:
    """``Collide`` (Alg. 1 line 21) for all K candidates at once: which are usable at ``q_from``?

    A proposal is rejected when a contact or any point of a push path leaves the robots'
    free space (obstacles, other objects, border), when a contact lies inside the object
    (deeper than ``contact_tolerance``), or when two pushing robots come closer than 2r.
    The pose-independent tests come precomputed (``PushCandidates.intrinsic_ok``); the
    free-space test is one query for all the candidates' points, in the robots' space
    around ``q_from`` (a point beyond its window counts as not free).
    """
    ok = cands.intrinsic_ok.copy()
    if not ok.any():
        return ok
    free = task.static_space_near(q_from).is_free(
        se2.transform_points(q_from, cands.dense_points))
    ok &= np.logical_and.reduceat(free, cands.starts[:-1])
    return ok


def assign_to_contacts(q_R: np.ndarray, contacts: np.ndarray) -> tuple[np.ndarray, float]:
    """Optimal robot-to-contact pairing by Euclidean distance: (paired robot rows, total)."""
    cost = np.linalg.norm(q_R[:, None, :] - contacts[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    return rows, float(cost[rows, cols].sum())


def reassign(task: ManipulationTask, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
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
    unpaired = [i for i in range(n) if i not in set(rows.tolist())]
    space = task.robot_space_at(q_from, task.window(q_from, q_R))
    r = task.robot_radius
    swept = se2.interpolate(q_from, q_to, np.linspace(0.0, 1.0, 5))
    keep_out = [pushes_world.reshape(-1, 2)]
    chosen: list[np.ndarray] = []

    def clear_of_push(points: np.ndarray) -> np.ndarray:
        ok = np.ones(points.shape[0], dtype=bool)
        for pose in swept:
            local = se2.inverse_transform_points(pose, points)
            ok &= signed_distance(task.shape, local) >= 2 * r
        for pts in keep_out + chosen:
            d = np.linalg.norm(points[:, None, :] - np.asarray(pts).reshape(-1, 2)[None], axis=2)
            ok &= d.min(axis=1) >= 3 * r
        return ok

    for slot, i in enumerate(unpaired):
        spot = space.nearest_free(q_R[i], accept=clear_of_push, max_distance=WAIT_SEARCH_RADIUS)
        if spot is None:
            spot = q_R[i]
        goals[b + slot] = spot
        chosen.append(np.asarray(spot).reshape(1, 2))
    return goals


def leave_contact(task: ManipulationTask, q_from: np.ndarray, q_R: np.ndarray) -> np.ndarray:
    """Short straight moves that take robots out of collision before they are routed.

    After a push the robots stand touching the object; drift can leave one a few mm
    inside its configuration-space obstacle. Such a robot first backs off to the nearest
    free configuration (a move of at most a few centimetres, away from the object).
    """
    space = task.robot_space_at(q_from, task.window(q_from, q_R))
    free = space.is_free(q_R)
    if np.all(free):
        return q_R[:, None, :].copy()
    ends = q_R.copy()
    for i in np.flatnonzero(~free):
        spot = space.nearest_free(q_R[i])
        if spot is not None:
            ends[i] = spot
    return straight_moves(q_R, ends)


def approach(task: ManipulationTask, q_from: np.ndarray, q_R: np.ndarray,
             goals: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Gspi (Alg. 1 line 23): paths for all robots to ``goals``; (paths, goal_of) or None.

    Gspi plans in the robot space over ``task.window(q_from, q_R)``; when it fails in a
    way a larger window may fix (a goal unreachable, a stall, the step budget; not the
    time limit nor an invalid start or goal) and the window does not hold the whole map, the
    window's margin and least side are doubled (up to ``WINDOW_MAX_SIDE``) and Gspi tries
    again. Gspi ends on its step and stall counts; ``gspi_time_limit`` caps all the
    windows' calls together, as an outer wall-clock cap."""
    backoff = leave_contact(task, q_from, q_R)
    starts = backoff[:, -1]
    task.stats.gspi_calls += 1
    t_end = time.perf_counter() + task.config.gspi_time_limit
    scale = 1.0
    while True:
        window = task.window(q_from, q_R, scale)
        space = task.robot_space_at(q_from, window)
        # Contacts deeper than the tolerance or robots left overlapping come back as a failed
        # plan (status INVALID_GOAL / INVALID_START), like any other infeasible approach.
        plan = plan_paths(
            task.scene, starts, goals, object_poses=task.poses_with(q_from),
            time_limit=max(1e-3, t_end - time.perf_counter()), space=space,
            seed=task.seed, goal_tolerance=task.config.contact_tolerance,
        )
        if plan.success:
            break
        if plan.status is GspiStatus.TIME_LIMIT:
            task.stats.gspi_timeouts += 1
        wider = task.window(q_from, q_R, 2.0 * scale)
        if (space.covers_workspace or plan.status not in _WINDOW_BOUND
                or max(wider[2] - wider[0], wider[3] - wider[1]) > WINDOW_MAX_SIDE
                or time.perf_counter() >= t_end):
            return None
        scale *= 2.0
    task.stats.gspi_success += 1
    return concat(backoff, plan.paths), np.asarray(plan.goal_of)


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


def route_push(task: ManipulationTask, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
               pushes_local: np.ndarray, *, edge: tuple | None = None,
               deadline: float | None = None) -> Transition | None:
    """Robot trajectories for one chosen push (``Reassign`` and Gspi, Alg. 1 lines 22-23), or None.

    The push paths ``pushes_local`` (object frame at ``q_from``) are placed in the world,
    the robots are paired with their contacts or sent to waiting spots (``Reassign``) and
    Gspi routes them there (``approach``); the push itself follows. Shared by ``verify``,
    ``reroute`` and the GCo baselines. With a ``deadline`` (``time.perf_counter`` seconds)
    that has passed after ``Reassign``, Gspi is not called and the answer is None.
    """
    pushes_world = se2.transform_points(q_from, pushes_local)
    contacts = pushes_world[:, 0]
    goals = reassign(task, q_from, q_to, q_R, contacts, pushes_world)
    if deadline is not None and time.perf_counter() > deadline:
        return None
    routed = approach(task, q_from, q_R, goals)
    if routed is None:
        return None
    move, goal_of = routed
    return Transition(
        q_from=q_from, q_to=q_to, contacts=contacts, pushes_local=pushes_local,
        move=move, manip=push_paths(move[:, -1], goal_of, pushes_world), edge=edge,
    )


def _usable_proposals(task: ManipulationTask, q_from: np.ndarray, q_R: np.ndarray,
                      motion: np.ndarray, budget: int, attempt: int) -> list[np.ndarray]:
    """Lines 20-21: the K proposals (C_R, T_manip) that pass ``Collide``, nearest to the robots first.

    Ordering by the optimal robot-to-contact distance is our addition: Gspi is tried on
    the candidates that need the shortest approach first, which shortens the makespan and
    keeps consecutive pushes in the same direction from reshuffling the robots.
    """
    cands = task.push_candidates(motion, budget, attempt)
    kept: list[tuple[float, int, np.ndarray]] = []
    for idx in np.flatnonzero(usable_mask(task, q_from, cands)):
        pushes_local = cands.pushes_local[idx]
        contacts = se2.transform_points(q_from, pushes_local[:, 0])
        kept.append((assign_to_contacts(q_R, contacts)[1], int(idx), pushes_local))
    kept.sort(key=lambda item: (item[0], item[1]))
    return [p for _, _, p in kept]


def verify(task: ManipulationTask, q_from: np.ndarray, q_to: np.ndarray, q_R: np.ndarray,
           attempt: int = 0) -> Transition | None:
    """``Verify`` (Alg. 1 lines 17-25): robot trajectories that move the object ``q_from -> q_to``."""
    task.stats.verify_calls += 1
    q_from = np.asarray(q_from, float)
    q_to = np.asarray(q_to, float)
    q_R = np.asarray(q_R, float)
    motion = se2.relative(q_from, q_to)
    top = min(task.n_robots, task.config.max_budget)
    for budget in range(top, 0, -1):  # line 19: budgets N down to 1
        candidates = _usable_proposals(task, q_from, q_R, motion, budget, attempt)
        for pushes_local in candidates[: task.config.gspi_attempts_per_budget]:
            trans = route_push(task, q_from, q_to, q_R, pushes_local)  # lines 22-23: Reassign, Gspi
            if trans is not None:  # line 24: T_move found, return it
                task.stats.verify_success += 1
                return trans
    return None  # line 25: return failure


def reroute(task: ManipulationTask, cached: Transition, q_R: np.ndarray) -> Transition | None:
    """Alg. 2 lines 27-33: reuse a verified push from new robot positions (new T_move only)."""
    q_R = np.asarray(q_R, float)
    return route_push(task, cached.q_from, cached.q_to, q_R, cached.pushes_local, edge=cached.edge)
