"""``RobotSpace.with_obstacle`` and the task's spaces built from it: the very space
``RobotSpace.from_scene`` builds, field value for value."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.geometry.geometry_set import GeometrySet
from lamp.geometry.robot_space import RobotSpace
from lamp.planners.config import PlannerConfig
from lamp.planners.task import ManipulationTask
from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject

W, H = 3.0, 2.0


def _shape(rng: np.random.Generator):
    kind = int(rng.integers(3))
    if kind == 0:
        return Circle(float(rng.uniform(0.03, 0.25)))
    if kind == 1:
        return Rectangle((float(rng.uniform(0.05, 0.5)), float(rng.uniform(0.05, 0.5))))
    return Polygon(((-0.1, -0.08), (0.15, -0.05), (0.02, 0.12)))


def _pose(rng: np.random.Generator) -> tuple[float, float, float]:
    return (float(rng.uniform(0.2, W - 0.2)), float(rng.uniform(0.2, H - 0.2)),
            float(rng.uniform(-3.0, 3.0)))


def _scene(seed: int) -> Scene:
    """A map with its own obstacles, robots standing as disks laid over it (as a team's
    scene has them) and 2-5 objects of every kind."""
    rng = np.random.default_rng(seed)
    fixed = tuple(Obstacle(_shape(rng), _pose(rng)) for _ in range(int(rng.integers(0, 6))))
    standing = tuple(Obstacle(Circle(0.05), (*_pose(rng)[:2], 0.0))
                     for _ in range(int(rng.integers(0, 6))))
    objects = tuple(SceneObject(_shape(rng), _pose(rng), _pose(rng))
                    for _ in range(int(rng.integers(2, 6))))
    scene = Scene("layers", (W, H), ((0.1, 0.1),), objects, fixed)
    return replace(scene, obstacles=fixed + standing, fixed=scene.fixed_obstacles)


def _same(a: RobotSpace, b: RobotSpace) -> None:
    assert np.array_equal(a.field, b.field) and a.origin == b.origin
    for name in ("circles", "verts", "ptr"):
        assert np.array_equal(getattr(a.geometry, name), getattr(b.geometry, name))
    assert a.key == b.key and a.overlay_obstacles == b.overlay_obstacles


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.data())
def test_laying_an_object_over_the_space_without_it_is_building_the_space(seed, data):
    """From the space without object ``k`` (over a window or the whole map), with object
    ``k`` laid over it at a pose: ``from_scene``'s space with ``k`` at that pose."""
    scene = _scene(seed)
    rng = np.random.default_rng(seed + 1)
    k = data.draw(st.integers(0, len(scene.objects) - 1))
    poses = scene.object_starts()
    q = _pose(rng)
    window = None
    if data.draw(st.booleans()):
        x0, y0 = float(rng.uniform(0, W - 1.0)), float(rng.uniform(0, H - 1.0))
        window = (x0, y0, x0 + float(rng.uniform(0.3, 1.0)), y0 + float(rng.uniform(0.3, 1.0)))
    without = RobotSpace.from_scene(scene, poses, exclude_objects=(k,), window=window)
    at = len(scene.obstacles) - len(scene.fixed_obstacles) + k
    field = without.field.copy()
    got = without.with_obstacle(Obstacle(scene.objects[k].shape, q), at)
    moved = poses.copy()
    moved[k] = q
    _same(got, RobotSpace.from_scene(scene, moved, window=window))
    assert np.array_equal(without.field, field)  # the space it was laid over is unchanged


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10**6), st.integers(0, 9), st.integers(0, 9))
def test_inserting_obstacles_is_building_the_longer_list(seed, n, i):
    """``GeometrySet.inserted`` gives the set of the list with the new obstacles at ``i``."""
    rng = np.random.default_rng(seed)
    obs = [Obstacle(_shape(rng), _pose(rng)) for _ in range(n)]
    new = [Obstacle(_shape(rng), _pose(rng)) for _ in range(int(rng.integers(0, 3)))]
    i = min(i, n)
    before = obs[:i]
    got = GeometrySet(obs).inserted(
        GeometrySet(new), sum(isinstance(o.shape, Circle) for o in before),
        sum(not isinstance(o.shape, Circle) for o in before))
    want = GeometrySet(obs[:i] + new + obs[i:])
    for name in ("circles", "verts", "ptr"):
        assert np.array_equal(getattr(got, name), getattr(want, name))


def test_the_tasks_spaces_are_from_scenes_spaces():
    """``ManipulationTask.robot_space_at`` over windows, one after another and back,
    answers with the spaces ``from_scene`` builds."""
    scene = _scene(7)
    task = ManipulationTask(scene, 1, scene.object_starts(), model=None,
                            config=PlannerConfig())
    rng = np.random.default_rng(3)
    for window in [(0.0, 0.0, 1.5, 1.0), (1.0, 0.5, 3.0, 2.0), (0.0, 0.0, 1.5, 1.0), None]:
        q = np.asarray(_pose(rng))
        _same(task.robot_space_at(q, window),
              RobotSpace.from_scene(scene, task.poses_with(q), window=window))
