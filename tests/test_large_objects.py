"""Large objects (1-1.5 m bars, L and T shapes up to 1.2 m) through the whole pipeline:
scene file, ObjectSpace, simulator bodies, LAMP-Lazy end to end, teams of 6 robots."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

import lamp
from lamp.geometry import se2
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.shapes import to_shapely
from lamp.manip.evaluate import l_shape, t_shape
from lamp.scene.model import Circle, Obstacle, Rectangle
from lamp.sim import Simulator
from lamp.sim.mjcf import OBJECT_MASS, build_model, plate_properties

L_12 = l_shape(1.2, 0.9, 0.2)
T_12 = t_shape(1.2, 0.8, 0.2)


def _scene_file(tmp_path, shape: dict, n_robots: int, goal=(2.3, 2.1, 0.4)):
    """An open 4 m map, robots in a row at the bottom, the object at (1.5, 1.5, 0) and its
    goal ~1 m away turned by 0.4 rad; written as a scene file and loaded back."""
    d = {"format": "lamp-scene/1", "name": "large", "workspace": [4.0, 4.0],
         "robots": {"starts": [[0.3 + 0.3 * i, 0.3] for i in range(n_robots)]},
         "objects": [{**shape, "start": [1.5, 1.5, 0.0], "goal": list(goal)}]}
    path = tmp_path / "large.yaml"
    path.write_text(yaml.safe_dump(d))
    return lamp.load_scene(path)


def _check_run(result, scene):
    d = result.to_dict()
    assert d["success"], d["objects"]
    obj = d["objects"][0]
    assert obj["position_error"] <= 0.1 and obj["orientation_error"] <= 0.1
    assert not obj["left_workspace"]
    robots = result.recording.arrays["robots"].astype(float)
    assert robots.shape[1] == scene.n_robots
    if scene.n_robots > 1:  # no two robots ever overlap
        dist = np.hypot(*(robots[:, :, None] - robots[:, None]).transpose(3, 0, 1, 2))
        iu = np.triu_indices(scene.n_robots, 1)
        assert dist[:, iu[0], iu[1]].min() >= 2 * scene.robot_radius - 2e-3
    return d


# --------------------------------------------------------------------------- end to end
@pytest.mark.parametrize("model", ["learned", "geometric"])
def test_lazy_pushes_a_long_bar_a_metre_and_turns_it(tmp_path, model):
    scene = _scene_file(tmp_path, {"type": "rectangle", "size": [1.2, 0.1]}, 3)
    assert math.dist(scene.objects[0].start[:2], scene.objects[0].goal[:2]) == pytest.approx(1.0)
    _check_run(lamp.solve(scene, planner="lazy", seed=0, model=model), scene)


@pytest.mark.parametrize("shape", [L_12, T_12], ids=["L", "T"])
def test_lazy_moves_l_and_t_shapes(tmp_path, shape):
    scene = _scene_file(tmp_path, shape.to_dict(), 3)
    _check_run(lamp.solve(scene, planner="lazy", seed=0), scene)


@pytest.mark.parametrize("shape", [Rectangle((1.5, 0.15)), L_12], ids=["bar", "L"])
def test_six_robots_move_a_large_object(tmp_path, shape):
    """The model uses at most 3 pushers; the other robots wait out of the way (Gspi routes
    all six, none ever overlaps another)."""
    scene = _scene_file(tmp_path, shape.to_dict(), 6)
    _check_run(lamp.solve(scene, planner="lazy", seed=0), scene)


def test_large_object_runs_are_deterministic(tmp_path):
    scene = _scene_file(tmp_path, T_12.to_dict(), 3)
    a = lamp.solve(scene, planner="lazy", seed=1).recording.arrays
    b = lamp.solve(scene, planner="lazy", seed=1).recording.arrays
    np.testing.assert_array_equal(a["robots"], b["robots"])
    np.testing.assert_array_equal(a["objects"], b["objects"])


# --------------------------------------------------------------------------- pieces
@pytest.mark.parametrize("shape", [Rectangle((1.5, 0.1)), L_12, T_12], ids=["bar", "L", "T"])
def test_simulated_bodies_of_large_objects(shape):
    """Centroid and planar inertia of the body are those of the uniform plate (Shapely)."""
    geom = to_shapely(shape)
    centroid, rho2 = plate_properties(shape)
    np.testing.assert_allclose(centroid, [geom.centroid.x, geom.centroid.y], atol=1e-12)
    # polar moment about the centroid by a fine grid over the shape
    g = np.linspace(-0.8, 0.8, 801)
    xx, yy = np.meshgrid(g, g)
    inside = shapely.contains_xy(geom, xx, yy)
    r2 = (xx[inside] - centroid[0]) ** 2 + (yy[inside] - centroid[1]) ** 2
    assert rho2 == pytest.approx(r2.mean(), rel=1e-2)
    scene = lamp.scene_from_dict({
        "format": "lamp-scene/1", "name": "body", "workspace": [4.0, 4.0],
        "robots": {"starts": [[0.2, 0.2]]},
        "objects": [{**shape.to_dict(), "start": [2.0, 2.0, 0.3], "goal": [2.0, 2.0, 0.3]}]})
    built = build_model(scene)
    body = built.model.body("o0")
    assert body.mass[0] == pytest.approx(OBJECT_MASS)
    assert body.inertia[2] == pytest.approx(OBJECT_MASS * rho2)
    # the body starts where the scene puts it, and stays there untouched
    out = Simulator(scene).execute(np.array([[[0.2, 0.2], [0.2, 0.2]]]))
    np.testing.assert_allclose(out.object_poses[0], [2.0, 2.0, 0.3], atol=1e-6)


def test_rotating_a_long_bar_sweeps_its_ends():
    """A 1.5 m bar turning 0.39 rad on the spot moves its ends ~0.29 m: an obstacle that only
    the sweep touches blocks the motion, and the free motion is accepted."""
    bar = Rectangle((1.5, 0.1))
    start, end = np.array([2.0, 2.0, 0.0]), np.array([2.0, 2.0, 2 * math.pi / 16])
    tip = se2.transform_points(se2.interpolate(start, end, 0.5), np.array([[0.75, 0.0]]))[0]
    post = Obstacle(Circle(0.03), (float(tip[0]), float(tip[1]), 0.0))
    space = ObjectSpace(bar, (4.0, 4.0), (post,))
    assert space.pose_free(np.stack([start, end])).all()
    assert not space.motion_free(start, end)
    assert ObjectSpace(bar, (4.0, 4.0), ()).motion_free(start, end)


big = st.one_of(
    st.builds(lambda a, b: Rectangle((a, b)), st.floats(1.0, 1.6), st.floats(0.08, 0.25)),
    st.builds(l_shape, st.floats(0.8, 1.2), st.floats(0.5, 0.8), st.floats(0.12, 0.25)),
    st.builds(t_shape, st.floats(0.8, 1.2), st.floats(0.5, 0.8), st.floats(0.12, 0.25)),
)


@settings(max_examples=40, deadline=None)
@given(big, st.floats(0.8, 3.2), st.floats(0.8, 3.2), st.floats(-0.5, 0.5),
       st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-0.5, 0.5))
def test_object_space_motions_of_large_objects_are_conservative(shape, ox, oy, dth, dx, dy,
                                                               turn):
    """A motion reported free never passes through a pose that hits an obstacle (dense
    Shapely check of the sweep)."""
    obstacles = (Obstacle(Circle(0.1), (2.0, 2.0, 0.0)),
                 Obstacle(Rectangle((0.6, 0.1)), (1.0, 3.0, 0.7)))
    space = ObjectSpace(shape, (4.0, 4.0), obstacles)
    a = np.array([ox, oy, dth])
    b = se2.compose(a, np.array([dx, dy, turn]))
    if not space.motion_free(a, b):
        return
    walls = shapely.box(0, 0, 4, 4)
    blocked = shapely.union_all([to_shapely(o.shape, o.pose) for o in obstacles])
    for s in np.linspace(0.0, 1.0, 60):
        foot = to_shapely(shape, se2.interpolate(a, b, s))
        assert not foot.intersects(blocked)
        assert walls.buffer(1e-9).contains(foot)


def test_lattice_keeps_every_primitive_of_a_long_bar_in_the_open():
    """Nothing in the lattice rejects a 1.5 m bar's primitives (a 0.39 rad turn sweeps its
    ends ~0.29 m); a turn costs the arc its farthest point travels."""
    from lamp.search.lattice import PRIMITIVES, ObjectLattice

    bar = Rectangle((1.5, 0.1))
    lat = ObjectLattice(ObjectSpace(bar, (4.0, 4.0), ()), (2.0, 2.0, 0.0))
    succ = lat.successors(lat.anchor_node)
    assert len(succ) == len(PRIMITIVES)
    turns = [c for v, c in succ if lat.ijk(v)[:2] == (0, 0)]
    assert turns == pytest.approx([bar.bounding_radius * 2 * math.pi / 16] * 2)
