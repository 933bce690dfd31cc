"""May a submitted segment start? The two tests of the fleet schedule's admission.

- :func:`meets_standing`: its bodies as planned (``Segment.core``) overlap an object or a
  robot that stands still (shrunk by ``regions.STATIC_SLACK``): the world changed since
  the plan, so the segment is declined and its loop plans anew.
- :func:`meets_moving`: it cannot run beside a running segment (``spacetime.compatible``),
  or it would leave its object and robots deeper inside a higher-ranked object's claim
  than they were (``CLAIM_AREA_SLACK`` of rounding): it waits for the next event. A plan
  that only crosses the claim (:func:`crosses`) keeps out of its near part only
  (``regions.claims``'s near reach): it may cross the other's way where that object will come
  only later, but never run along it towards it, nor stop in it.
- :func:`standing_in`: the objects standing in a claim, which a blocked object's claim
  does not bind (``Fleet.plan_failed``).
- :func:`heeded_claims`: the claims a segment must heed, each whole or, where a plan that
  only crosses it may, its near part: any claim's with ``cross_near``; with
  ``cross_waiting``, the claim of an object standing waiting (``ObjectState.held_up``);
  and the claim of an object its own object passes ahead of (:func:`passes_ahead`).

Bodies, claims and ways whose bounding boxes lie apart (``spacetime.apart``) are answered
from the boxes: the same answers as the full tests (``tests/test_fleet_boxes.py``), without
building or intersecting their geometry, which on a depot of 48 loads is most pairs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import shapely

from lamp.fleet.regions import ROBOT_MARGIN, standing, standing_robots
from lamp.fleet.segments import Segment
from lamp.fleet.spacetime import apart, compatible, object_space
from lamp.fleet.state import ObjectState
from lamp.scene.model import Scene

__all__ = ["CLAIM_AREA_SLACK", "CROSSING", "PASS_STEP", "crosses", "ends_box", "heeded_claims",
           "meets_moving", "meets_standing", "passes_ahead", "standing_in"]

#: A segment may end with this much more of its bodies' area (m^2) inside a higher claim
#: than it started with (rounding of the footprints).
CLAIM_AREA_SLACK = 1e-4
#: A way that runs at most this far (m) inside a claim, and ends outside it, crosses it.
CROSSING = 1.5
#: Answers of :func:`passes_ahead` a memo of :func:`heeded_claims` keeps at most.
_MEMO_KEPT = 4096
#: The spacing (m) of the points at which :func:`passes_ahead` compares two ways.
PASS_STEP = 0.1


def crosses(way: shapely.Geometry, region: shapely.Geometry) -> bool:
    """Whether a plan's ``way`` (its centre's path to its goal, ``regions.claims``)
    crosses ``region``: its goal lies outside it and at most ``CROSSING`` m of the way
    inside."""
    end = shapely.points(shapely.get_coordinates(way)[-1])
    return (not region.intersects(end)
            and float(shapely.length(shapely.intersection(way, region))) <= CROSSING)


def passes_ahead(way: shapely.LineString, region: shapely.Geometry,
                 claimer_way: shapely.LineString, reach: float, margin: float,
                 step: float = PASS_STEP, along: Callable | None = None) -> bool:
    """Whether a plan whose ``way`` (its centre's path on to its goal) goes through a
    higher-ranked object's claim ``region`` passes it ahead of that object. Its goal lies
    outside the claim, its way does not run towards the claiming object (the point where
    it leaves the claim is no nearer that object along its own way, ``claimer_way``, than
    where it enters: they would meet head-on), and either it stands in the claim already
    (it is in that object's way: waiting there only makes that one come to it, so it
    leaves by its way), or it passes every point of its way inside the claim, going at
    the claiming object's pace, ``margin`` m of travel before that object's centre comes
    within ``reach`` of the point. Both ways are taken at points ``step`` m apart. False
    when the way does not go through the claim (its robots may still come in), ends
    inside it, or ``margin`` is infinite. ``along(line, step)`` gives a way's points
    (:func:`_along`, the default; a caller may keep them)."""
    along = along or _along
    if not math.isfinite(margin) or apart(np.asarray(way.bounds, float),
                                          np.asarray(region.bounds, float), 0.0):
        return False  # (boxes apart: its end and every point of it lie outside the claim)
    if region.intersects(shapely.points(shapely.get_coordinates(way)[-1])):
        return False
    s, points = along(way, step)
    inside = shapely.intersects(region, shapely.points(points))
    if not inside.any():
        return False  # it does not go through: its robots may still come in
    a, theirs = along(claimer_way, step)
    near = np.hypot(*np.moveaxis(points[inside, None] - theirs[None], -1, 0)) <= reach
    comes = np.where(near.any(axis=1), a[np.argmax(near, axis=1)], np.inf)
    if comes[-1] < comes[0] - step:
        return False  # through it towards the other: they would meet head-on
    return bool(inside[0] or np.all(s[inside] + margin <= comes))


def _along(line: shapely.LineString, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points of ``line`` every ``step`` m from its start, and its end: (distances along
    it, (n, 2) points)."""
    s = np.append(np.arange(0.0, float(line.length), step), float(line.length))
    return s, shapely.get_coordinates(shapely.line_interpolate_point(line, s))


def meets_standing(seg: Segment, scene: Scene, object_poses: np.ndarray,
                   robot_positions: np.ndarray, still_objects: Sequence[int],
                   moving_robots: set[int]) -> bool:
    """Whether ``seg``'s planned bodies overlap an object of ``still_objects`` where it is
    or a robot (not in ``seg``'s team nor in ``moving_robots``) where it stands."""
    core = seg.core()
    box = np.asarray(core.bounds, float)
    r = scene.robot_radius
    poses = np.asarray(object_poses, float)
    for k in still_objects:  # a body whose box misses the core's cannot meet it
        reach = scene.objects[k].shape.bounding_radius
        if (not apart(box, np.concatenate([poses[k, :2] - reach, poses[k, :2] + reach]), 0.0)
                and core.intersects(standing(scene.objects[k].shape, poses[k]))):
            return True
    team, xy = set(seg.team), np.asarray(robot_positions, float)[:, :2]
    near = np.all((xy > box[:2] - r) & (xy < box[2:] + r), axis=1)
    still = [i for i in np.flatnonzero(near).tolist() if i not in team and i not in moving_robots]
    return bool(still) and bool(shapely.intersects(
        core, standing_robots(xy[still], r)).any())


def meets_moving(seg: Segment, running: Sequence[Segment],
                 claims: Sequence[tuple[int, shapely.Geometry, shapely.Geometry]],
                 way: shapely.Geometry | None = None,
                 seen: np.ndarray | None = None) -> str | None:
    """Why ``seg`` must wait: ``"running k"`` (it cannot run beside object k's running
    segment; ``seen``: the objects' poses read now, see ``spacetime.compatible``) or
    ``"claim k"`` (it would end deeper in object k's claim, ``claims`` being the
    higher-ranked objects' (index, claim, near part); only the near part when ``seg``'s
    object's ``way`` crosses the claim); None when it need not."""
    for other in running:
        if not compatible(other, seg, seen):
            return f"running {other.index}"
    ends, box = None, ends_box(seg)
    for k, full, near in claims:
        if apart(box, np.asarray(full.bounds, float), 0.0):
            continue  # its bodies are outside the claim before and after
        region = near if way is not None and crosses(way, full) else full
        ends = seg.ends() if ends is None else ends
        before, after = (float(shapely.area(shapely.intersection(g, region))) for g in ends)
        if after > before + CLAIM_AREA_SLACK:
            return f"claim {k}"
    return None


def ends_box(seg: Segment) -> np.ndarray:
    """(x0, y0, x1, y1): a box holding ``seg.ends()`` (its bodies before and after it),
    found without building them; kept in ``seg.bounds`` with the rows it came from (a
    waiting segment is asked at every event)."""
    cached = seg.bounds.get("ends")
    if cached is not None and cached[0] is seg.rows:
        return cached[1]
    rows = seg.rows[:, [0, -1]].reshape(-1, 2)
    grow = seg.robot_radius + ROBOT_MARGIN
    boxes = [np.concatenate([rows.min(axis=0) - grow, rows.max(axis=0) + grow]),
             np.asarray(object_space(seg, first=True).bounds, float),
             np.asarray(object_space(seg, final=True).bounds, float)]
    stack = np.stack(boxes)
    box = np.concatenate([stack[:, :2].min(axis=0), stack[:, 2:].max(axis=0)])
    seg.bounds["ends"] = (seg.rows, box)
    return box


def standing_in(region: shapely.Geometry, scene: Scene, object_poses: np.ndarray,
                robot_positions: np.ndarray, teams: Mapping[int, Sequence[int]]
                ) -> frozenset[int]:
    """The objects of ``teams`` (object -> its sub-team's robots) whose body where it
    stands, or a robot of whose sub-team, meets ``region`` (each shrunk by
    ``regions.STATIC_SLACK``, as in :func:`meets_standing`)."""
    r = scene.robot_radius
    return frozenset(k for k, team in teams.items() if region.intersects(
        standing(scene.objects[k].shape, object_poses[k])) or bool(shapely.intersects(
        region, standing_robots(np.asarray(robot_positions, float)[list(team)], r)).any()))


def heeded_claims(objects: Sequence[ObjectState], me: ObjectState, cross_near: float,
                  cross_waiting: float, reach: Sequence[float] = (),
                  pass_margin: float = math.inf, memo: dict | None = None,
                  box: np.ndarray | None = None
                  ) -> list[tuple[int, shapely.Geometry, shapely.Geometry]]:
    """The claims of the ``objects`` ranked above ``me`` that bind it (not those that
    exempt it), as :func:`meets_moving` takes them: (index, claim, the part a plan that
    only crosses it heeds). That part is the claim's near part (``ObjectState.near``)
    with ``cross_near`` > 0, or with ``cross_waiting`` > 0 while its object stands
    waiting: it comes no nearer while it waits, so a crossing far ahead of it is clear
    of it; otherwise the whole claim. Where ``me``'s way passes through the claim ahead
    of its object (:func:`passes_ahead`, ``reach[k]`` each object's share of the reach,
    ``pass_margin``) only the near part binds, for both: it may go through, never into
    the near part. ``memo`` (a dict the caller keeps) remembers
    :func:`passes_ahead`'s answers by the plans' geometries, which never change once
    made: the same answers, each found once. A claim whose box lies apart from ``box``
    (a segment's :func:`ends_box`, by which :func:`meets_moving` then skips it) is given
    whole, :func:`passes_ahead` not asked."""
    out = []
    for o in objects:
        if o.rank >= me.rank or o.claim is None or me.index in o.exempt:
            continue
        if box is not None and apart(box, np.asarray(o.claim.bounds, float), 0.0):
            out.append((o.index, o.claim, o.claim))
        elif (math.isfinite(pass_margin) and me.way is not None and o.way is not None
                and _passes(me.way, o.claim, o.way, reach[me.index] + reach[o.index],
                            pass_margin, memo)):
            out.append((o.index, o.near, o.near))
        else:
            out.append((o.index, o.claim, o.near if cross_near > 0
                        or (cross_waiting > 0 and o.held_up) else o.claim))
    return out


def _passes(way: shapely.LineString, claim: shapely.Geometry, claimer_way: shapely.LineString,
            reach: float, margin: float, memo: dict | None) -> bool:
    """:func:`passes_ahead`, remembered in ``memo`` under the geometries' identities (the
    entry holds them, so no identity is reused while it stands; at most ``_MEMO_KEPT``
    entries, the memo emptied when full); so are the ways' points (:func:`_along`), which
    every claim a way is weighed against reads again."""
    if memo is None:
        return passes_ahead(way, claim, claimer_way, reach, margin)

    def points(line: shapely.LineString, step: float) -> tuple[np.ndarray, np.ndarray]:
        return _kept(memo, ("along", id(line), step), (line,), lambda: _along(line, step))

    return _kept(memo, (id(way), id(claim), id(claimer_way), reach, margin),
                 (way, claim, claimer_way),
                 lambda: passes_ahead(way, claim, claimer_way, reach, margin, along=points))


def _kept(memo: dict, key: tuple, holds: tuple, make: Callable[[], Any]) -> Any:
    """``make()``, remembered in ``memo`` under ``key`` (built from the identities of the
    objects ``holds``, which the entry keeps so none is reused while it stands); at most
    ``_MEMO_KEPT`` entries, the memo emptied when full."""
    hit = memo.get(key)
    if hit is None:
        if len(memo) >= _MEMO_KEPT:
            memo.clear()
        hit = memo[key] = (make(), holds)
    return hit[0]
