"""The plane's verdict on reachability (``lamp.search.connectivity``): a wall with no gap
wide enough separates, one with a wide gap does not, and on random maps a "separated"
verdict is never given to two lattice poses a lattice path joins (against the lattice's
own connected components); LAMP-Lazy refuses a walled-in goal before searching."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from lamp.contract.plan import PlanStatus
from lamp.geometry.object_space import ObjectSpace
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle
from lamp.search.connectivity import PlaneConnectivity
from lamp.search.lattice import ObjectLattice

BOX = Rectangle((0.4, 0.2))  # inscribed radius 0.1


def walled(gap: float) -> ObjectSpace:
    """A 4 x 3 m map cut at x = 2 by a wall 0.1 m thick with one gap of ``gap`` m."""
    lo = 1.5 - gap / 2
    wall = [Obstacle(Rectangle((0.1, lo)), (2.0, lo / 2, 0.0)),
            Obstacle(Rectangle((0.1, 3.0 - lo - gap)), (2.0, (lo + gap + 3.0) / 2, 0.0))]
    return ObjectSpace(BOX, (4.0, 3.0), wall)


@pytest.mark.parametrize(("gap", "separated"), [(0.15, True), (0.19, True), (0.3, False),
                                                (0.6, False)])
def test_a_wall_separates_unless_its_gap_lets_the_inscribed_disk_through(gap, separated):
    plane = PlaneConnectivity(walled(gap))
    assert plane.radius == pytest.approx(0.1, abs=1e-5)
    assert plane.separated((1.0, 1.5), (3.0, 1.5, 0.3)) is separated
    assert plane.separated((3.0, 1.5), (1.0, 1.5)) is separated
    assert not plane.separated((1.0, 1.0), (0.5, 2.5))  # the same side


def test_slack_shrinks_the_disk_and_no_verdict_outside_the_free_space():
    space = walled(0.19)
    assert PlaneConnectivity(space).separated((1.0, 1.5), (3.0, 1.5))
    # shrunk by 1 cm the disk (diameter 0.18) passes the 0.19 m gap
    assert not PlaneConnectivity(space, slack=0.01).separated((1.0, 1.5), (3.0, 1.5))
    plane = PlaneConnectivity(space)
    assert plane.component((2.0, 2.9)) is None  # inside the wall: no verdict
    assert not plane.separated((2.0, 2.9), (3.0, 1.5))
    assert not plane.separated((1.0, 1.5), (0.05, 1.5))  # too close to the border
    with pytest.raises(ValueError, match="slack"):
        PlaneConnectivity(space, slack=-0.1)


def test_a_footprint_without_an_inscribed_disk_gets_no_verdict():
    off = Polygon(((0.2, 0.2), (0.3, 0.2), (0.3, 0.3)))  # the origin lies outside it
    plane = PlaneConnectivity(ObjectSpace(off, (4.0, 3.0), walled(0.1).obstacles))
    assert plane.parts == [] and not plane.separated((1.0, 1.5), (3.0, 1.5))


SHAPES = (Rectangle((0.24, 0.12)), Circle(0.08),
          Polygon(((-0.1, -0.06), (0.12, -0.05), (0.02, 0.1))))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_never_separates_two_poses_a_lattice_path_joins(seed):
    """A random wall with a random gap plus random clutter: for every pair of valid
    lattice nodes the plane calls separated, the lattice has no path between them."""
    rng = np.random.default_rng(seed)
    gap = float(rng.uniform(0.02, 0.3))
    at = float(rng.uniform(0.3, 1.2))
    obstacles = [Obstacle(Rectangle((0.06, at - gap / 2)), (0.9, (at - gap / 2) / 2, 0.0)),
                 Obstacle(Rectangle((0.06, 1.5 - at - gap / 2)),
                          (0.9, (1.5 + at + gap / 2) / 2, 0.0))]
    for _ in range(int(rng.integers(0, 5))):
        pose = (*rng.uniform(0, [1.8, 1.5]), float(rng.uniform(-math.pi, math.pi)))
        obstacles.append(Obstacle(Circle(float(rng.uniform(0.03, 0.15))), pose))
    shape = SHAPES[int(rng.integers(len(SHAPES)))]
    space = ObjectSpace(shape, (1.8, 1.5), obstacles, float(rng.choice([0.0, 0.02])))
    lat = ObjectLattice(space, (0.3, 0.3, 0.0), step=0.1, n_headings=8, max_rotation=0.8)
    valid = np.nonzero(lat.validate_all_nodes())[0]
    rows, cols = [], []
    for u in valid:
        for v, _ in lat.successors(int(u)):
            rows.append(int(u))
            cols.append(v)
    graph = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(lat.n_nodes, lat.n_nodes))
    _, label = connected_components(graph, directed=False)
    plane = PlaneConnectivity(space)
    comp = {int(u): plane.component(lat.pose(int(u))) for u in valid}
    for u in valid[:: max(1, len(valid) // 60)]:
        for v in valid[:: max(1, len(valid) // 60)]:
            if plane.separated(lat.pose(int(u)), lat.pose(int(v))):
                assert label[u] != label[v], (lat.pose(int(u)), lat.pose(int(v)))
                assert comp[int(u)] != comp[int(v)]


def test_lazy_refuses_a_walled_in_goal_before_searching():
    from lamp import solve
    from lamp.scene.loader import scene_from_dict

    obstacles = [{"type": "rectangle", "size": list(o.shape.size), "center": list(o.pose[:2])}
                 for o in walled(0.12).obstacles]
    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "walled-in", "workspace": [4.0, 3.0],
        "robots": {"radius": 0.05, "starts": [[0.5, 0.5], [0.5, 1.0], [0.5, 2.5]]},
        "obstacles": obstacles,
        "objects": [{"type": "rectangle", "size": [0.4, 0.2], "start": [1.0, 1.5, 0.0],
                     "goal": [3.0, 1.5, 0.0]}]})
    result = solve(scene, "lazy", 0, model="geometric")
    assert not result.success
    assert result.objects[0].failure_reason == PlanStatus.SEPARATED.reason
    assert result.objects[0].segments == 0
