"""Gspi: anonymous multi-robot motion planning by Goal Swapping with Priority Inheritance.

N disk robots of radius r move from continuous starts to M <= N continuous goal points;
any robot may take any goal. The planner works on the free 8-connected lattice of a
:class:`~lamp.geometry.robot_space.RobotSpace` (step ``L``, default 5 cm), extended by one
*special vertex* per start and per goal, each linked by checked straight motions to the
lattice nodes within ``link_radius`` (and starts to goals directly when close).

Each time step (GCo's Gspi, with the continuous-space changes of step 2):

1. goal swapping: for every pair of robots (within ``swap_radius`` of each other in teams
   of 32 or more), swap their goals (and priorities, which travel with goals) when that
   lowers the sum of their heuristic distances; a robot without a goal counts 0, so an
   idle robot closer to a goal takes it over;
2. one PIBT step (Okumura et al., "Priority inheritance with backtracking", AIJ 2022,
   Algorithm 1, ``funcPIBT``), iterative with an explicit stack: robots in priority order pick
   the candidate (neighbours and *wait*) that most lowers their heuristic; when a chosen
   move would hit a robot that has not decided yet, that robot decides first (priority
   inheritance) and the parent re-checks, taking its next candidate on failure
   (backtracking). Continuous-space changes: a move is checked against every decided
   robot's whole linear motion (robot-robot distance >= 2r over the step, exact), and
   descendants also keep clear of their ancestors' current positions (the continuous
   form of PIBT's no-swap rule), which keeps "stay" always valid for a failed robot; a
   child with no move compatible with its ancestors' motions may still *yield* (move
   clear of their positions) so that the way opens for the next step;
3. priorities: robots at their goal (or without one) reset to their fractional tie-break
   part, the others grow by 1;
4. deadlocks (TSWAP's rule, before step 2): a robot with no progress towards its goal for
   10 steps trades goals with a neighbour that is stuck too or rests on its goal nearer
   to the stuck robot's goal (``gspi_swaps.break_deadlocks``): two robots each
   blocking the other's last move, as in a one-cell pocket, no longer stall the team.

Heuristic: one Dijkstra per goal over the lattice (8-connected, diagonal moves cost
``L * sqrt(2)``), seeded with the goal's links, in a window around the goal that grows
only as far as the queries need (:mod:`lamp.mrmp.goal_distances`: exact distances, Dial's
buckets, memory and time growing with the area reached, not the map). Initial assignment
(:mod:`lamp.mrmp.assignment`): least longest distance first, then least sum (TSWAP's
bottleneck-then-sum), over distances computed only for the pairs that can matter (for
fleets whose exact searches would be very large, over a coarse block graph, each chosen
pair then costed exactly), for fleets over 100 robots then lowered over any-angle path
estimates where its bottleneck is far above the straight lines (:mod:`lamp.mrmp.anyangle`);
``assignment="sum"`` gives the least-sum assignment of earlier versions (with it the plans
are bit for bit those of the all-pairs implementation on teams below 32 robots). A goal no
robot can reach is reported at once. Robot-robot checks and goal swaps use neighbour
lists from a spatial hash (:mod:`lamp.mrmp.gspi_kernels`): a step costs about O(N), not
O(N^2). Lattices: 5 cm first; when that fails in a way a finer lattice can fix (a goal or
start that cannot be linked, a passage narrower than the lattice, a stall) 3 cm and then
2 cm are tried while time is left. Lattices are built once per space and reused.

Fleets (teams of 32 or more, :data:`~lamp.mrmp.gspi_kernels.ALL_PAIRS_BELOW`) follow
TSWAP more closely, for shorter makespans: goals are swapped only with a robot resting on
its goal (or without one) and only when the longer of the two ways left gets shorter (or
stays and the sum drops), so swaps never lengthen the longest way left; a robot on its way
is never pushed back more than one lattice step. After the steps, the robots that
arrive last are planned again (:mod:`lamp.mrmp.repair`), the paths of the robots that
arrive last are straightened where nothing is in the way (:mod:`lamp.mrmp.shortcut`), and
every robot then moves at its own speed along its path (:mod:`lamp.mrmp.retime`).

Output: the vertex sequence, all-wait steps dropped; below 32 robots each step cut into
the fewest equal sub-steps that keep every robot's consecutive rows <= ``max_spacing``
apart (linear motion within a step is exactly what was checked, so the rows are a
faithful sampling); for fleets, the retimed rows (as exact, and as far apart at most).

Obstacle safety: lattice edges are checked conservatively over the whole motion
(:mod:`lamp.mrmp.distance_field`); links are checked with the exact segment clearance.
Tolerances (documented in :func:`plan_paths`): a goal may lie up to ``goal_tolerance``
closer to an obstacle than the free threshold ``r + margin``; a start up to
``start_tolerance``. The rule for every motion is *non-worsening*: clearance along it is
at least ``min(threshold, clearance at its ends)``; for robot pairs, distance along a step
is at least ``min(2r, distance at the step start)``, and two robots arriving at two goals
closer than 2r (within ``goal_tolerance``) may end at that distance.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.anyangle import lower_assignment, warm_descent
from lamp.mrmp.assignment import assign, unreached_reason
from lamp.mrmp.coarse import coarse_below, get_coarse
from lamp.mrmp.distance_field import FEW, Lattice, clear_segments, get_lattice
from lamp.mrmp.effort import stall_limit, timed_effort
from lamp.mrmp.endpoints import DENSE_POINTS, exact_clearance
from lamp.mrmp.goal_distances import GoalDistances
from lamp.mrmp.gspi_inputs import PlanInputs, check_inputs
from lamp.mrmp.gspi_kernels import ALL_PAIRS_BELOW
from lamp.mrmp.gspi_loop import SearchOptions, search_with_restarts
from lamp.mrmp.links import Links, link_special_vertices
from lamp.mrmp.repair import (
    REPAIR_BUDGET,
    REPAIR_EXCHANGES,
    REPAIR_GROUP,
    REPAIR_WAIT,
    arrival_estimates,
    repair_last,
)
from lamp.mrmp.result import GspiStatus, MRMPPlan
from lamp.mrmp.retime import RETIME_QUANTA, densify, drop_waits, retime
from lamp.mrmp.shortcut import shortcut_rows
from lamp.mrmp.timed_repair import timed_repair
from lamp.scene.model import Scene

__all__ = ["GspiStatus", "MRMPPlan", "plan_paths", "warmup"]

_WARM = False


def warmup() -> None:
    """Compile (or load from Numba's cache) every kernel on a tiny problem.

    Called by the first :func:`plan_paths` of a process *before* its clock starts, so that
    compilation (about 20 s the very first time, about 0.5 s loading from the on-disk
    cache later) never eats into ``time_limit``.
    """
    global _WARM
    if _WARM:
        return
    _WARM = True
    from lamp.scene.model import Circle, Obstacle, Rectangle

    sc = Scene("warmup", (0.6, 0.6), ((0.1, 0.1), (0.1, 0.5)), (),
               (Obstacle(Circle(0.05), (0.3, 0.3, 0.0)),
                Obstacle(Rectangle((0.05, 0.05)), (0.5, 0.1, 0.0))))
    sp = RobotSpace.from_scene(sc)
    sp.is_free(np.array([[0.2, 0.2]]))
    sp.clearance(np.array([[0.2, 0.2]]))
    sp.nearest_free(np.array([0.3, 0.3]))
    warm_descent(sp)  # the fleets' descent over any-angle estimates (lamp.mrmp.anyangle)
    plan_paths(sc, sc.robot_starts_array, np.array([[0.5, 0.5], [0.1, 0.3]]), time_limit=1e6)
    # a team of 36: the lazy bottleneck assignment and the spatial hash (large teams)
    grid = np.stack(np.meshgrid(np.arange(6), np.arange(6)), -1).reshape(-1, 2) * 0.3 + 0.2
    team = Scene("warmup-team", (2.2, 2.2), tuple(map(tuple, grid.tolist())), (), ())
    plan_paths(team, grid, grid[::-1] + 0.05, time_limit=1e6)
    # the coarse assignment of large fleets (lamp.mrmp.coarse), and their goals' reach
    team_lat = get_lattice(RobotSpace.from_scene(team), 0.05)
    team_lat.any_node_near(grid, 0.075)
    cg = get_coarse(team_lat)
    one = np.zeros(1, np.int64)
    coarse_below(one, one, 1.0, one, one, grid, grid, cg.rep, cg.nbr, cg.wlen, cg.unit)
    # the shortcuts of fleets' rows (lamp.mrmp.shortcut), on rows of its own: the team's
    # plan may be too short to reach the compiled part
    rows = np.stack([grid[:2], grid[:2] + 0.03, grid[:2] + (0.06, 0.03)])
    shortcut_rows(rows, np.zeros(rows.shape[:2], bool), np.ones(2), 0.1, 0.05, sp.geometry,
                  sp.workspace, sp.threshold)
    # the retiming's exact pair checks (lamp.mrmp.retime_pairs): two moves of one step
    # that come within 2r, their ends farther apart, are checked rather than locked
    retime(np.array([[[0.2, 0.2], [0.3, 0.23]], [[0.24, 0.2], [0.34, 0.23]]]), 0.1,
           0.03 / RETIME_QUANTA, 0.02)
    # the obstacles' bucket grid of large fleets' clearance checks (lamp.mrmp.obstacle_grid)
    exact_clearance(sp, np.tile(grid[:1], (DENSE_POINTS + 1, 1)))
    clear_segments(sp.geometry, sp.workspace, np.tile(grid[:1], (FEW + 1, 1)),
                   np.tile(grid[1:2], (FEW + 1, 1)), np.full(FEW + 1, 0.01))


def plan_paths(
    scene: Scene | RobotSpace,
    starts: ArrayLike,
    goals: ArrayLike,
    object_poses: ArrayLike | None = None,
    extra_obstacles: Any = (),
    time_limit: float = 5.0,
    *,
    space: RobotSpace | None = None,
    seed: int = 0,
    lattice_step: float | tuple[float, ...] = (0.05, 0.03, 0.02),
    link_radius: float | None = None,
    goal_swapping: bool = True,
    max_spacing: float = 0.02,
    goal_tolerance: float = 0.006,
    start_tolerance: float = 0.01,
    max_steps: int | None = None,
    stall_steps: int | None = None,
    initial_goal_of: ArrayLike | None = None,
    assignment: str = "bottleneck",
    swap_radius: float | None = None,
) -> MRMPPlan:
    """Anonymous multi-robot motion planning (Gspi) for the disk robots of ``scene``.

    Parameters
    ----------
    scene: the scene (workspace, obstacles, objects, robot radius), or directly the
        :class:`RobotSpace` to plan in (as ``space=``; then ``object_poses`` and
        ``extra_obstacles`` do not apply and must be left out).
    starts: (N, 2) robot centres now.
    goals: (M, 2) goal centres, M <= N; any robot may take any goal.
    object_poses: (K, 3) current poses of the scene's objects (default: start poses); the
        objects are obstacles. extra_obstacles: more shapes (scene-file dicts).
    time_limit: seconds; on expiry the result is a failure with a reason.
    space: a prebuilt :class:`RobotSpace` to plan in (then ``object_poses`` and
        ``extra_obstacles`` are ignored); its threshold ``r + margin`` is the clearance
        every lattice position keeps. A space over a window of the map plans on the
        part of the lattice inside the window (starts and goals outside it cannot be
        linked: a failure, not an error).
    seed: tie-breaking seed (the plan is a deterministic function of all arguments).
    lattice_step: lattice spacing L (multiple of the space's 1 cm grid), or a sequence
        of them tried in turn while time is left: after a failure that a finer lattice can
        fix (a goal or start that cannot be linked, a passage narrower than the lattice, a
        stall), the next step is tried. Default (0.05, 0.03, 0.02): GCo's 5 cm first,
        then 3 and 2 cm for passages and pockets the coarser lattices miss (bands of
        free centres narrower than the step); pass a single step for fast failures.
    link_radius: how far a start or goal may be from the lattice nodes it connects to by a
        straight move (default 1.5 L).
    goal_swapping: False gives plain PIBT with a fixed optimal assignment (baseline).
    max_spacing: largest distance between consecutive output rows of a robot.
    goal_tolerance: a goal may have exact clearance down to ``threshold - goal_tolerance``
        (contacts from the manipulation model touch the object and come on a 7.8 mm pixel
        grid; 6 mm is LAMP's ``contact_tolerance``), and two goals may be
        ``2r - goal_tolerance`` apart; the last approach then never gets closer than the
        goal itself (non-worsening rule). Deeper goals: status ``INVALID_GOAL``.
    start_tolerance: the same for starts (robots left in contact after a push); motions
        out of such a start never reduce the clearance or robot distance further.
    max_steps, stall_steps: step budget, and failure after this many steps without a
        new best summed heuristic (defaults scale with the lattice; the stall at most
        256 steps for fleets of more than 100 robots, :func:`~lamp.mrmp.effort.
        stall_limit`).
    initial_goal_of: (N,) initial goal per robot (-1 none) instead of the optimal
        assignment (tests and experiments).
    assignment: the initial assignment's objective (:mod:`lamp.mrmp.assignment`):
        ``"bottleneck"`` (least longest distance, then least sum; TSWAP's) or ``"sum"``
        (least summed distance).
    swap_radius: goal swapping considers the robot pairs at most this far apart (metres;
        default twice the distance within which two robots can conflict in one step,
        ``2 * (2r + 2 * longest move)``); teams below 32 robots consider all pairs.

    Raises
    ------
    lamp.errors.InputError (a ValueError) for malformed arguments: shapes, non-finite
    values, M > N, bad limits. Starts or goals that cannot be used (outside the workspace,
    inside or overlapping obstacles beyond the tolerance, overlapping each other) are *not*
    errors: ``success=False`` with status ``INVALID_START`` / ``INVALID_GOAL``, as are
    unreachable or blocked goals (``UNREACHABLE``...).
    """
    if not _WARM:
        warmup()
    t_begin = time.perf_counter()
    inp = check_inputs(scene, starts, goals, object_poses, extra_obstacles, time_limit,
                       space=space, max_spacing=max_spacing, goal_tolerance=goal_tolerance,
                       start_tolerance=start_tolerance, assignment=assignment,
                       swap_radius=swap_radius, initial_goal_of=initial_goal_of,
                       lattice_step=lattice_step)
    S, N = inp.starts, len(inp.starts)
    if inp.bad_start or inp.bad_goal:
        status = GspiStatus.INVALID_START if inp.bad_start else GspiStatus.INVALID_GOAL
        return MRMPPlan(False, S[:, None, :].copy(), np.full(N, -1, np.int64),
                        inp.bad_start or inp.bad_goal, 0, time.perf_counter() - t_begin, {},
                        status)
    if len(inp.goals) == 0:
        return MRMPPlan(True, S[:, None, :].copy(), np.full(N, -1, np.int64), "", 0,
                        time.perf_counter() - t_begin, {})
    opts = SearchOptions(link_radius, goal_swapping, float(max_spacing), max_steps, stall_steps,
                    seed, t_begin + float(time_limit), float(time_limit), assignment,
                    swap_radius)
    return _try_lattices(inp, opts, t_begin)


def _try_lattices(inp: PlanInputs, opts: SearchOptions, t_begin: float) -> MRMPPlan:
    """Attempt each lattice step in turn until one succeeds, fails in a way a finer
    lattice cannot fix, or time runs out; the plan reports every attempt."""
    stats: dict[str, Any] = {"attempts": []}
    reasons: list[str] = []
    out: _Attempt | None = None
    for L in inp.steps:
        if out is not None and time.perf_counter() >= opts.deadline:
            reasons.append(f"time limit of {opts.time_limit:g} s reached before trying the "
                           f"{L:g} m lattice")
            out.status = GspiStatus.TIME_LIMIT
            break
        out = _attempt(inp.space, inp.starts, inp.goals, inp.c_start, inp.c_goal, float(L),
                       inp.goal0, opts)
        stats["attempts"].append({"lattice_step": float(L), **out.stats})
        stats.update(out.stats)
        if out.success:
            break
        reasons.append(f"lattice {L:g} m: {out.reason}")
        if not out.retry:
            break
    assert out is not None
    reason = "" if out.success else "; ".join(reasons)
    return MRMPPlan(out.success, out.paths, out.goal_of, reason, out.iterations,
                    time.perf_counter() - t_begin, stats, out.status)


@dataclass
class _Attempt:
    success: bool
    reason: str
    paths: np.ndarray
    goal_of: np.ndarray
    iterations: int
    retry: bool  # a finer lattice may succeed (static or stall failure, time left)
    stats: dict[str, Any]
    status: GspiStatus


def _attempt(space: RobotSpace, S: np.ndarray, G: np.ndarray, c_start: np.ndarray,
             c_goal: np.ndarray, lattice_step: float, goal0: np.ndarray | None,
             opts: SearchOptions) -> _Attempt:
    """Gspi on one lattice."""
    N, M = len(S), len(G)
    lat: Lattice = get_lattice(space, lattice_step)
    stats: dict[str, Any] = {"lattice_nodes": lat.V}
    unmoved = S[:, None, :].copy()

    def failure(reason: str, status: GspiStatus, retry: bool = False) -> _Attempt:
        return _Attempt(False, reason, unmoved, np.full(N, -1, np.int64), 0, retry, stats,
                        status)

    if time.perf_counter() > opts.deadline:
        return failure(f"time limit of {opts.time_limit:g} s reached while building the "
                       f"{lattice_step:g} m lattice", GspiStatus.TIME_LIMIT)
    L = lat.step
    R = 1.5 * L if opts.link_radius is None else float(opts.link_radius)
    V = lat.V
    gv0 = V + N  # first goal vertex
    clock = time.perf_counter()
    links = link_special_vertices(space, lat, S, G, c_start, c_goal, R, stats)
    stats["time_links"] = time.perf_counter() - clock
    if not isinstance(links, Links):  # goals without any link: the reason, at once
        return failure(unreached_reason(G, links, np.zeros(M, bool)),
                       GspiStatus.UNREACHABLE, retry=True)

    # Heuristic: a lazy windowed Dijkstra per goal, seeded with the goal's links; + EPS
    # on every vertex but the goal itself (see goal_distances.EPS).
    hs = GoalDistances.build(links.goal_links, G, lat, N + M)
    no_link = np.array([len(n) == 0 for n, _ in links.goal_links], dtype=bool)
    no_link &= ~links.direct.any(axis=0)
    clock = time.perf_counter()
    coarse = get_coarse(lat) if N >= ALL_PAIRS_BELOW else None
    asg = assign(links.graph, V, hs, S, G, no_link, opts.assignment, goal0, opts.deadline,
                 coarse)
    stats["time_assignment"] = time.perf_counter() - clock
    if asg.timed_out:
        return failure(f"time limit of {opts.time_limit:g} s reached while computing "
                       "heuristic distances", GspiStatus.TIME_LIMIT)
    if asg.goal is None:
        return failure(asg.why, GspiStatus.UNREACHABLE, retry=True)
    stats["assignment_bound"] = asg.bound
    goal, cost = lower_assignment(asg, links.graph, V, hs, S, G, space, stats)

    n_side = lat.ids.shape[0] + lat.ids.shape[1]
    max_steps = int(20 * n_side + 50 * N) if opts.max_steps is None else opts.max_steps
    stall = stall_limit(n_side, N) if opts.stall_steps is None else opts.stall_steps
    clock = time.perf_counter()
    run, goal, stats["stall_restarts"] = search_with_restarts(
        links.graph, V, gv0, hs, goal, cost, 2.0 * space.radius, links, max_steps, stall,
        opts)
    stats["time_steps"] = time.perf_counter() - clock

    # Output: drop all-wait steps; for a fleet, the last robots planned again and every
    # robot at its own speed; else each step densified.
    VX = drop_waits(run.hist[: run.t + 1], links.graph.coords)
    stats["steps_removed"] = run.t + 1 - len(VX)
    if run.done and N >= ALL_PAIRS_BELOW:
        clock = time.perf_counter()
        VX, rep, work = repair_last(links.graph, V, gv0, hs, VX, goal, 2.0 * space.radius,
                                    links.max_move, REPAIR_WAIT * L, REPAIR_BUDGET,
                                    REPAIR_GROUP, REPAIR_EXCHANGES)
        stats["repaired_paths"] = rep
        stats["repair_states"] = work
        stats["time_repair"] = time.perf_counter() - clock
        clock = time.perf_counter()
        VX = drop_waits(VX, links.graph.coords)
        coords = links.graph.coords
        est = arrival_estimates(VX, coords, REPAIR_WAIT * L)
        P, stats["shortcuts"] = shortcut_rows(coords[VX], np.greater_equal(VX, gv0), est,
                                              2.0 * space.radius, links.max_move,
                                              space.geometry, space.workspace,
                                              space.threshold)
        stats["time_shortcut"] = time.perf_counter() - clock
        clock = time.perf_counter()
        paths, span, times = retime(P, 2.0 * space.radius, L / RETIME_QUANTA,
                                    opts.max_spacing, times=True)
        stats["time_retime"] = time.perf_counter() - clock
        clock = time.perf_counter()
        (paths, goal, stats["timed_repairs"], stats["timed_states"],
         stats["timed_groups"]) = timed_repair(
            paths, times, links.graph, V, gv0, hs, goal, 2.0 * space.radius,
            L / RETIME_QUANTA, links.max_move, opts.max_spacing, space.geometry,
            space.workspace, space.threshold, **timed_effort(N, span, asg.floor))
        stats["time_timed_repair"] = time.perf_counter() - clock
    else:
        paths = densify(links.graph.coords[VX], opts.max_spacing)
    reason = run.reason
    if run.done:
        # independent of the search's bookkeeping: every goal held by exactly one robot
        held = goal >= 0
        final_ok = np.all(np.hypot(*(paths[held, -1] - G[goal[held]]).T) <= 1e-9)
        if final_ok and np.all(np.bincount(goal[held], minlength=M) == 1):
            return _Attempt(True, "", paths, goal, run.t, False, stats, GspiStatus.SOLVED)
        # pragma: no cover - the search's bookkeeping disagrees with its output
        raise AssertionError("Gspi internal error: final positions do not match the goals")
    return _Attempt(False, reason, paths, goal, run.t, run.retry, stats, run.status)
