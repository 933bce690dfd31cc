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
  Otherwise it waits for the next event, as does one that meets a leader standing
  (``fleet.follow``). A planner that finds no plan while other objects still move
  waits for a change too (``fleet.blocked``).
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
- **Teams.** Allocated by ``lamp.fleet.teams``. A failed robot (``executor.failed``) leaves
  its team for good, replaced by the nearest free robot if any; far robots hand over to
  free ones nearer (``fleet.handover``); the loop then plans anew (``team_changed``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from lamp.contract.events import RunObserver
from lamp.contract.runner import ObjectOutcome, WorldExecutor
from lamp.fleet import tasks as T
from lamp.fleet.admission import ends_box, heeded_claims, meets_moving, meets_standing
from lamp.fleet.blocked import blocked_space, looks_now, wait_over
from lamp.fleet.config import FleetConfig
from lamp.fleet.knocked import Knocks
from lamp.fleet.makeway import make_way, with_goal
from lamp.fleet.objects import given_up
from lamp.fleet.regions import claims
from lamp.fleet.segments import Segment, on_grid, run_together
from lamp.fleet.spacetime import halted
from lamp.fleet.state import FREE, ObjectState, ObjectStatus
from lamp.fleet.teams import allocate, near_way, start_order
from lamp.fleet.turns import Turns
from lamp.fleet.view import FleetExecution, FleetView
from lamp.scene.model import Scene

__all__ = ["Fleet"]


class Fleet(Knocks):
    """Moves a scene's objects concurrently on ``executor`` (see the module docstring): a
    ``Simulator`` or an executor wrapping one. The one writer of the schedule's state
    (``board.Board``): the rules return decisions, and it applies them.

    ``object_main(fleet, k)`` runs in object ``k``'s thread and returns its outcome; it
    drives its closed loops on ``fleet.view(k)`` (``objects.LoopHost``: what a loop may
    ask). ``timeline(trace, sim_time, team)`` receives every stretch of the shared clock
    and the object whose sub-team each robot was in (-1: none; the recorder's
    ``follow``)."""

    def __init__(self, scene: Scene, executor: WorldExecutor,
                 object_main: Callable[[Fleet, int], ObjectOutcome],
                 timeline: Callable[[Any, float, np.ndarray], None],
                 observers: Sequence[RunObserver] = (), row_step: float = 0.02,
                 config: FleetConfig | None = None, feed: T.TaskFeed | None = None,
                 serial: bool = False) -> None:
        super().__init__(scene, executor, row_step, config or FleetConfig(),
                         T.ScheduledFeed(scene) if feed is None else feed, serial)
        self.observers = list(observers)
        self.object_main, self.timeline, self.turns = object_main, timeline, Turns()
        self.outcomes: list[list[ObjectOutcome]] = [[] for _ in scene.objects]  # by task
        self._at_rest = False  # whether the world stood still through the last idle stretch
        self._take_tasks()  # those released at 0: the objects' own goals, first of all

    # ------------------------------------------------------------------ the schedule
    def run(self) -> list[ObjectOutcome]:
        """Serve every task the feed releases; the objects' outcomes in object order
        (each merges its tasks', ``tasks.merged_tasks``)."""
        try:
            while not self.desk.feed.stopped:
                self._take_tasks()
                if self.all_done():  # every released task ended: idle until the next
                    until = self.desk.feed.wait(self.clock)
                    if until is None:
                        break
                    self._idle(until)
                    continue
                self._release()
                if self.all_done():  # the last waiting ones given up
                    continue
                self._wake_blocked()
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
        self.desk.stop(self.clock, "stopped: the run ended before it")
        return [T.merged_tasks(self.outcomes[o.index]) or given_up(
            self.scene, o.index, self.executor.object_poses[o.index], "stopped: no task done")
            for o in self.objects]

    def _take_tasks(self) -> None:
        """Released tasks (and knocked objects' again, ``fleet.knocked``) queue at their
        objects; one with none takes its next: it waits to start again, to its goal."""
        self.desk.take(self.clock)
        self.reopen_knocked()
        for o in self.objects:
            task = self.desk.next_for(o.index)
            if task is not None and o.status.done:
                o.renew()
            if task is not None and tuple(task.goal) != tuple(self.scene.objects[o.index].goal):
                self.scene = with_goal(self.scene, o.index, np.asarray(task.goal))

    def _idle(self, until: float) -> None:
        """Nothing to do before simulated time ``until``: the robots hold still (module
        docstring of ``fleet.tasks``: simulated till the world rests, then skipped)."""
        now = np.asarray(self.executor.robot_positions, float)
        out, self._at_rest = T.hold_still(self.executor, now, self._at_rest, until - self.clock)
        self._clocked(out, [], now[:, None])

    def _release(self) -> None:
        """Start objects whose ``after`` objects are placed (and those their goals would cut
        done, ``fleet.precedence``), give robots to those waiting for a team
        (``teams.allocate``), fail those waiting on a failed object; free robots reinforce
        moving teams (when no object waits) and take far team robots' places."""
        ready = []
        for o in self.objects:
            if o.status == ObjectStatus.ACTIVE and o.needs_team and self.may_start(o.index):
                ready.append(o.index)
            elif o.status == ObjectStatus.WAITING and self.desk.current[o.index] is not None:
                after = self.after(o.index)
                failed = [k for k in after if self.objects[k].status == ObjectStatus.FAILED]
                if failed:
                    self._give_up(o, f"not started: object {failed[0]}, which it waits for "
                                  f"(after), was not placed")
                elif self.may_start(o.index):
                    ready.append(o.index)
        if ready:
            self._start(ready)
        if self.config.reinforce_reach > 0 and not self.any_waits():
            self._reinforce()
        self._hand_over()

    def _start(self, ready: list[int]) -> None:
        """Sub-teams for the ``ready`` objects (waiting for robots first, then the rest in
        ``teams.start_order``), sharing the robots (``teams.allocate``)."""
        if self.serial:  # first come, first served: the earliest task, every robot
            k = min(ready, key=lambda j: (self.desk.current[j].release_s,  # type: ignore[union-attr]
                                          self.desk.current[j].id))  # type: ignore[union-attr]
            self._give_team(k, self.free())
            return
        first = [k for k in ready if self.objects[k].status == ObjectStatus.ACTIVE]
        moving = [o.index for o in self.objects if o.status == ObjectStatus.ACTIVE and o.team]
        order = start_order(self.scene, self.executor.object_poses, [k for k in ready if k
                            not in first], moving + first, bool(self.config.order_in_way))
        goals = np.array([o.goal for o in self.scene.objects]) if self.config.balance_teams else None
        teams = allocate(first + order, self.free(), self.executor.robot_positions,
                         self.executor.object_poses, bool(moving), goals)
        for k, team in teams.items():
            self._give_team(k, team)

    def _give_team(self, k: int, team: list[int]) -> None:
        """Object ``k`` (waiting to start, or for robots) gets ``team`` and goes on."""
        o = self.objects[k]
        o.team, o.ready = team, True
        self.owner[team] = k
        if o.needs_team:
            o.needs_team = False
            return
        o.move_to(ObjectStatus.ACTIVE)
        self.desk.begin(k, self.clock)
        o.rank = self.started
        self.started += 1
        for obs in self.observers:
            obs.object_started(k, len(self.objects))
        self.turns.start(k, lambda: self._main(k))

    def _main(self, k: int) -> None:
        o = self.objects[k]
        o.outcome = self.object_main(self, k)
        self._task_ended(o)
        o.move_to(ObjectStatus.PLACED if o.outcome.result.success else ObjectStatus.FAILED)
        if o.status == ObjectStatus.PLACED and o.placed_at_s is None:
            o.placed_at_s = self.clock
        o.claim = None
        self.owner[o.team] = FREE
        self.finished += 1
        for obs in self.observers:
            obs.object_finished(k, len(self.objects), o.outcome.result)

    def _give_up(self, o: ObjectState, why: str) -> None:
        o.move_to(ObjectStatus.FAILED)
        o.outcome = given_up(self.scene, o.index, self.executor.object_poses[o.index], why)
        self._task_ended(o)
        for obs in self.observers:
            obs.object_started(o.index, len(self.objects))
            obs.object_finished(o.index, len(self.objects), o.outcome.result)

    def _task_ended(self, o: ObjectState) -> None:
        """``o``'s task ended with ``o.outcome``."""
        r = o.outcome.result  # type: ignore[union-attr]
        self.outcomes[o.index].append(o.outcome)  # type: ignore[arg-type]
        self.desk.end(o.index, self.clock, r.success, r.failure_reason,
                      segments=r.segments, replans=r.replans)

    def _resume_ready(self) -> bool:
        """Resume the highest-priority thread that has something to go on with."""
        for o in self.ranked():
            if o.status == ObjectStatus.ACTIVE and o.ready:
                o.ready = False
                self.turns.resume(o.index)
                return True
        return False

    # ------------------------------------------------------------------ waiting planners
    def _note_blocked(self, o: ObjectState, poses: np.ndarray) -> None:
        """``o``'s planner found no plan with the objects at ``poses``: it waits from now
        on, and the objects standing in the space it needs are noted (``blocked``)."""
        o.blocked_in = blocked_space(self.scene, o, poses, self.executor.robot_positions)
        o.blockers = self.inside(o.blocked_in, poses) - {o.index}
        o.blocked_at = (self.finished, self.events)
        o.looked_at = self.events

    def _wake_blocked(self) -> None:
        """Waiting planners whose wait is over plan again (``blocked``: poses read once)."""
        now, poses = self.events, None
        for o in self.objects:
            if o.blocked_at is None:
                continue
            left = False
            if looks_now(o, now):
                o.looked_at = now
                poses = self.executor.object_poses if poses is None else poses
                left = not o.blockers <= self.inside(o.blocked_in, poses)
            if wait_over(o, self.finished, now, left):
                o.resume()

    # ------------------------------------------------------------------ admission
    def _admit(self, force: bool) -> None:
        """Start the waiting segments that may start (module docstring), in priority
        order; decline those that meet a standing body; with ``force`` the first waiting
        one starts against standing bodies only."""
        for o in self.ranked():
            seg = o.request
            if seg is None:
                continue
            if self.held_for_leader(seg, force):  # ``fleet.follow``
                if force:
                    return
                continue
            # a plan made in the world as it stands cannot have been overtaken by it
            hit_standing = o.world_at < self.events and self._meets_standing(seg)
            hit_moving = not force and self._meets_moving(seg)
            if hit_standing and not force:
                if not hit_moving:
                    o.request, o.reply, o.ready = None, self.reply(seg.team, declined=True), True
                    self.stats.count("declined")
                continue
            if hit_moving:
                self.stats.count("waited")
                continue
            o.request, o.running = None, seg
            self.stats.count("admitted" if not force else "forced")
            if force:
                return

    def _meets_standing(self, seg: Segment) -> bool:
        still = [o.index for o in self.objects if o.index != seg.index and o.running is None]
        moving = {i for o in self.objects if o.running is not None for i in o.team}
        return meets_standing(seg, self.scene, self.executor.object_poses,
                              self.executor.robot_positions, still, moving)

    def _meets_moving(self, seg: Segment) -> str | None:
        """Why ``seg`` must wait (``admission.meets_moving``), None if it need not."""
        me, cfg, ex = self.objects[seg.index], self.config, self.executor
        seen = ex.object_poses if cfg.reach_cut and ex.pushes_tracked else None
        running = [o.running for o in self.objects if o.running is not None and o is not me]
        why = meets_moving(seg, running, heeded_claims(
            self.objects, me, cfg.cross_near, cfg.cross_waiting, self.reach, cfg.pass_margin,
            self.passing, ends_box(seg)), me.way, seen)
        if why:
            self.stats.note(self.clock, "meets", seg.index, why)
        return why

    def _unstick(self) -> bool:
        """Nothing runs and no loop can go on. Planners that wait for a change: one
        standing in another's way moves aside (``makeway.make_way``); else the first gets
        the robots of all of them (as sequentially), the others wait for robots; when it
        has them all already, it plans in the world as it is. Else the first waiting
        segment is forced."""
        blocked = [o for o in self.ranked() if o.blocked_at is not None]
        if blocked and self._make_way(blocked):
            return True
        if blocked:
            first = blocked[0]
            pool = sorted({i for o in blocked for i in o.team} | set(self.free()))
            merge = len(pool) > len(first.team)
            for o in blocked:
                o.resume(replan=merge)
                o.claim = None
                if merge and o is not first:
                    o.team = []
            if merge:
                self._reteam(first, pool, "merged")
            return True
        if any(o.request is not None for o in self.objects):
            self._admit(force=True)
            return True
        return False

    def _make_way(self, blocked: list[ObjectState]) -> bool:
        """Apply ``makeway.make_way``'s decision for ``blocked`` (priority order); True
        if an object moves aside or to its goal with the blocked one's robots."""
        decided = make_way(self.scene, self.objects, blocked,
                           np.asarray(self.executor.object_poses, float),
                           self.executor.robot_positions, self.made_way, self.may_start,
                           self.after)
        self.made_way.update(decided.tried)
        for what, j, detail in decided.notes:
            self.stats.note(self.clock, what, j, detail)
        move = decided.move
        if move is None:
            return False
        if move.target is not None:
            self.stats.count("made_way")
        J, o = self.objects[move.j], self.objects[move.k]
        J.detour, J.lent_by = move.target, None
        if J.team:
            J.resume()
        else:  # the blocked object's robots go to the one in its way; it waits for robots
            o.team = []
            o.resume()
            self.stats.note(self.clock, "handed", move.j, f"robots {move.team} of {move.k}")
            self._give_team(move.j, move.team)
            J.lent_by = move.k if move.target is not None else None  # back after the detour
        return True

    def detour_done(self, j: int) -> None:
        """Object ``j`` stands at its detour's end (or found no way there): the planners
        waiting for a change plan again, and ``j`` goes on to its own goal; with robots lent
        by the object it made way for, once that one has them back (if it still waits); and
        only once it may start (``may_start``): until then its robots go free and it waits
        for robots where it stands, which it is given only then."""
        J = self.objects[j]
        J.detour, lender, J.lent_by = None, J.lent_by, None
        for o in self.objects:
            if o.blocked_at is not None:
                o.resume()
        if lender is not None and self.objects[lender].needs_team and J.team:
            team, J.team = J.team, []
            self.stats.note(self.clock, "handed", lender, f"robots {team} back from {j}")
            self._give_team(lender, team)
        elif J.team and not self.may_start(j):  # held back still (precedence): it waits aside
            self._reteam(J, [], "freed: it may not start yet")

    # ------------------------------------------------------------------ the clock
    def _advance(self) -> None:
        """Run every admitted segment until the first ends (or a watch stops one)."""
        running = [o.running for o in self.objects if o.running is not None]
        now, cfg = np.asarray(self.executor.robot_positions, float), self.config
        for s in running:  # robots nudged off their rows (``Segment.rejoin``) rejoin them
            s.rejoin(now[s.team], self.grid, cfg.rejoin_limit, cfg.rejoin_slack)
            self.stats.count("jammed", int(s.done))  # it spent its slack (or limit): it ends
        if any(s.done for s in running):  # nothing runs: its loop goes on first
            self._ended(running)
            return
        out, paths, done, fired = run_together(self.executor, running)
        self._clocked(out, running, paths)
        self._at_rest = False
        self._note_failures()
        self.stats.count("events")
        left = np.asarray(out.objects_left)
        for s in running:
            s.cursor += done
            s.sim_time += float(out.sim_time)
            s.left |= bool(left[s.index])
            if s in fired:
                s.stopped_at = int(out.stopped_at)
        self._ended(running)

    def _clocked(self, out: Any, running: list[Segment], paths: np.ndarray) -> None:
        """The clock ran ``out`` (``paths``): charged, recorded, fed; time moves on."""
        self.stats.robot_time.charge([s.team for s in running], self.owner, paths,
                                     float(out.sim_time))
        self.timeline(out.trace, float(out.sim_time), np.maximum(self.owner, FREE))
        self.desk.feed.moved(self.clock, out.trace)
        self.clock += float(out.sim_time)

    def _ended(self, running: list[Segment]) -> None:
        """Done segments' loops go on; first, any an off-plan object blocks stop (``halted``)."""
        for s in halted(running, self.executor.object_poses):
            s.stopped_at = 0  # they plan anew around where it stands
            self.stats.count("halted")
        for s in running:
            if s.done:
                o = self.objects[s.index]
                o.running = None
                o.reply = self.reply(s.team, left_workspace=s.left, stopped_at=s.stopped_at,
                                     sim_time=s.sim_time)
                o.ready = True
        self._wake_blocked()

    # ------------------------------------------------------------------ a loop's side
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
        self.objects[k].world_at = self.events

    def announce(self, k: int, segment: np.ndarray, rest: np.ndarray) -> None:
        o = self.objects[k]
        o.announced = np.asarray(segment, float)
        poses = np.concatenate([o.announced, np.asarray(rest, float).reshape(-1, 3)])
        obj, cfg = self.scene.objects[k], self.config
        goal = obj.goal if o.detour is None else o.detour
        o.claim, o.near, o.way = claims(obj.shape, poses, goal, self.scene.robot_radius,
                                        cfg.cross_near or cfg.cross_waiting, self.claim_blocks)
        o.exempt = frozenset()  # a new plan's claim binds everyone

    def plan_failed(self, k: int) -> bool:
        """Object ``k``'s planner found no plan: free robots near its way join its team
        (``teams.near_way``; True: plan anew), else wait for the world to change (True:
        it did) unless nothing else can change it (False: go on as alone)."""
        o = self.objects[k]
        ex, free = self.executor, self.free()  # the pose (a sensor draw) read only if any
        if free and (free := near_way(self.scene, k, ex.object_poses[k], free,
                                      ex.robot_positions)):
            self._reteam(o, [*o.team, *free], "grown")
            return True
        if not any(other.index != k and other.unplaced for other in self.objects):
            return False
        poses = np.asarray(ex.object_poses, float)
        # its last claim binds only those outside it (module docstring, Priority)
        o.exempt = self.inside(o.claim, poses) if o.claim is not None else frozenset()
        self._note_blocked(o, poses)
        self.stats.count("blocked")
        self.turns.pause(k)
        return o.replan

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
        return (any(p.status == ObjectStatus.ACTIVE for p in self.objects if p.index != k)
                and not self.any_waits(but=k))
