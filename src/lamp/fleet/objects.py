"""One object's life in the fleet schedule: LAMP's closed loop, started anew whenever the
world changed around its plan.

:func:`object_main` is what ``Fleet`` runs in object ``k``'s thread: a
:class:`~lamp.planners.runner.ClosedLoopRunner` loop on the object's sub-team
(``Fleet.view``), in the world as it is when the loop starts (``sub_scene``: every other
robot a disk obstacle where it stands; once a loop's planner found no plan, only those
within ``replan_near`` of its team, ``FleetConfig``). A team that stands far from its
object first drives to it (``lamp.fleet.transit``; its hops cross the claims of objects
ranked above rather than stop in them); a team whose object is placed moves
out of the others' way before its robots go free (``lamp.fleet.parking``). A loop that
ends with ``WORLD_CHANGED`` (its segment was declined, or it found no plan while others
moved) or ``TEAM_CHANGED`` (a robot of its sub-team failed: ``Fleet`` took it out of the
team) is followed by a new one, and so is a loop that took the object aside to a detour's
end (``lamp.fleet.makeway``), within the object's segment limit, its planners' count
budgets and its cumulative planning limit (``planners.series``: when one of them ends it,
the object's failure names that limit); the object's outcome merges every loop's (each
new loop counts as a replan). The objects moving at once share ``config.SPACE_CACHE_MB``
of robot-space cache, and their lattices keep no successor lists
(``successor_cache_nodes`` = 0): on a depot's lattices of some 10^5-10^6 nodes a search
asks for 1.1 lists a node it expands, so kept lists were asked again 5 % of the time on
the 36-robot depot and held 130 MB at the 144-robot depot's peak, and rebuilding one from
the validity store costs about what keeping it does. What the loops ask of the fleet is
:class:`LoopHost`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection
from typing import Protocol

import numpy as np
import shapely

from lamp.contract.events import SegmentEvent
from lamp.contract.goals import goal_errors
from lamp.contract.result import ObjectResult
from lamp.contract.runner import LoopEnd, ObjectOutcome
from lamp.fleet.config import MIN_SPACE_CACHE_MB, SPACE_CACHE_MB, FleetConfig
from lamp.fleet.makeway import with_goal
from lamp.fleet.parking import park
from lamp.fleet.stats import FleetStats
from lamp.fleet.transit import transit
from lamp.fleet.view import FleetView, SharedWorld
from lamp.planners.closed_loop import NO_PLAN_YET
from lamp.planners.runner import ClosedLoopRunner
from lamp.planners.series import LoopSeries
from lamp.planners.team import team_scene
from lamp.scene.model import Scene

__all__ = ["LoopHost", "given_up", "object_main", "sub_scene"]


class LoopHost(SharedWorld, Protocol):
    """What an object's loops ask of the fleet (``Fleet`` is one): its views and state
    are read, and its decisions asked for, through these only."""

    @property
    def scene(self) -> Scene:
        """The scene in force: every object's goal is its current task's."""
        ...

    @property
    def stats(self) -> FleetStats:
        """The schedule's counters (transit hops and parking moves are counted here)."""
        ...

    def moving(self) -> int:
        """How many objects are active."""
        ...

    def view(self, k: int) -> FleetView: ...

    def detour_of(self, k: int) -> np.ndarray | None:
        """The pose object ``k`` moves to before its goal (``fleet.makeway``), if any."""
        ...

    def wait_for_team(self, k: int) -> None: ...

    def world_taken(self, k: int) -> None: ...

    def detour_done(self, k: int) -> None: ...

    def mark_placed(self, k: int) -> bool: ...

    def needed_by_others(self, k: int) -> shapely.Geometry | None:
        """What the other unplaced objects still need (``parking.needed_by_others``)."""
        ...

    def claims_above(self, k: int) -> list[shapely.Geometry]:
        """The claims object ``k``'s transit hops must not end in (``Board.claims_above``)."""
        ...

    def following(self, k: int) -> dict[int, np.ndarray]:
        """The objects object ``k``'s new loop plans at other poses (``fleet.follow``)."""
        ...


def sub_scene(scene: Scene, team: list[int], robot_positions: np.ndarray,
              near: float = math.inf, skip: Collection[int] = ()) -> Scene:
    """``scene`` as ``team`` plans in it (``team.team_scene``): its robots only, where
    they stand now, and every other robot within ``near`` (m) of one of them, but those
    of ``skip``, a disk obstacle where it stands."""
    pos = np.asarray(robot_positions, float)
    mine = pos[list(team)]
    reach = (np.full(len(pos), True) if not math.isfinite(near) or not len(mine) else
             np.hypot(*np.moveaxis(pos[:, None, :2] - mine[None, :, :2], -1, 0)).min(axis=1)
             <= near)
    others = {i: pos[i] for i in range(scene.n_robots)
              if i not in team and reach[i] and i not in skip}
    return team_scene(scene, list(team), others, mine)


def given_up(scene: Scene, k: int, pose: np.ndarray, why: str) -> ObjectOutcome:
    """The outcome of object ``k``, never started, standing at ``pose``: failed ``why``."""
    pose = np.asarray(pose, float)
    goal = np.asarray(scene.objects[k].goal, float)
    pos_err, rot_err = goal_errors(pose, goal)
    return ObjectOutcome(ObjectResult(
        success=False, final_pose=[float(v) for v in pose], goal=[float(v) for v in goal],
        position_error=pos_err, orientation_error=rot_err, left_workspace=False, segments=0,
        full_horizon_plan=False, failure_reason=why, replans=0, planning_time_s=0.0))


def _share(own: float, total: float, least: float, moving: int) -> float:
    """An object's part of a cache budget the ``moving`` objects share: ``total / moving``,
    at most its own setting ``own``, at least ``least``."""
    return max(least, min(own, total / moving))


def object_main(runner: ClosedLoopRunner, observe: Callable[[SegmentEvent], None],
                settings: FleetConfig) -> Callable[[LoopHost, int], ObjectOutcome]:
    """The function ``Fleet`` runs for each object (see the module docstring), with the
    fleet's ``settings``."""

    def main(fleet: LoopHost, k: int) -> ObjectOutcome:
        scene, cfg = fleet.scene, runner.config  # the object's goal: its task's
        seed = runner.seed * 1000 + k  # the object's tasks' seed (``ClosedLoopRunner.loop``)
        series = LoopSeries.of(scene, k, fleet.executor.object_poses[k], cfg, planning=True)
        near = settings.plan_near
        while True:
            moving = max(1, fleet.moving())
            config = series.config(cfg).but(
                space_cache_mb=_share(cfg.loop.space_cache_mb, SPACE_CACHE_MB,
                                      MIN_SPACE_CACHE_MB, moving),
                successor_cache_nodes=0)  # (module docstring)
            while not fleet.team_of(k):  # its robots went to another object
                fleet.wait_for_team(k)
            view = fleet.view(k)

            def world(team: list[int] = view.team, near: float = math.inf,
                      skip: Collection[int] = ()) -> Scene:
                return sub_scene(scene, team, fleet.executor.robot_positions, near, skip)

            hops, planning = transit(view, world, k, seed, lambda: fleet.claims_above(k))
            fleet.stats.count("transit_hops", hops)
            fleet.stats.transit_planning_s += planning
            if view.team_changed:  # a robot failed or joined during transit
                continue
            detour = fleet.detour_of(k)
            view.ghosts = fleet.following(k)  # (its leaders' robots move with them)
            mine = world(near=near, skip={i for j in view.ghosts for i in fleet.team_of(j)})
            scene_k = mine if detour is None else with_goal(mine, k, detour)
            fleet.world_taken(k)
            if detour is not None:  # a place to stand aside: any heading will do
                config = config.but(stop_orientation=math.pi)
            last = series.add(runner.loop(scene_k, k, view, config, observe, view.hooks))
            view.ghosts = {}  # (parking plans in the world as it is)
            if last.result.failure_reason == NO_PLAN_YET:  # from now on: only those near
                near = min(near, settings.replan_near)
            ended = last.end not in (LoopEnd.WORLD_CHANGED, LoopEnd.TEAM_CHANGED)
            if ended and detour is not None:  # aside (or no way there): on to its goal
                fleet.detour_done(k)
            elif ended:
                break
            if series.ran_out():  # the verdict names the limit, not the last loop's end
                break
        outcome = series.outcome(fleet.executor.true_object_poses[k], scene.objects[k].goal)
        if outcome.result.success and fleet.mark_placed(k) and settings.park_clear > 0:
            moves, planning = park(view, world, k, fleet.needed_by_others(k),
                                   settings.park_clear, seed)
            fleet.stats.count("parking_moves", moves)
            fleet.stats.transit_planning_s += planning
        return outcome

    return main
