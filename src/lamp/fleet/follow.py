"""Loads that follow the loads ahead of them (``fleet_follow``): a line of loads leaves an
aisle together instead of one after another.

Without it an object's loop plans round every other object where it stands, so a load
queued behind another in a narrow aisle has no way out (or a detour round it) until the
one ahead has gone, and its team holds. With it, object ``k``'s loop plans as if its
*leaders* were already at their goals: the objects that move (active, with a team, not
on a detour, not waiting on a change), rank above ``k``, stand in its way
(``teams.in_way_of``: within reach of its body and robots along its shortest way to its
goal) and in whose way ``k`` does not stand (not head-on). Their robots are left
out of its world too (they move with them). Its plan then runs through where a leader
stands; admission holds each segment that meets a leader's standing body or robots until
the leader has moved on (it waits, not declined: the leader moves away), and running
beside the leader's segments is decided as for any two segments
(``spacetime.compatible``), so the follower keeps behind it. Nothing is admitted on the
leaders' account alone: every segment is still checked against every running segment,
every claim and every body standing still that is not a leader.

When nothing else can move (the schedule's liveness step would force a waiting segment)
a segment that meets a leader is declined instead, and that object's next loop plans
round everything where it stands, as without ``follow``.
"""

from __future__ import annotations

import numpy as np

from lamp.fleet.admission import meets_standing
from lamp.fleet.reteam import TeamChanges
from lamp.fleet.segments import Segment
from lamp.fleet.state import ObjectStatus
from lamp.fleet.teams import in_way_of

__all__ = ["Following"]


class Following(TeamChanges):
    """The ``follow`` setting's part of the fleet schedule's writer (module docstring)."""

    def leaders(self, k: int) -> frozenset[int]:
        """The objects object ``k`` may follow now (module docstring)."""
        me = self.objects[k]
        ahead = [o.index for o in self.objects
                 if o.index != k and o.status == ObjectStatus.ACTIVE and o.team
                 and o.detour is None and o.blocked_at is None and o.rank < me.rank]
        if not ahead:
            return frozenset()
        poses = np.asarray(self.executor.object_poses, float)
        return frozenset(j for j in in_way_of(self.scene, poses, k, ahead)
                         if not in_way_of(self.scene, poses, j, [k]))

    def following(self, k: int) -> dict[int, np.ndarray]:
        """Object ``k``'s new loop: its leaders (none with ``follow`` off, on its way to a
        detour, or once after a segment that met one was declined), each mapped to the
        pose its loop plans it at (its goal). Admission holds its segments for them until
        its next loop."""
        o = self.objects[k]
        o.leaders = (frozenset() if not self.config.follow or o.follow_off
                     or o.detour is not None else self.leaders(k))
        o.follow_off = False
        return {j: np.asarray(self.scene.objects[j].goal, float) for j in sorted(o.leaders)}

    def leader_met(self, seg: Segment) -> int | None:
        """The first of its object's moving leaders whose body or robots, standing still,
        ``seg``'s planned bodies meet (``admission.meets_standing``); None if none."""
        poses, robots = self.executor.object_poses, self.executor.robot_positions
        for j in sorted(self.objects[seg.index].leaders):
            leader = self.objects[j]
            if leader.status != ObjectStatus.ACTIVE or leader.running is not None:
                continue
            others = set(range(self.scene.n_robots)) - set(leader.team)
            if meets_standing(seg, self.scene, poses, robots, [j], others):
                return j
        return None

    def held_for_leader(self, seg: Segment, force: bool) -> bool:
        """Whether ``seg`` meets a standing leader of its object (:meth:`leader_met`): it
        waits for it (counted as waiting on ``leader j``), or with ``force`` (nothing else
        can move) it is declined and its object's next loop follows no one."""
        o = self.objects[seg.index]
        j = self.leader_met(seg) if o.leaders else None
        if j is None:
            return False
        if force:
            o.request, o.reply, o.ready = None, self.reply(seg.team, declined=True), True
            o.follow_off = True
            self.stats.count("declined")
        else:
            self.stats.note(self.clock, "meets", seg.index, f"leader {j}")
            self.stats.count("waited")
        return True
