"""The fleet schedule: several objects moved at once, each by its own sub-team, in one
simulator. Design (``docs/fleet.md``):

- **Loops.** Every object runs LAMP's own closed loop (planning, Verify, drift and stall
  handling, recovery: ``lamp.planners``) in the world as it is when the loop starts: its
  sub-team are the robots, every other robot is a disk obstacle where it stands, every
  other object a body where it stands. Loops run as coroutines (``lamp.fleet.turns``):
  one at a time, in priority order, so a run is deterministic.
- **Priority.** Objects rank in the order they started (the scene's order among those
  that start together); one with ``after`` starts once those objects are placed, and one
  whose goal would cut others' ways once those are done (``fleet.precedence``). A
  lower-priority segment may not end with its object and robots deeper in a higher
  object's *claim* (the rest of its plan, ``regions.claims``) than they began (crossing
  one, or leaving it, is allowed; a plan that only crosses the claim of an object standing
  waiting heeds its near part, ``cross_waiting``, and with ``cross_near`` any claim's; so
  does one that passes through it ``pass_margin`` ahead of its object, or leaves it, never
  towards that object, ``admission.passes_ahead``): loads never meet head-on in a
  door. The claim of an object whose planner found no plan stays, binding only the
  objects outside it then.
- **Admission.** A segment starts only if it is compatible with every running segment
  (robots row by row on the shared clock, objects by the space they may take:
  ``spacetime.compatible``), respects higher claims, and its bodies as planned overlap
  no body standing still (else the world changed since the plan: it is declined and the
  loop plans anew, ``WORLD_CHANGED``; not before the first event after its loop took its
  world, ``world_taken``: that plan saw the world as it is, and would be made again).
  Otherwise it waits for the next event. A planner that finds no plan while other
  objects still move waits for a change too (``fleet.blocked``).
- **Clock.** Admitted segments are re-timed on a common row grid (``segments.on_grid``),
  with rows appended in which their robots hold for the simulator's settle time, and run
  together until the first ends (or a push watch stops one, or its robots, held back,
  spent its ``rejoin_slack`` moving back to their rows: ``Segment.rejoin``); that loop
  plans its next segment while the others hold their place in their rows (simulated time
  stands still while loops plan). Only when every running segment ends together does the
  simulator settle as it does after a sequential segment.
- **Liveness.** When nothing runs and nothing waits on a change, an object standing in
  a blocked one's way moves aside or takes its robots (``fleet.makeway``); else planners
  waiting on a change plan in the world as it is (as sequentially), claims dropped, or the
  highest-priority waiting segment is admitted against standing bodies only (``forced``).
- **Teams.** Allocated by ``lamp.fleet.teams``. A robot that fails (``executor.failed``)
  leaves its sub-team for good (``FAILED``), replaced by the nearest free robot if any;
  far robots hand over to free ones nearer (``lamp.fleet.handover``). The team's loop
  ends after its segment (``team_changed``) and plans anew.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import shapely

from lamp.contract.events import RunObserver
from lamp.contract.runner import ObjectOutcome
from lamp.fleet.admission import heeded_claims, meets_moving, meets_standing, standing_in
from lamp.fleet.blocked import note_blocked, wake_blocked
from lamp.fleet.handover import better_team
from lamp.fleet.makeway import make_way
from lamp.fleet.objects import given_up
from lamp.fleet.precedence import goal_cuts
from lamp.fleet.regions import CLAIM_NEAR, claims
from lamp.fleet.segments import Segment, on_grid, run_together
from lamp.fleet.state import FAILED, FREE, ObjectState
from lamp.fleet.teams import allocate, near_way, nearest, reinforce, start_order
from lamp.fleet.turns import Turns
from lamp.fleet.utilisation import RobotTime, schedule_stats
from lamp.fleet.view import FleetExecution, FleetView
from lamp.planners.config import PASS_MARGIN, REJOIN_SLACK
from lamp.scene.model import Scene
from lamp.sim.simulator import SETTLE_TIME

__all__ = ["Fleet"]


class Fleet:
    """Moves a scene's objects concurrently on ``executor`` (see the module docstring): a
    ``Simulator`` or an executor wrapping one, with its ``row_durations`` and the
    ``settle_time`` of its ``execute``.

    ``object_main(fleet, k)`` runs in object ``k``'s thread and returns its outcome; it
    drives its closed loops on ``fleet.view(k)``. ``timeline(trace, sim_time, team)``
    receives every stretch of the shared clock and the object whose sub-team each robot
    was in (-1: none; the recorder's ``follow``).
    """

    def __init__(self, scene: Scene, executor: Any, object_main: Callable[[Fleet, int],
                 ObjectOutcome], timeline: Callable[[Any, float, np.ndarray], None],
                 observers: Sequence[RunObserver] = (), row_step: float = 0.02,
                 reinforce_reach: float = 0.0, cross_near: float = 0.0,
                 cross_waiting: float = CLAIM_NEAR, pass_margin: float = PASS_MARGIN,
                 rejoin_limit: int = 0, rejoin_slack: float = REJOIN_SLACK) -> None:
        self.scene, self.executor, self.observers = scene, executor, list(observers)
        self.object_main, self.timeline = object_main, timeline
        self.grid, self.reinforce_reach = float(row_step), float(reinforce_reach)  # 0: off
        #: near reach (m) crossing any claim / a waiting object's claim; 0: the whole claim
        self.cross_near, self.cross_waiting = float(cross_near), float(cross_waiting)
        self.pass_margin = float(pass_margin)  # admission.passes_ahead; inf: off
        #: Segment.rejoin's limit (0: none) and slack (inf: none)
        self.rejoin_limit, self.rejoin_slack = int(rejoin_limit), float(rejoin_slack)
        self.reach = [o.shape.bounding_radius + scene.robot_radius for o in scene.objects]
        #: rows a segment's robots hold at its end while others move: the settle time
        self.hold_rows = math.ceil(SETTLE_TIME * float(scene.physics.robot_speed) / self.grid
                                   - 1e-9)
        self.objects = [ObjectState(k) for k in range(len(scene.objects))]
        self.turns = Turns()
        self.started = self.finished = 0  # objects started (their ranks), placed or given up
        self.clock = 0.0
        #: (simulated time, what, object, detail) of every decision: for the curious
        self.log: list[tuple[float, str, int, str]] = []
        self.counts = dict.fromkeys((
            "admitted", "declined", "waited", "forced", "blocked", "merged", "grown",
            "reinforced", "replaced", "handed_over", "events", "transit_hops",
            "parking_moves", "made_way", "jammed"), 0)
        self.made_way: set[tuple[int, int]] = set()  # (j, k): j made way for k (makeway)
        self.cuts = goal_cuts(scene, scene.object_starts())  # k starts after cuts[k] are done
        self._handover_checked: set[tuple[int, tuple[int, ...], tuple[int, ...]]] = set()
        self.transit_planning_s = 0.0  # wall-clock s planning transit hops and parking moves
        self.robot_time = RobotTime(scene.n_robots)  # utilisation
        self.owner = np.full(scene.n_robots, FREE)  # robot -> object of its team (FREE, FAILED)
        #: robots that failed (``executor.failed``: a ``DisturbedExecutor``'s), and when
        self.failed_at: dict[int, float] = {}

    # ------------------------------------------------------------------ the schedule
    def run(self) -> list[ObjectOutcome]:
        """Move every object; their outcomes in object order."""
        try:
            while not self._all_done():
                self._release()
                if self._all_done():  # the last waiting ones given up
                    break
                wake_blocked(self)
                if self._resume_ready():
                    continue
                self._admit(force=False)
                if any(o.ready for o in self.objects):
                    continue
                if any(o.running for o in self.objects):
                    self._advance()
                    continue
                if not self._unstick():
                    raise RuntimeError("fleet schedule: no object can move and none waits")
        finally:
            self.turns.close()
        return [o.outcome for o in self.objects]  # type: ignore[misc]

    def _release(self) -> None:
        """Start objects whose ``after`` objects are placed (and those their goals would cut
        done, ``fleet.precedence``), give robots to those waiting for a team
        (``teams.allocate``), fail those waiting on a failed object; free robots reinforce
        moving teams (when no object waits) and take far team robots' places."""
        ready = []
        for o in self.objects:
            if o.status == "active" and o.needs_team and self.may_start(o.index):
                ready.append(o.index)
            elif o.status == "waiting":
                after = self.scene.objects[o.index].after
                failed = [k for k in after if self.objects[k].status == "failed"]
                if failed:
                    self._give_up(o, f"not started: object {failed[0]}, which it waits for "
                                  f"(after), was not placed")
                elif self.may_start(o.index):
                    ready.append(o.index)
        if ready:
            self._start(ready)
        if self.reinforce_reach > 0 and not self._any_waits():
            self._reinforce()
        self._hand_over()

    def _all_done(self) -> bool:
        return all(o.status in ("placed", "failed") for o in self.objects)

    def may_start(self, k: int) -> bool:
        """Whether object ``k`` may start: its ``after`` objects are placed and those its
        goal would cut are done (``fleet.precedence``)."""
        return all(self.objects[a].status == "placed" for a in self.scene.objects[k].after) \
            and all(self.objects[j].status in ("placed", "failed") for j in self.cuts[k])

    def _any_waits(self, but: int | None = None) -> bool:
        """Whether an object (other than ``but``) waits to start or waits for robots."""
        return any(o.status == "waiting" or o.needs_team for o in self.objects if o.index != but)

    def _start(self, ready: list[int]) -> None:
        """Sub-teams for the ``ready`` objects: those waiting for robots first, then the
        rest in ``teams.start_order`` (the moving objects' ways busy); the robots shared
        among them (``teams.allocate``)."""
        first = [k for k in ready if self.objects[k].status == "active"]
        moving = [o.index for o in self.objects if o.status == "active" and o.team]
        order = start_order(self.scene, self.executor.object_poses,
                            [k for k in ready if k not in first], moving + first)
        teams = allocate(first + order, self._free(), self.executor.robot_positions,
                         self.executor.object_poses, bool(moving))
        for k, team in teams.items():
            self.give_team(k, team)

    def give_team(self, k: int, team: list[int]) -> None:
        """Object ``k`` (waiting to start, or for robots) gets ``team`` and goes on."""
        o = self.objects[k]
        o.team, o.ready = team, True
        self.owner[team] = k
        if o.needs_team:
            o.needs_team = False
            return
        o.status, o.rank = "active", self.started
        self.started += 1
        for obs in self.observers:
            obs.object_started(k, len(self.objects))
        self.turns.start(k, lambda: self._main(k))

    def _reinforce(self) -> None:
        """Free robots join the moving teams with room within ``reinforce_reach``
        (``teams.reinforce``; not a blocked planner's: it takes them when it plans again),
        whose loops plan anew with them after their segment."""
        teams = {o.index: o.team for o in self._ranked() if o.status == "active" and o.team
                 and o.blocked_at is None}
        for k, team in reinforce(self._free(), self.executor.robot_positions,
                                 self.executor.object_poses, teams,
                                 self.reinforce_reach).items():
            if team != self.objects[k].team:
                self.reteam(self.objects[k], team, "reinforced")

    def _hand_over(self) -> None:
        """Between its segments (a reply waits), a team's far robots give their places to
        free robots nearer by route (``handover.better_team``; checked once per team)."""
        for o in self._ranked():
            key = (o.index, tuple(o.team), tuple(self._free()))
            if o.status != "active" or o.reply is None or key in self._handover_checked:
                continue
            self._handover_checked.add(key)
            team = better_team(self.scene, o.index, o.team, key[2], self.executor.robot_positions,
                               o.reply.object_poses[o.index], lambda: self.executor.object_poses)
            if team is not None:
                self.reteam(o, team, "handed_over")

    def reteam(self, o: ObjectState, team: Sequence[int], what: str) -> None:
        """``o``'s sub-team becomes ``team`` (robots it loses go free); logged as ``what``,
        and counted when ``what`` is one of the schedule's counts."""
        self.log.append((self.clock, what, o.index, f"{o.team} -> {sorted(team)}"))
        self.owner[[i for i in o.team if self.owner[i] == o.index]] = FREE
        o.team = sorted(team)
        self.owner[o.team] = o.index
        if what in self.counts:
            self.counts[what] += 1

    def _main(self, k: int) -> None:
        o = self.objects[k]
        o.outcome = self.object_main(self, k)
        o.status = "placed" if o.outcome.result.success else "failed"
        if o.status == "placed" and o.placed_at_s is None:
            o.placed_at_s = self.clock
        o.claim = None
        self.owner[o.team] = FREE
        self.finished += 1
        for obs in self.observers:
            obs.object_finished(k, len(self.objects), o.outcome.result)

    def _give_up(self, o: ObjectState, why: str) -> None:
        o.status = "failed"
        o.outcome = given_up(self.scene, o.index, self.executor.object_poses[o.index], why)
        for obs in self.observers:
            obs.object_started(o.index, len(self.objects))
            obs.object_finished(o.index, len(self.objects), o.outcome.result)

    def _ranked(self) -> list[ObjectState]:
        """The objects by priority: in the order they started (then the scene's)."""
        return sorted(self.objects, key=lambda o: (o.rank, o.index))

    def _resume_ready(self) -> bool:
        """Resume the highest-priority thread that has something to go on with."""
        for o in self._ranked():
            if o.status == "active" and o.ready:
                o.ready = False
                self.turns.resume(o.index)
                return True
        return False

    # ------------------------------------------------------------------ admission
    def _admit(self, force: bool) -> None:
        """Start the waiting segments that may start (module docstring), in priority
        order; decline those that meet a standing body; with ``force`` the first waiting
        one starts against standing bodies only."""
        for o in self._ranked():
            seg = o.request
            if seg is None:
                continue
            # a plan made in the world as it stands cannot have been overtaken by it
            hit_standing = o.world_at < self.counts["events"] and self._meets_standing(seg)
            hit_moving = not force and self._meets_moving(seg)
            if hit_standing and not force:
                if not hit_moving:
                    o.request, o.reply, o.ready = None, self._reply(seg.team, declined=True), True
                    self.counts["declined"] += 1
                continue
            if hit_moving:
                self.counts["waited"] += 1
                continue
            o.request, o.running = None, seg
            self.counts["admitted" if not force else "forced"] += 1
            if force:
                return

    def _meets_standing(self, seg: Segment) -> bool:
        still = [o.index for o in self.objects if o.index != seg.index and o.running is None]
        moving = {i for o in self.objects if o.running is not None for i in o.team}
        return meets_standing(seg, self.scene, self.executor.object_poses,
                              self.executor.robot_positions, still, moving)

    def _meets_moving(self, seg: Segment) -> str | None:
        """Why ``seg`` must wait (``admission.meets_moving``), None if it need not."""
        me = self.objects[seg.index]
        running = [o.running for o in self.objects if o.running is not None and o is not me]
        why = meets_moving(seg, running, heeded_claims(
            self.objects, me, self.cross_near, self.cross_waiting, self.reach,
            self.pass_margin), me.way)
        if why:
            self.log.append((self.clock, "meets", seg.index, why))
        return why

    def _unstick(self) -> bool:
        """Nothing runs and no loop can go on. Planners that wait for a change: one
        standing in another's way moves aside (``makeway.make_way``); else the first gets
        the robots of all of them (as sequentially), the others wait for robots; when it
        has them all already, it plans in the world as it is. Else the first waiting
        segment is forced."""
        blocked = [o for o in self._ranked() if o.blocked_at is not None]
        if blocked and make_way(self, blocked):
            return True
        if blocked:
            first = blocked[0]
            pool = sorted({i for o in blocked for i in o.team}
                          | set(self._free()))
            merge = len(pool) > len(first.team)
            for o in blocked:
                o.blocked_at, o.wake, o.ready, o.claim = None, merge, True, None
                if merge and o is not first:
                    o.team = []
            if merge:
                self.reteam(first, pool, "merged")
            return True
        if any(o.request is not None for o in self.objects):
            self._admit(force=True)
            return True
        return False

    # ------------------------------------------------------------------ the clock
    def _advance(self) -> None:
        """Run every admitted segment until the first ends (or a watch stops one)."""
        running = [o.running for o in self.objects if o.running is not None]
        now = np.asarray(self.executor.robot_positions, float)
        for s in running:  # robots nudged off their rows (``Segment.rejoin``) rejoin them
            s.rejoin(now[s.team], self.grid, self.rejoin_limit, self.rejoin_slack)
            self.counts["jammed"] += s.done  # it spent its slack (or limit): it ends
        if any(s.done for s in running):  # nothing runs: its loop goes on first
            self._ended(running)
            return
        out, paths, done, fired = run_together(self.executor, running)
        self.robot_time.charge([s.team for s in running], self.owner, paths,
                               float(out.sim_time))
        self.timeline(out.trace, float(out.sim_time), np.maximum(self.owner, FREE))
        self.clock += float(out.sim_time)
        self._note_failures()
        self.counts["events"] += 1
        left = np.asarray(getattr(out, "objects_left", np.zeros(len(self.objects), bool)))
        for s in running:
            s.cursor += done
            s.sim_time += float(out.sim_time)
            s.left |= bool(left[s.index])
            if s in fired:
                s.stopped_at = int(out.stopped_at)
        self._ended(running)

    def _ended(self, running: list[Segment]) -> None:
        """The loops of the ``running`` segments that are done go on, with their replies."""
        for s in running:
            if s.done:
                o = self.objects[s.index]
                o.running = None
                o.reply = self._reply(s.team, left_workspace=s.left, stopped_at=s.stopped_at,
                                      sim_time=s.sim_time)
                o.ready = True
        wake_blocked(self)

    def _reply(self, team: Sequence[int], **outcome: Any) -> FleetExecution:
        """A loop's reply: the objects as observed now and ``team``'s robots."""
        return FleetExecution(np.asarray(self.executor.object_poses, float),
                              np.asarray(self.executor.robot_positions, float)[team], **outcome)

    def _free(self) -> list[int]:
        """The robots in no sub-team that have not failed (ascending)."""
        return [int(i) for i in np.flatnonzero(self.owner == FREE)]

    def _note_failures(self) -> None:
        """Robots that failed in the last stretch (``executor.failed``) leave their teams
        for good, each replaced by the free robot nearest its object if any (the loop
        plans anew after its segment); every later plan has them as obstacles."""
        for i in sorted(getattr(self.executor, "failed", {})):
            if i in self.failed_at:
                continue
            self.failed_at[i] = self.clock
            k = int(self.owner[i])
            self.owner[i] = FAILED
            self.log.append((self.clock, "failed", k, f"robot {i}"))
            if k >= 0:
                o = self.objects[k]
                o.team = [j for j in o.team if j != i]
                if free := self._free():  # the nearest robot nobody needs takes its place
                    self.reteam(o, [*o.team, *nearest(free, self.executor.robot_positions,
                                                       self.executor.object_poses[k], 1)],
                                 "replaced")

    # ------------------------------------------------------------------ a loop's executor
    def view(self, k: int) -> FleetView:
        return FleetView(self, k)  # object k's sub-team's executor, for its closed loop

    def submit(self, k: int, paths: np.ndarray, stop: Callable[[np.ndarray], bool] | None,
               team: Sequence[int]) -> FleetExecution:
        """Run ``paths`` of ``team`` (its view's; robots that joined since hold still)."""
        o = self.objects[k]
        poses = o.announced if o.announced is not None else np.asarray(
            self.executor.object_poses[k], float)[None]
        start = np.asarray(self.executor.robot_positions, float)[list(team)]
        rows = on_grid(start, paths, self.grid)
        rows = np.concatenate([rows, np.repeat(rows[:, -1:], self.hold_rows, axis=1)], axis=1)
        o.request = Segment(k, list(team), rows, poses, stop, self.scene.objects[k].shape,
                            self.scene.robot_radius)
        o.announced = None
        self.turns.pause(k)
        reply, o.reply = o.reply, None
        return reply  # type: ignore[return-value]

    def world_taken(self, k: int) -> None:
        """Object ``k``'s new loop plans in the world as it is now: until the next event
        its segments meet no standing body it did not see (none is declined)."""
        self.objects[k].world_at = self.counts["events"]

    def announce(self, k: int, segment: np.ndarray, rest: np.ndarray) -> None:
        o = self.objects[k]
        o.announced = np.asarray(segment, float)
        poses = np.concatenate([o.announced, np.asarray(rest, float).reshape(-1, 3)])
        obj = self.scene.objects[k]
        goal = obj.goal if o.detour is None else o.detour
        o.claim, o.near, o.way = claims(obj.shape, poses, goal, self.scene.robot_radius,
                                        self.cross_near or self.cross_waiting)
        o.exempt = frozenset()  # a new plan's claim binds everyone

    def plan_failed(self, k: int) -> bool:
        """Object ``k``'s planner found no plan: free robots near its way join its team
        (``teams.near_way``; True: plan anew), else wait for the world to change (True:
        it did) unless nothing else can change it (False: go on as alone)."""
        o = self.objects[k]
        ex, free = self.executor, self._free()  # the pose (a sensor draw) read only if any
        if free and (free := near_way(self.scene, k, ex.object_poses[k], free,
                                      ex.robot_positions)):
            self.reteam(o, [*o.team, *free], "grown")
            return True
        if not any(other.index != k and other.status in ("active", "waiting")
                   for other in self.objects):
            return False
        poses = np.asarray(ex.object_poses, float)
        # its last claim binds only those outside it (module docstring, Priority)
        o.exempt = self.inside(o.claim, poses) if o.claim is not None else frozenset()
        note_blocked(self, o, poses)
        self.counts["blocked"] += 1
        self.turns.pause(k)
        return o.wake

    def inside(self, region: shapely.Geometry, poses: np.ndarray | None = None
                ) -> frozenset[int]:
        """The objects whose body (at ``poses``, else as read now) or sub-team's robots
        stand in ``region`` (``admission.standing_in``)."""
        return standing_in(region, self.scene,
                           self.executor.object_poses if poses is None else poses,
                           self.executor.robot_positions,
                           {p.index: p.team for p in self.objects
                            if p.status in ("active", "waiting")})

    def wait_for_team(self, k: int) -> None:
        """Object ``k`` has no robots (they went to another object): wait for some."""
        self.objects[k].claim, self.objects[k].needs_team = None, True
        self.turns.pause(k)

    def mark_placed(self, k: int) -> bool:
        """Object ``k`` is placed (its time is now) and its plan claims nothing more;
        True when its team should park (``fleet.parking``): other objects still move
        and none waits for robots (they would go to it at once)."""
        o = self.objects[k]
        o.placed_at_s, o.claim = self.clock, None
        return (any(p.status == "active" for p in self.objects if p.index != k)
                and not self._any_waits(but=k))

    def stats(self) -> dict[str, Any]:
        """The schedule's figures for ``result.json`` (``utilisation.schedule_stats``)."""
        return schedule_stats(self)
