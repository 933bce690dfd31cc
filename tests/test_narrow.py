"""Narrow passages off the lattice: aligned poses, the refined lattice and a full run."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Point

from lamp import solve
from lamp.geometry.exact_space import ExactSpace
from lamp.geometry.object_space import ObjectSpace
from lamp.planners.lazy import join_lattice
from lamp.scene.loader import scene_from_dict
from lamp.scene.model import Circle, Polygon, Rectangle
from lamp.search.dstar_lite import DStarLite
from lamp.search.lattice import ObjectLattice
from lamp.search.narrow import aligned_headings, narrow_poses
from lamp.search.refined_lattice import (
    EDGE_OVERHEAD,
    LINK_CLEARANCE,
    TIGHT_LINK_COST,
    TIGHT_TURN,
    RefinedLattice,
)
from lamp.suites.corridor_layout import wall_polygons


def corridor_scene(angle_deg: float, clearance: float, size=(0.4, 0.3), length=2.6) -> dict:
    """Two round rooms joined by a straight corridor at ``angle_deg``, ``clearance`` wider
    than the object's short side; walls cut into simple polygons (the corridor family's)."""
    a = math.radians(angle_deg)
    s = np.array([0.9, 1.0 if angle_deg >= 0 else 2.0])
    g = s + length * np.array([math.cos(a), math.sin(a)])
    w, h = 5.0, 3.0
    free = shapely.union_all([Point(*s).buffer(0.75), Point(*g).buffer(0.75),
                              LineString([s, g]).buffer((size[1] + clearance) / 2,
                                                        cap_style="flat")])
    polys = [{"type": "polygon", "points": pts.tolist()} for pts in wall_polygons((w, h), free)]
    return {"format": "lamp-scene/1", "name": "corridor", "workspace": [w, h],
            "robots": {"radius": 0.05,
                       "starts": [[float(s[0]) - 0.5, float(s[1]) + dy] for dy in (-0.2, 0, 0.2)]},
            "obstacles": polys,
            "objects": [{"type": "rectangle", "size": list(size),
                         "start": [float(s[0]), float(s[1]), 0.3],
                         "goal": [float(g[0]), float(g[1]), -0.5]}]}


def test_aligned_headings_lay_the_narrow_side_across():
    rows = aligned_headings(Rectangle((0.4, 0.3)), 0.3)
    assert len(rows) == 4
    assert rows[0][2] == pytest.approx(0.3) and rows[-1][2] == pytest.approx(0.4)
    for theta, shift, _ in rows[:2]:
        assert math.remainder(theta - 0.3, math.pi) == pytest.approx(0.0, abs=1e-9)
        assert shift == pytest.approx(0.0, abs=1e-12)
    # an off-centre triangle: the shift centres its extent across the corridor
    tri = Polygon(((0.0, 0.0), (0.3, 0.0), (0.0, 0.1)))
    for theta, shift, width in aligned_headings(tri, 0.0):
        c, s = math.cos(theta), math.sin(theta)
        ys = [s * x + c * y + shift for x, y in tri.points]
        assert max(ys) + min(ys) == pytest.approx(0.0, abs=1e-9)
        assert max(ys) - min(ys) == pytest.approx(width)
    circle = aligned_headings(Circle(0.2), 0.1)  # any heading within 22.5 degrees of one
    gaps = np.diff(np.sort(np.remainder([t for t, _, _ in circle], 2 * math.pi)))
    assert len(circle) == 8 and np.allclose(gaps, math.pi / 4)
    given = aligned_headings(Circle(0.2), 0.1, circle_headings=[0.5, -3.0, 4.0])
    assert [t for t, _, _ in given] == pytest.approx([0.5, -3.0, 4.0 - 2 * math.pi])
    assert all(shift == 0.0 and width == pytest.approx(0.4) for _, shift, width in given)


@pytest.mark.parametrize("angle", [17.0, -38.5])
def test_narrow_poses_are_free_centred_and_aligned(angle):
    scene = scene_from_dict(corridor_scene(angle, 0.02))
    space = ObjectSpace.from_scene(scene, 0)
    exact = ExactSpace.from_space(space)
    poses = narrow_poses(space, exact, (0.0, 0.0, 5.0, 3.0))
    assert len(poses) > 20
    assert exact.pose_free(poses).all()
    phi = math.radians(angle)
    start = np.array(scene.objects[0].start[:2])
    u = np.array([math.cos(phi), math.sin(phi)])
    rel = poses[:, :2] - start
    along = rel @ u
    inside = (along > 0.8) & (along < 1.8)  # well inside the corridor, away from the rooms
    assert inside.sum() >= 10
    across = rel[inside] @ np.array([-u[1], u[0]])
    assert np.abs(across).max() < 0.011  # centred to the clearance
    dth = np.abs(np.remainder(poses[inside, 2] - phi + math.pi / 2, math.pi) - math.pi / 2)
    assert dth.max() < math.radians(1.5)  # long side along the corridor


def _refined_cost(refined, a, v, cost):
    """(turns where tight, the cost the module promises, ``cost``) of the motion from pose
    ``a`` to extra vertex ``v``: the metric plus ``EDGE_OVERHEAD``, plus ``TIGHT_LINK_COST``
    when it turns by more than ``TIGHT_TURN`` where either end is tighter than
    ``LINK_CLEARANCE``."""
    b = refined.pose(v)
    turn = abs(math.remainder(b[2] - a[2], 2 * math.pi))
    tight = min(refined.exact.clearance(a), refined.exact.clearance(b)) < LINK_CLEARANCE
    tight_turn = bool(tight and turn > TIGHT_TURN)
    want = float(refined.distance(a, b)) + EDGE_OVERHEAD + (TIGHT_LINK_COST if tight_turn else 0.0)
    return tight_turn, want, cost


def test_refined_lattice_is_the_lattice_until_refined_then_passes_the_corridor():
    scene = scene_from_dict(corridor_scene(17.0, 0.02))
    space = ObjectSpace.from_scene(scene, 0)
    goal = scene.objects[0].goal
    plain, refined = ObjectLattice(space, goal), RefinedLattice(space, goal)
    rng = np.random.default_rng(0)
    for u in rng.integers(0, plain.n_nodes, 50).tolist():
        assert plain.successors(u) == refined.successors(u)
    start = np.array(scene.objects[0].start)
    d = DStarLite(plain)
    d.initialize(plain.goal_node)
    assert not d.plan_shortest_path(*join_lattice(plain, start))  # the lattice cannot pass
    added = refined.refine(start)
    assert added > 0 and refined.refine(start) == 0  # once per window
    # symmetric adjacency, every refined edge certified free; lattice links only in the open
    for u in range(refined.n_nodes, refined.n_nodes + refined.n_extra):
        for v, c in refined.successors(u):
            assert (u, c) in refined.successors(v)
            assert c >= refined.heuristic(u, v)
            if v < refined.n_nodes and refined.exact.clearance(refined.pose(u)) < LINK_CLEARANCE:
                metric = float(refined.distance(refined.pose(u), refined.pose(v)))
                assert c >= metric + TIGHT_LINK_COST  # turning in the passage costs more
            if v >= refined.n_nodes:  # extra <-> extra: the tight-turn cost, exactly
                _, want, _ = _refined_cost(refined, refined.pose(u), v, c)
                assert c == pytest.approx(want, abs=1e-9)
    # a start off the refined poses (turned 0.1 rad) joins them at the same costs
    rng = np.random.default_rng(0)
    extra = np.array([refined.pose(u) for u in range(refined.n_nodes,
                                                     refined.n_nodes + refined.n_extra)])
    costs = []
    for k in rng.choice(len(extra), 40, replace=False):
        a = extra[k] + np.array([0.0, 0.0, rng.choice([-0.1, 0.1])])
        costs += [_refined_cost(refined, a, v, c) for v, c in refined.start_connections(a)
                  if v >= refined.n_nodes]
    assert sum(tight for tight, _, _ in costs) > 0 and sum(not t for t, _, _ in costs) > 0
    assert all(c == pytest.approx(want, abs=1e-9) for _, want, c in costs)
    d = DStarLite(refined)
    d.initialize(refined.goal_node)
    path = d.plan_shortest_path(*join_lattice(refined, start))
    assert path and path[-1] == refined.goal_node
    poses = refined.path_poses(path)
    exact = refined.exact
    assert all(exact.motion_free(a, b) or space.motion_free(a, b)
               for a, b in zip(poses[:-1], poses[1:], strict=True))


def test_a_circle_passes_a_corridor_on_the_lattice_headings():
    """A circle fits at any heading: its corridor poses take the lattice headings next to
    its own heading and the goal's, so the refined path need not turn it in the corridor."""
    d = corridor_scene(17.0, 0.02)
    d["objects"][0] = {"type": "circle", "radius": 0.15, "start": d["objects"][0]["start"][:2]
                       + [3 * math.pi / 8], "goal": d["objects"][0]["goal"][:2] + [0.0]}
    scene = scene_from_dict(d)
    space = ObjectSpace.from_scene(scene, 0)
    refined = RefinedLattice(space, scene.objects[0].goal)
    start = np.array(scene.objects[0].start)
    assert refined.refine(start) > 0
    extra = np.array([refined.pose(u) for u in
                      range(refined.n_nodes, refined.n_nodes + refined.n_extra)])
    steps = (extra[:, 2] - refined.anchor[2]) / refined.dtheta
    assert np.allclose(steps, np.round(steps), atol=1e-9)
    used = set((np.round(steps).astype(int) % refined.n_headings).tolist())
    assert used == {15, 0, 1, 2, 3, 4}  # the goal's heading (0) and the start's (3) +- 1
    dstar = DStarLite(refined)
    dstar.initialize(refined.goal_node)
    path = dstar.plan_shortest_path(*join_lattice(refined, start))
    assert path and path[-1] == refined.goal_node


def test_lazy_pushes_a_box_through_a_tilted_corridor_two_centimetres_wider():
    """The learned model, MuJoCo execution: 1 cm a side, 17 degrees off the lattice."""
    scene = scene_from_dict(corridor_scene(17.0, 0.02))
    result = solve(scene, "lazy", seed=0).to_dict()
    assert result["success"], result["objects"][0]["failure_reason"]


def test_refined_links_are_checked_when_asked_and_alike_in_any_order():
    """Refinement proposes links and checks none; a vertex's links are checked when it is
    first asked for, and every vertex gets the same links, in the same order, whatever
    order the search asks in."""
    scene = scene_from_dict(corridor_scene(-30.0, 0.03))
    space = ObjectSpace.from_scene(scene, 0)
    goal, start = scene.objects[0].goal, np.array(scene.objects[0].start)
    a, b = RefinedLattice(space, goal), RefinedLattice(space, goal)
    for lat in (a, b):
        checks = lat.n_motion_checks
        assert lat.refine(start) > 0
        lat.refine(start + np.array([0.3, 0.1, 0.0]))
        assert lat.n_motion_checks == checks  # nothing checked yet
    u0 = a.n_nodes
    a.successors(u0)
    asked_one = a.n_motion_checks
    assert asked_one > 0
    extras = list(range(a.n_nodes, a.n_nodes + a.n_extra))
    ends = sorted({v for u in extras for v, _ in a.successors(u)} | set(extras))
    assert a.n_motion_checks > asked_one
    order = np.random.default_rng(1).permutation(ends).tolist()
    assert all(b.successors(u) == a.successors(u) for u in order)
    assert b.n_motion_checks == a.n_motion_checks  # each link checked once
