"""One object's life in the fleet schedule: LAMP's closed loop, started anew whenever the
world changed around its plan.

:func:`object_main` is what ``Fleet`` runs in object ``k``'s thread: a
:class:`~lamp.planners.runner.ClosedLoopRunner` loop on the object's sub-team
(``Fleet.view``), in the world as it is when the loop starts (``sub_scene``: every other
robot a disk obstacle where it stands). A team that stands far from its object first
drives to it (``lamp.fleet.transit``); a team whose object is placed moves out of the
others' way before its robots go free (``lamp.fleet.parking``). A loop that ends with ``WORLD_CHANGED`` (its
segment was declined, or it found no plan while others moved) or ``TEAM_CHANGED`` (a robot
of its sub-team failed: ``Fleet`` took it out of the team) is followed by a new one, and so
is a loop that took the object aside to a detour's end (``lamp.fleet.makeway``),
within the object's segment limit and cumulative planning limit (when one of them ends it,
the object's failure names that limit, :func:`limit_reached`); the object's outcome
merges every loop's (``runner.merged``: each new loop counts as a replan). The objects
moving at once share ``FLEET_SPACE_CACHE_MB`` of robot-space cache.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from lamp.contract.events import SegmentEvent
from lamp.contract.goals import goal_errors
from lamp.contract.result import ObjectResult
from lamp.contract.runner import ObjectOutcome
from lamp.fleet.makeway import detour_done, with_goal
from lamp.fleet.parking import needed_by_others, park
from lamp.fleet.transit import transit
from lamp.planners.closed_loop import TEAM_CHANGED, WORLD_CHANGED
from lamp.planners.config import segment_limit
from lamp.planners.runner import ClosedLoopRunner, judged, merged
from lamp.planners.task import route_distance
from lamp.planners.team import team_scene
from lamp.scene.model import Scene

if TYPE_CHECKING:
    from lamp.fleet.coordinator import Fleet

__all__ = ["FLEET_SPACE_CACHE_MB", "MIN_SPACE_CACHE_MB", "given_up", "limit_reached",
           "object_main", "sub_scene"]

#: Robot-space cache (MB) the objects moving at once share (``space_cache_mb`` each
#: gets its part, at least ``MIN_SPACE_CACHE_MB``): memory stays near one sequential
#: run's up to 48 objects moving at once. (A floor of 16 MB let 32 movers hold 512 MB;
#: 4 MB gave the same plans on the fleet family and 96 x 32, 50 MB less at its peak.)
FLEET_SPACE_CACHE_MB = 192.0
MIN_SPACE_CACHE_MB = 4.0


def sub_scene(scene: Scene, team: list[int], robot_positions: np.ndarray) -> Scene:
    """``scene`` as ``team`` plans in it: its robots only, where they stand now, and every
    other robot a disk obstacle where it stands."""
    pos = np.asarray(robot_positions, float)
    others = {i: pos[i] for i in range(scene.n_robots) if i not in team}
    return team_scene(scene, list(team), others).with_robot_starts(pos[list(team)])


def given_up(scene: Scene, k: int, pose: np.ndarray, why: str) -> ObjectOutcome:
    """The outcome of object ``k``, never started, standing at ``pose``: failed ``why``."""
    pose = np.asarray(pose, float)
    goal = np.asarray(scene.objects[k].goal, float)
    pos_err, rot_err = goal_errors(pose, goal)
    return ObjectOutcome(ObjectResult(
        success=False, final_pose=[float(v) for v in pose], goal=[float(v) for v in goal],
        position_error=pos_err, orientation_error=rot_err, left_workspace=False, segments=0,
        full_horizon_plan=False, failure_reason=why, replans=0, planning_time_s=0.0))


def limit_reached(segment_limit: int, segments: int, loops: int, planning_s: float,
                  planning_limit: float) -> str:
    """Which of an object's limits its loops have reached ("" if none): its segments, as
    many loops as segments, or its cumulative planning time."""
    if planning_s >= planning_limit:
        return "planning time limit"
    if segments >= segment_limit:
        return f"segment limit reached ({segment_limit})"
    if loops > segment_limit:
        return f"plan-anew limit reached ({segment_limit} loops)"
    return ""


def object_main(runner: ClosedLoopRunner, observe: Callable[[SegmentEvent], None]
                ) -> Callable[[Fleet, int], ObjectOutcome]:
    """The function ``Fleet`` runs for each object (see the module docstring)."""

    def main(fleet: Fleet, k: int) -> ObjectOutcome:
        scene, cfg = runner.scene, runner.config
        goal = np.asarray(scene.objects[k].goal, float)
        start = np.asarray(fleet.executor.object_poses[k], float)
        seed = runner.seed * 1000 + k  # the object's tasks' seed (``ClosedLoopRunner.loop``)
        limit = segment_limit(cfg.max_segments, lambda: route_distance(
            scene, k, start, cfg.lattice_step))
        parts: list[ObjectOutcome] = []
        while True:
            used = sum(p.result.segments for p in parts)
            spent = sum(p.result.planning_time_s for p in parts)
            moving = sum(o.status == "active" for o in fleet.objects)
            config = replace(cfg, max_segments=max(1, limit - used),
                             planning_time_limit=max(1e-3, cfg.planning_time_limit - spent),
                             space_cache_mb=max(MIN_SPACE_CACHE_MB, min(
                                 cfg.space_cache_mb, FLEET_SPACE_CACHE_MB / max(1, moving))))
            while not fleet.objects[k].team:  # its robots went to another object
                fleet.wait_for_team(k)
            view = fleet.view(k)

            def world(team: list[int] = view.team) -> Scene:
                return sub_scene(scene, team, fleet.executor.robot_positions)

            hops, planning = transit(view, world, k, seed)
            fleet.counts["transit_hops"] += hops
            fleet.transit_planning_s += planning
            if view.team_changed:  # a robot failed or joined during transit
                continue
            detour = fleet.objects[k].detour
            scene_k = world() if detour is None else with_goal(world(), k, detour)
            fleet.world_taken(k)
            if detour is not None:  # a place to stand aside: any heading will do
                config = replace(config, stop_orientation=math.pi)
            parts.append(runner.loop(scene_k, k, view, config, observe))
            r = parts[-1].result
            ended = r.failure_reason not in (WORLD_CHANGED, TEAM_CHANGED)
            if ended and detour is not None:  # aside (or no way there): on to its goal
                detour_done(fleet, k)
            elif ended:
                break
            ran_out = limit_reached(limit, used + r.segments, len(parts),
                                    spent + r.planning_time_s, cfg.planning_time_limit)
            if ran_out:  # the object's verdict names the limit, not the last loop's end
                parts[-1] = replace(parts[-1], result=replace(r, failure_reason=ran_out))
                break
        truth = getattr(fleet.executor, "true_object_poses", fleet.executor.object_poses)
        outcome = judged(merged(parts), np.asarray(truth[k], float), goal)
        if outcome.result.success and fleet.mark_placed(k) and cfg.fleet_park_clear > 0:
            moves, planning = park(view, world, k, needed_by_others(fleet, k),
                                   cfg.fleet_park_clear, seed)
            fleet.counts["parking_moves"] += moves
            fleet.transit_planning_s += planning
        return outcome

    return main
