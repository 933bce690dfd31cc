"""Physics in the scene file: defaults change nothing, values reach the simulator, bad values
are refused by name, and files round-trip."""

from __future__ import annotations

import copy

import jsonschema
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.scene import SceneError, scene_from_dict
from lamp.scene.physics import DEFAULT_PHYSICS, OBJECT_RANGES, PHYSICS_RANGES, Physics
from lamp.scene.schema import scene_schema
from lamp.sim import SETTLE_TIME, Simulator
from lamp.sim.mjcf import build_model

BASE = {
    "format": "lamp-scene/1", "name": "phys", "workspace": [3.0, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.3, 1.0], [0.3, 0.4]]},
    "objects": [{"type": "rectangle", "size": [0.4, 0.3], "start": [1.5, 1.0, 0.0],
                 "goal": [2.2, 1.0, 0.0]},
                {"type": "circle", "radius": 0.15, "start": [1.5, 0.4, 0.0],
                 "goal": [2.2, 0.4, 0.0]}],
}


def _with(**changes) -> dict:
    d = copy.deepcopy(BASE)
    for path, value in changes.items():
        node = d
        *head, last = path.split("__")
        for key in head:
            node = node[int(key)] if key.isdigit() else node.setdefault(key, {})
        node[last] = value
    return d


def test_defaults_written_out_change_nothing():
    plain = scene_from_dict(BASE)
    explicit = scene_from_dict(_with(
        physics__contact_friction=0.5, physics__ground_damping=30.0, robots__speed=0.25,
        robots__force_limit=60.0))
    assert plain.physics == explicit.physics == DEFAULT_PHYSICS
    assert build_model(plain).xml == build_model(explicit).xml
    assert "physics" not in plain.to_dict() and "speed" not in plain.to_dict()["robots"]


def test_values_reach_the_simulator():
    scene = scene_from_dict(_with(
        physics__contact_friction=0.9, physics__ground_damping=12.0, robots__force_limit=25.0,
        objects__0__mass=3.0, objects__0__friction=0.3))
    built = build_model(scene)
    m = built.model
    box, disk = m.body("o0"), m.body("o1")
    assert box.mass[0] == pytest.approx(3.0) and disk.mass[0] == pytest.approx(1.0)
    assert m.dof_damping[built.object_dof[0, 0]] == pytest.approx(12.0 * 3.0)
    assert m.dof_damping[built.object_dof[1, 0]] == pytest.approx(12.0 * 1.0)
    box_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == box.id]
    disk_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == disk.id]
    assert all(m.geom_friction[g, 0] == pytest.approx(0.3) and m.geom_priority[g] == 1
               for g in box_geoms)
    assert all(m.geom_friction[g, 0] == pytest.approx(0.9) and m.geom_priority[g] == 0
               for g in disk_geoms)
    assert np.allclose(m.actuator_forcerange, [[-25.0, 25.0]] * (2 * scene.n_robots))


@pytest.mark.parametrize("speed", [0.125, 0.5])
def test_robot_speed_sets_the_time_a_path_takes(speed):
    scene = scene_from_dict(_with(robots__speed=speed))
    sim = Simulator(scene)
    path = np.linspace([0.3, 1.7], [1.3, 1.7], 51)[None]  # 1 m along the top, clear
    sim.set_state(robot_positions=[[0.3, 1.7], [0.3, 0.4]])
    paths = np.concatenate([path, np.repeat([[[0.3, 0.4]]], 51, axis=1)])
    out = sim.execute(paths)
    assert out.sim_time == pytest.approx(1.0 / speed + SETTLE_TIME, abs=0.01)
    assert np.allclose(out.robot_positions[0], [1.3, 1.7], atol=0.005)


def test_a_heavier_object_resists_more():
    """The same push moves a 20 kg box less than a 1 kg one with weak robots (the force
    limit binds): mass is physics, not decoration."""
    moved = []
    for mass in (1.0, 20.0):
        scene = scene_from_dict(_with(robots__force_limit=8.0, objects__0__mass=mass))
        sim = Simulator(scene)
        sim.set_state(robot_positions=[[1.24, 1.0], [0.3, 0.4]])
        push = np.linspace([1.24, 1.0], [1.84, 1.0], 31)
        paths = np.stack([push, np.repeat([[0.3, 0.4]], 31, axis=0)])
        out = sim.execute(paths)
        moved.append(out.object_poses[0, 0] - 1.5)
    assert moved[0] > 0.3 and moved[1] < 0.5 * moved[0]


@pytest.mark.parametrize(("changes", "fragments"), [
    ({"physics__contact_friction": 3.0}, ("physics.contact_friction: must be in [0.01, 2]",
                                          "got 3")),
    ({"physics__ground_damping": 0.0}, ("physics.ground_damping: must be in [0.1, 500]",
                                        "time constant", "got 0")),
    ({"physics__gravity": 9.8}, ("physics.gravity: unknown key",)),
    ({"robots__speed": -0.1}, ("robots.speed: must be in [0.05, 2]", "got -0.1")),
    ({"robots__speed": 1.192092896e-07}, ("robots.speed: must be in [0.05, 2]",
                                          "10/speed physics steps per 2 cm row")),
    ({"robots__force_limit": "strong"}, ("robots.force_limit: must be a number",)),
    ({"objects__1__mass": 0}, ("objects[1].mass: must be in [0.01, 100]", "got 0")),
    ({"objects__1__mass": 1e-300}, ("objects[1].mass: must be in [0.01, 100]",
                                    "MuJoCo refuses")),
    ({"objects__0__friction": float("nan")}, ("objects[0].friction: must be a finite number",)),
    ({"objects__0__start": [1.5, 1.0, 1e308]}, ("objects[0].start[2]: an angle of at most 1e+06",
                                                "got 1e+308")),
])
def test_bad_values_are_refused_naming_the_field(changes, fragments):
    with pytest.raises(SceneError) as err:
        scene_from_dict(_with(**changes))
    for fragment in fragments:
        assert fragment in str(err.value)


@pytest.mark.parametrize("field", [*PHYSICS_RANGES, *OBJECT_RANGES])
@pytest.mark.parametrize("end", ["low", "high"])
def test_a_push_at_either_end_of_every_range_stays_stable(field, end):
    """What each range's reason promises: a box pushed 0.3 m with the field at that end of
    its range is simulated without MuJoCo reporting an unstable state (which raises)."""
    value = getattr(PHYSICS_RANGES.get(field) or OBJECT_RANGES[field], end)
    key = {"robot_speed": "robots__speed", "robot_force_limit": "robots__force_limit",
           "mass": "objects__0__mass", "friction": "objects__0__friction"}.get(
        field, f"physics__{field}")
    sim = Simulator(scene_from_dict(_with(**{key: value})))
    sim.set_state(robot_positions=[[1.24, 1.0], [0.3, 0.4]])
    push = np.linspace([1.24, 1.0], [1.54, 1.0], 16)
    out = sim.execute(np.stack([push, np.repeat([[0.3, 0.4]], 16, axis=0)]))
    assert np.isfinite(out.object_poses).all() and np.isfinite(out.robot_positions).all()
    assert abs(out.object_poses[1, 0] - 1.5) < 1e-3  # the other object stood still


@settings(max_examples=40, deadline=None)
@given(st.fixed_dictionaries({}, optional={
    "physics__contact_friction": st.floats(0.01, 2.0),
    "physics__ground_damping": st.floats(0.1, 500.0),
    "robots__speed": st.floats(0.05, 2.0),
    "robots__force_limit": st.floats(0.1, 1000.0),
    "objects__0__mass": st.floats(0.01, 100.0),
    "objects__1__friction": st.floats(0.01, 2.0),
}))
def test_files_round_trip_and_match_the_schema(changes):
    d = _with(**changes)
    jsonschema.validate(d, scene_schema())
    scene = scene_from_dict(d)
    again = scene_from_dict(scene.to_dict())
    assert again == scene
    jsonschema.validate(scene.to_dict(), scene_schema())


def test_ranges_are_owned_once():
    assert set(PHYSICS_RANGES) == set(vars(DEFAULT_PHYSICS))
    assert set(OBJECT_RANGES) == {"mass", "friction"}
    with pytest.raises(ValueError, match="Physics.robot_speed: must be in"):
        Physics(robot_speed=5.0)
