"""ObjectLattice: ids, primitives within the model's range, validity against ObjectSpace,
heuristic admissibility/consistency, start connections and nearest nodes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from lamp.geometry import se2
from lamp.geometry.object_space import ObjectSpace
from lamp.scene.model import Circle, Obstacle, Rectangle, Scene, SceneObject
from lamp.search.lattice import PRIMITIVES, ObjectLattice
from lamp.search.metric import lattice_metric, motion_cost

OBSTACLES = (
    Obstacle(Circle(0.15), (0.7, 0.6, 0.0)),
    Obstacle(Rectangle((0.1, 0.6)), (1.2, 0.9, 0.3)),
)


@pytest.fixture(scope="module")
def lattice() -> ObjectLattice:
    space = ObjectSpace(Rectangle((0.3, 0.16)), (1.6, 1.3), OBSTACLES)
    return ObjectLattice(space, (1.33, 0.41, 0.7))


def test_primitive_set():
    assert len(PRIMITIVES) == 26 and len(set(PRIMITIVES)) == 26
    assert (0, 0, 0) not in PRIMITIVES
    for di, dj, dk in PRIMITIVES:
        assert (-di, -dj, -dk) in PRIMITIVES
    assert sum(1 for di, dj, _ in PRIMITIVES if (di, dj) == (0, 0)) == 2


def test_ids_and_poses(lattice):
    goal = lattice.pose(lattice.goal_node)
    np.testing.assert_allclose(goal, [1.33, 0.41, 0.7])
    assert lattice.ijk(lattice.goal_node) == (0, 0, 0)
    ids = np.arange(0, lattice.n_nodes, 7)
    poses = lattice.poses(ids)
    for u, p in zip(ids[:200], poses[:200], strict=True):
        assert lattice.node_id(*lattice.ijk(int(u))) == u
        np.testing.assert_allclose(lattice.pose(int(u)), p, atol=1e-12)
    w, h = lattice.space.workspace
    assert np.all((poses[:, 0] >= -1e-9) & (poses[:, 0] <= w + 1e-9))
    assert np.all((poses[:, 1] >= -1e-9) & (poses[:, 1] <= h + 1e-9))
    with pytest.raises(ValueError, match="outside"):
        lattice.node_id(100, 0, 0)


def test_successors_match_object_space(lattice):
    space = lattice.space
    rng = np.random.default_rng(0)
    for u in rng.choice(lattice.n_nodes, 150, replace=False):
        u = int(u)
        succ = lattice.successors(u)
        if not space.pose_free(lattice.pose(u)):
            assert succ == []
            continue
        got = {v: c for v, c in succ}
        i, j, k = lattice.ijk(u)
        for di, dj, dk in PRIMITIVES:
            try:
                v = lattice.node_id(i + di, j + dj, k + dk)
            except ValueError:
                continue
            pu, pv = lattice.pose(u), lattice.pose(v)
            lo, hi = (pu, pv) if u < v else (pv, pu)
            expect = bool(space.pose_free(pv)) and space.motion_free(lo, hi)
            assert (v in got) == expect
            if expect:
                cost = lattice.step * math.hypot(di, dj) + lattice.w_rot * lattice.dtheta * abs(dk)
                assert got[v] == pytest.approx(cost)
                # the model's range, in the object frame at u
                m = se2.relative(pu, pv)
                assert abs(m[0]) <= 0.2 and abs(m[1]) <= 0.2 and abs(m[2]) <= 0.5
                np.testing.assert_allclose(lattice.primitive(u, v), m)
                # symmetric: v's successors contain u at the same cost
                assert dict(lattice.predecessors(v))[u] == pytest.approx(got[v])
                assert lattice.cost(u, v) == pytest.approx(got[v])


def test_heuristic_admissible_and_consistent(lattice):
    valid = np.nonzero(lattice.validate_all_nodes())[0]
    rows, cols, vals = [], [], []
    for u in valid:
        for v, c in lattice.successors(int(u)):
            rows.append(v)
            cols.append(int(u))
            vals.append(c)
    mat = csr_matrix((vals, (rows, cols)), shape=(lattice.n_nodes, lattice.n_nodes))
    dist = dijkstra(mat, indices=lattice.goal_node)
    reach = valid[np.isfinite(dist[valid])]
    assert len(reach) > 100
    for u in reach:
        h = lattice.heuristic(int(u), lattice.goal_node)
        assert h <= dist[u] + 1e-9
        for v, c in lattice.successors(int(u)):
            assert h <= c + lattice.heuristic(v, lattice.goal_node) + 1e-9


def _all_pairs_reference(lat: ObjectLattice, sources: np.ndarray) -> np.ndarray:
    """Plain Dijkstra over the whole lattice (scipy), from each of ``sources``."""
    rows, cols, vals = [], [], []
    for u in range(lat.n_nodes):
        for v, c in lat.successors(u):
            rows.append(u)
            cols.append(v)
            vals.append(c)
    mat = csr_matrix((vals, (rows, cols)), shape=(lat.n_nodes, lat.n_nodes))
    return dijkstra(mat, indices=sources)


def _random_lattice(seed: int) -> ObjectLattice:
    rng = np.random.default_rng(seed)
    obstacles = [
        Obstacle(Circle(float(rng.uniform(0.03, 0.12))), (*rng.uniform(0, 1.0, 2), 0.0))
        for _ in range(int(rng.integers(0, 4)))
    ]
    space = ObjectSpace(Rectangle((0.16, 0.08)), (1.0, 0.8), obstacles)
    anchor = (*rng.uniform(0.1, 0.7, 2), float(rng.uniform(-math.pi, math.pi)))
    w_rot = float(rng.choice([0.0, 0.05, 0.3]))
    landmark = rng.uniform([0.0, 0.0], [1.0, 0.8]) if rng.random() < 0.5 else None
    return ObjectLattice(space, anchor, step=0.1, n_headings=8, max_rotation=0.8, w_rot=w_rot,
                         landmark=landmark)


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_metric_is_a_consistent_lower_bound_on_random_maps(seed):
    """Against a plain Dijkstra on small random maps (with and without a landmark): the
    heuristic between any two nodes never exceeds the cheapest path cost; it is consistent
    on every edge (h(u, t) <= c(u, v) + h(v, t)) and every edge costs exactly the metric
    between its ends. A start connection costs its motion, at most the metric; lowered by
    the start's slack (the largest excess over its connections, as D* Lite does) the
    heuristic from a continuous pose is consistent on those edges and admissible."""
    lat = _random_lattice(seed)
    rng = np.random.default_rng(seed + 1)
    valid = np.nonzero(lat.validate_all_nodes())[0]
    if len(valid) == 0:
        return
    targets = rng.choice(valid, size=min(4, len(valid)), replace=False)
    dist = _all_pairs_reference(lat, targets)  # edge costs are symmetric: dist[t, u] = d(u, t)
    for row, t in enumerate(targets):
        t = int(t)
        reach = valid[np.isfinite(dist[row, valid])]
        h = np.array([lat.heuristic(int(u), t) for u in reach])
        assert np.all(h <= dist[row, reach] + 1e-9)
        for u in reach[:: max(1, len(reach) // 60)]:
            for v, c in lat.successors(int(u)):
                assert c == pytest.approx(lat.heuristic(int(u), v), abs=1e-12)
                assert lat.heuristic(int(u), t) <= c + lat.heuristic(v, t) + 1e-9
        for _ in range(5):
            p = rng.uniform([0.05, 0.05, -math.pi], [0.95, 0.75, math.pi])
            pose = (float(p[0]), float(p[1]), float(p[2]))
            conns = lat.start_connections(pose)
            slack = max((lat.heuristic(pose, v) - c for v, c in conns), default=0.0)
            for v, c in conns:
                assert c == pytest.approx(motion_cost(pose, lat.pose(v), lat.w_rot), abs=1e-12)
                assert c <= lat.heuristic(pose, v) + 1e-12
                assert lat.heuristic(pose, t) - slack <= c + lat.heuristic(v, t) + 1e-9
            best = min((c + dist[row, v] for v, c in conns), default=math.inf)
            assert lat.heuristic(pose, t) - slack <= best + 1e-9
            if lat.landmark is None:  # the octile norm's excess over the motion's length
                assert slack <= (math.sqrt(4 - 2 * math.sqrt(2)) - 1) * 0.2 * math.sqrt(2) + 1e-9


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_metric_is_exact_in_free_space(seed):
    """With no obstacles, the metric equals the cheapest lattice path between interior
    nodes whose heading bins differ by at most max(|di|, |dj|) (the guarantee that makes
    the search cheap on long routes; the Euclidean norm is below it off the diagonals)."""
    rng = np.random.default_rng(seed)
    space = ObjectSpace(Circle(0.05), (1.2, 1.0), [])
    anchor = (*rng.uniform(0.1, 1.0, 2), float(rng.uniform(-math.pi, math.pi)))
    lat = ObjectLattice(space, anchor, step=0.1, n_headings=8, max_rotation=0.8,
                        w_rot=float(rng.uniform(0.0, 0.3)))
    poses = lat.poses(np.arange(lat.n_nodes))
    interior = np.nonzero((poses[:, 0] >= 0.06) & (poses[:, 0] <= 1.14)
                          & (poses[:, 1] >= 0.06) & (poses[:, 1] <= 0.94))[0]
    sources = rng.choice(interior, size=3, replace=False)
    dist = _all_pairs_reference(lat, sources)
    n_off_axis = 0
    for row, s in enumerate(sources):
        si, sj, sk = lat.ijk(int(s))
        for u in interior:
            i, j, k = lat.ijk(int(u))
            dk = min((k - sk) % 8, (sk - k) % 8)
            if dk <= max(abs(i - si), abs(j - sj)):
                assert lat.heuristic(int(s), int(u)) == pytest.approx(dist[row, u], abs=1e-9)
                n_off_axis += i != si and j != sj and abs(i - si) != abs(j - sj)
    assert n_off_axis > 0


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-7, 7)), min_size=3,
             max_size=3),
    st.floats(0.0, 1.0),
)
def test_metric_triangle_inequality_and_vectorised_agree(poses, w_rot):
    """The metric obeys the triangle inequality and symmetry between continuous poses (D*
    Lite's key modifier relies on it), and the scalar heuristic equals ``distance`` and
    ``lattice_metric``."""
    space = ObjectSpace(Circle(0.1), (2.0, 2.0), [])
    lat = ObjectLattice(space, (1.0, 1.0, 0.0), w_rot=w_rot)
    a, b, c = poses
    assert lat.heuristic(a, c) <= lat.heuristic(a, b) + lat.heuristic(b, c) + 1e-9
    assert lat.heuristic(a, b) == pytest.approx(lat.heuristic(b, a), abs=1e-12)
    assert lat.heuristic(a, b) == pytest.approx(float(lat.distance(a, b)), abs=1e-12)
    d = np.subtract(a, b)
    assert lat.heuristic(a, b) == pytest.approx(lattice_metric(d[0], d[1], d[2], w_rot),
                                                abs=1e-12)
    # never below the Euclidean SE(2) metric, at most sqrt(4 - 2 sqrt 2) above it
    dt, dr = se2.pose_distance(a, b)
    assert dt + w_rot * dr - 1e-9 <= lat.heuristic(a, b)
    assert lat.heuristic(a, b) <= math.sqrt(4 - 2 * math.sqrt(2)) * dt + w_rot * dr + 1e-9


def test_start_connections(lattice):
    space = lattice.space
    rng = np.random.default_rng(1)
    n_some = 0
    for _ in range(40):
        pose = rng.uniform([0.2, 0.2, -math.pi], [1.4, 1.1, math.pi])
        conns = lattice.start_connections(pose)
        n_some += bool(conns)
        costs = [c for _, c in conns]
        assert costs == sorted(costs)
        for v, c in conns:
            pv = lattice.pose(v)
            assert lattice.in_model_range(pose, pv)
            assert space.pose_free(pv) and space.motion_free(pose, pv)
            assert c == pytest.approx(float(motion_cost(pose, pv, lattice.w_rot)))
        # completeness: every in-range node with a free motion is listed
        listed = {v for v, _ in conns}
        for v in lattice._candidates(pose, 0.3, 3):
            pv = lattice.pose(int(v))
            if (
                lattice.in_model_range(pose, pv)
                and space.pose_free(pv)
                and space.motion_free(pose, pv)
            ):
                assert int(v) in listed
    assert n_some > 10
    # near the goal, the goal itself is reachable directly (final approach)
    goal = lattice.pose(lattice.goal_node)
    near = goal + np.array([0.03, -0.05, 0.1])
    assert lattice.goal_node in {v for v, _ in lattice.start_connections(near)}
    assert lattice.connection_cost(near, goal) == pytest.approx(
        float(motion_cost(near, goal, lattice.w_rot)))
    assert lattice.connection_cost(near, goal + np.array([0.3, 0.0, 0.0])) is None


def test_start_connections_tolerance_leaves_contact():
    wall = Obstacle(Rectangle((0.1, 1.0)), (0.55, 0.5, 0.0))
    space = ObjectSpace(Rectangle((0.2, 0.2)), (1.0, 1.0), [wall])
    lat = ObjectLattice(space, (0.25, 0.5, 0.0))
    touching = np.array([0.395, 0.5, 0.0])  # 5 mm from the wall: inside the checker's band
    assert not space.pose_free(touching)
    assert lat.start_connections(touching) == []
    conns = lat.start_connections(touching, tolerance=0.02)
    assert conns and all(lat.pose(v)[0] < 0.4 for v, _ in conns)


def test_nearest_nodes(lattice):
    pose = np.array([0.41, 1.02, -2.0])
    near = lattice.nearest_nodes(pose, 0.15, valid_only=False)
    d = [x for _, x in near]
    assert d == sorted(d) and all(x <= 0.15 for x in d)
    brute = lattice.distance(pose, lattice.poses(np.arange(lattice.n_nodes)))
    assert len(near) == int(np.sum(brute <= 0.15))
    on_node = lattice.pose(lattice.goal_node)
    assert lattice.nearest_nodes(on_node, 1e-6)[0][0] == lattice.goal_node


def test_from_scene_and_bad_arguments():
    scene = Scene(
        name="t",
        workspace=(1.0, 1.0),
        robot_starts=((0.05, 0.05),),
        objects=(
            SceneObject(Circle(0.1), (0.3, 0.3, 0.0), (0.7, 0.7, 0.0)),
            SceneObject(Circle(0.1), (0.7, 0.3, 0.0), (0.3, 0.7, 0.0)),
        ),
    )
    lat = ObjectLattice.from_scene(scene, 0)
    np.testing.assert_allclose(lat.pose(lat.goal_node), [0.7, 0.7, 0.0])
    assert not lat.node_valid(lat.node_id(0, -4, 0))  # object 1 sits at (0.7, 0.3)
    space = lat.space
    with pytest.raises(ValueError, match="step"):
        ObjectLattice(space, (0.5, 0.5, 0.0), step=0.2)
    with pytest.raises(ValueError, match="n_headings"):
        ObjectLattice(space, (0.5, 0.5, 0.0), n_headings=8)
    with pytest.raises(ValueError, match="anchor"):
        ObjectLattice(space, (0.5, 0.5))
    with pytest.raises(ValueError, match="tolerance"):
        lat.start_connections((0.5, 0.5, 0.0), tolerance=-1.0)


def test_a_thin_object_joins_the_lattice_without_shrinking_to_nothing():
    """The planners join a drifted object to the lattice with footprints shrunk by up to
    2 cm; an object thinner than that is joined with the tolerances it survives (before,
    the shrunk footprint raised and the run ended in an internal error)."""
    from lamp.planners.lazy import JOIN_TOLERANCES, join_lattice

    space = ObjectSpace(Rectangle((0.4, 0.01)), (1.6, 1.3), OBSTACLES)
    lat = ObjectLattice(space, (1.33, 0.41, 0.7))
    with pytest.raises(ValueError):
        lat.tolerant_space(max(JOIN_TOLERANCES))
    pose = np.array([0.41, 0.37, 0.013])  # off the lattice
    real = lat.start_connections
    asked = []

    def no_exact_join(q, tolerance=0.0):  # as for an object drifted into contact
        asked.append(tolerance)
        return [] if tolerance == 0.0 else real(q, tolerance=tolerance)

    lat.start_connections = no_exact_join
    node, edges = join_lattice(lat, pose)
    assert node == tuple(pose.tolist()) and edges == []
    assert asked == [0.0, JOIN_TOLERANCES[1]]
