"""lamp.env: API checkers, determinism, task semantics, observations and bad input."""

from __future__ import annotations

import math
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st
from pettingzoo.test import parallel_api_test

import lamp.env
from lamp.env import PushConfig, PushEnv, RewardWeights, parallel_env
from lamp.scene import SceneError, scene_from_dict
from lamp.suites import export_suite

# a free 2 x 2 m workspace with two circle obstacles (a reference clearance is easy to write)
OPEN = {
    "format": "lamp-scene/1",
    "name": "open",
    "workspace": [2.0, 2.0],
    "robots": {"radius": 0.05, "starts": [[0.3, 0.3], [0.3, 1.7], [1.7, 0.3]]},
    "obstacles": [
        {"type": "circle", "center": [1.5, 1.5], "radius": 0.2},
        {"type": "circle", "center": [0.6, 1.2], "radius": 0.1},
    ],
    "objects": [
        {"type": "rectangle", "size": [0.3, 0.2], "start": [1.0, 0.6, 0.0],
         "goal": [1.0, 1.0, 0.0]},
        {"type": "circle", "radius": 0.1, "start": [1.6, 0.9, 0.0], "goal": [1.4, 0.9, 0.0]},
    ],
}


@pytest.fixture(scope="module")
def open_scene():
    return scene_from_dict(OPEN)


def test_gym_env_passes_check_env():
    env = gymnasium.make("lamp/Push-v0", scene="random-01", render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the checker reports problems as warnings too
        check_env(env.unwrapped)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert env.action_space.shape == (3, 2)


def test_parallel_env_passes_api_test():
    env = parallel_env(scene="maze-07")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(env, num_cycles=300)
    assert env.possible_agents == ["robot_0", "robot_1", "robot_2"]


def _rollout(env, actions):
    obs, info = env.reset(seed=3)
    out = [(obs, 0.0, info)]
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append((obs, r, info))
        if term or trunc:
            break
    return out


def _same(a, b):
    for (oa, ra, ia), (ob, rb, ib) in zip(a, b, strict=True):
        assert ra == rb and ia == ib
        for k in oa:
            assert np.array_equal(oa[k], ob[k]), k


def test_gym_env_is_deterministic_across_instances_and_resets():
    actions = np.random.default_rng(1).uniform(-1, 1, (150, 3, 2))
    a = PushEnv("tilt-03")
    first = _rollout(a, actions)
    _same(first, _rollout(a, actions))  # same instance after reset
    _same(first, _rollout(PushEnv("tilt-03"), actions))  # a new instance
    moved = [o["robots"] for o, _, _ in first]
    assert not np.array_equal(moved[0], moved[-1])  # the actions did something


def test_parallel_env_matches_gym_env():
    """The per-agent observations are the centralised one seen from each robot, and the team
    reward is the Gymnasium reward, step for step."""
    actions = np.random.default_rng(2).uniform(-1, 1, (60, 3, 2))
    g, p = PushEnv("maze-03"), parallel_env("maze-03")
    go, _ = g.reset()
    po, _ = p.reset()
    for a in actions:
        for i, agent in enumerate(p.agents):
            assert np.array_equal(po[agent]["self"], go["robots"][i])
            assert np.array_equal(po[agent]["others"], np.delete(go["robots"], i, axis=0))
            assert np.array_equal(po[agent]["patch"], go["patch"][i])
            assert np.array_equal(po[agent]["goal"], go["goal"])
        go, gr, _, _, _ = g.step(a)
        po, pr, _, _, _ = p.step({f"robot_{i}": a[i] for i in range(3)})
        assert set(pr.values()) == {gr}


def test_scene_by_name_equals_scene_by_file(tmp_path):
    export_suite("maze", tmp_path)
    by_name, by_file = PushEnv("maze-07"), PushEnv(tmp_path / "maze-07.yaml")
    assert by_name.scene == by_file.scene
    actions = np.random.default_rng(0).uniform(-1, 1, (20, 3, 2))
    _same(_rollout(by_name, actions), _rollout(by_file, actions))


@pytest.mark.parametrize("name", ["maze-99", "mazes-01", "nothing.yaml", "random"])
def test_unknown_scene_is_a_clear_error(name):
    with pytest.raises(SceneError, match=f"unknown scene '{name}'.*suites: random, maze"):
        gymnasium.make("lamp/Push-v0", scene=name)
    with pytest.raises(SceneError, match=f"unknown scene '{name}'"):
        parallel_env(scene=name)


def test_invalid_scene_file_names_the_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("format: lamp-scene/1\nname: x\n")
    with pytest.raises(SceneError, match="bad.yaml"):
        PushEnv(bad)


def test_non_finite_and_malformed_actions_are_rejected(open_scene):
    env = PushEnv(open_scene)
    env.reset()
    before = env.core.robot_positions().copy()
    bad = np.zeros((3, 2))
    bad[1, 0] = np.nan
    with pytest.raises(ValueError, match=r"action\[1\] = \[nan, 0.0\] is not finite"):
        env.step(bad)
    with pytest.raises(ValueError, match=r"action has shape \(4,\), expected \(3, 2\)"):
        env.step(np.zeros(4))
    with pytest.raises(ValueError, match="numeric array"):
        env.step("fast")
    assert np.array_equal(env.core.robot_positions(), before)  # nothing was simulated
    penv = parallel_env(open_scene)
    penv.reset()
    acts = {a: np.zeros(2) for a in penv.agents}
    acts["robot_2"] = np.array([np.inf, 0.0])
    with pytest.raises(ValueError, match=r"actions\['robot_2'\] = \[inf, 0.0\] is not finite"):
        penv.step(acts)
    with pytest.raises(ValueError, match="no action for agent 'robot_0'"):
        penv.step({"robot_1": np.zeros(2), "robot_2": np.zeros(2)})
    with pytest.raises(ValueError, match="unknown agent 'robot_7'"):
        penv.action_space("robot_7")


@pytest.mark.parametrize(
    ("setting", "value"),
    [("frame_skip", 0), ("frame_skip", 2.5), ("max_speed", -1.0), ("time_limit", math.inf),
     ("position_tolerance", 0.0), ("orientation_tolerance", -0.1), ("patch_size", 4),
     ("patch_spacing", math.nan)],
)
def test_bad_settings_name_the_field(setting, value):
    with pytest.raises(ValueError, match=f"{setting} = "):
        PushEnv("random-01", **{setting: value})


def test_bad_reward_weight_and_unknown_settings():
    with pytest.raises(ValueError, match="reward.success = -1"):
        RewardWeights(success=-1)
    with pytest.raises(ValueError, match="unknown environment setting.*'speed'"):
        PushEnv("random-01", speed=1.0)
    env = PushEnv("random-01")
    with pytest.raises(ValueError, match="unknown reset option.*'goals'"):
        env.reset(options={"goals": [1, 1, 0]})
    with pytest.raises(ValueError, match="goal = .*finite pose"):
        env.reset(options={"goal": [1.0, math.nan, 0.0]})
    with pytest.raises(ValueError, match="object = 3: must be an object index"):
        env.reset(options={"object": 3})
    with pytest.raises(ValueError, match="render_mode = 'human'"):
        PushEnv("random-01", render_mode="human")


def test_objects_succeed_in_order_then_the_episode_terminates(open_scene):
    """An object within tolerance of its goal succeeds at the end of the step (success bonus
    paid), the next object becomes active, the last one ends the episode."""
    env = PushEnv(open_scene)
    starts = open_scene.object_starts()
    env.reset(options={"goal": starts[0]})  # object 0 already sits at its (new) goal
    _, r, term, trunc, info = env.step(np.zeros((3, 2)))
    assert info["placed"] == 0 and info["object"] == 1 and not (term or trunc)
    assert r > RewardWeights().success - 1.0
    env.core.set_goal(starts[1])
    obs, r, term, trunc, info = env.step(np.zeros((3, 2)))
    assert term and not trunc and info["is_success"] and info["placed"] == 1
    # the observation now refers to object 1 (a circle of radius 0.1)
    assert np.allclose(obs["extent"], [0.1, 0.1])
    with pytest.raises(ValueError, match="episode is over"):
        env.step(np.zeros((3, 2)))


def test_orientation_is_ignored_when_its_tolerance_is_none(open_scene):
    start = open_scene.object_starts()[0]
    turned = start + [0.0, 0.0, 1.0]
    strict = PushEnv(open_scene)
    strict.reset(options={"goal": turned})
    assert strict.step(np.zeros((3, 2)))[4]["placed"] == -1
    loose = PushEnv(open_scene, orientation_tolerance=None, position_tolerance=0.5)
    loose.reset(options={"goal": turned + [0.3, 0.0, 0.0]})
    assert loose.step(np.zeros((3, 2)))[4]["placed"] == 0


@settings(max_examples=8, deadline=None)
@given(st.integers(1, 20), st.floats(0.01, 0.5))
def test_truncation_after_the_time_limit(frame_skip, time_limit):
    env = PushEnv("random-02", frame_skip=frame_skip, time_limit=time_limit)
    env.reset()
    period = frame_skip * 0.002
    expected = max(1, math.ceil(time_limit / period - 1e-9))
    n = 0
    while True:
        n += 1
        _, _, term, trunc, info = env.step(np.zeros((3, 2)))
        if term or trunc:
            break
    assert trunc and not term and n == expected
    assert info["sim_time"] == pytest.approx(n * period)


def test_object_outside_the_workspace_ends_the_episode(open_scene):
    env = PushEnv(open_scene)
    poses = open_scene.object_starts()
    poses[1] = [1.95, 0.9, 0.0]  # the circle (r = 0.1) reaches 5 cm past the border x = 2
    env.reset(options={"object_poses": poses})
    _, r, term, trunc, info = env.step(np.zeros((3, 2)))
    assert term and not trunc and info["left_workspace"] and not info["is_success"]
    assert r < -RewardWeights().leave + 1.0


@settings(max_examples=6, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(5, 60))
def test_shaping_rewards_telescope(seed, n_steps):
    """Without success or leaving, the return is the weighted change of distance, angle
    error and robot gap minus the time cost (a check of every reward term at once)."""
    w = RewardWeights(progress=3.0, rotation=0.7, approach=1.3, time=0.05, behind=0.9)
    env = PushEnv("random-03", reward=w, position_tolerance=1e-3, orientation_tolerance=1e-3)
    _, info0 = env.reset()
    actions = np.random.default_rng(seed).uniform(-1, 1, (n_steps, 3, 2))
    total = 0.0
    for a in actions:
        _, r, _, _, info = env.step(a)
        total += r
    expected = (
        w.progress * (info0["position_error"] - info["position_error"])
        + w.rotation * (info0["orientation_error"] - info["orientation_error"])
        + w.approach * (info0["robot_gap"] - info["robot_gap"])
        + w.behind * (info["robots_behind"] - info0["robots_behind"])
        - w.time * n_steps
    )
    assert total == pytest.approx(expected, abs=1e-9)
    # the behind term against its definition: mean cosine of (robot - object, object - goal)
    core = env.unwrapped.core
    pose, goal = core.object_poses()[0], core.goals[0]
    back = (pose[:2] - goal[:2]) / np.linalg.norm(pose[:2] - goal[:2])
    cos = [np.dot(p - pose[:2], back) / np.linalg.norm(p - pose[:2])
           for p in core.robot_positions()]
    assert info["robots_behind"] == pytest.approx(float(np.mean(cos)), abs=1e-9)


def test_observation_is_in_the_common_frame(open_scene):
    env = PushEnv(open_scene)
    obs, _ = env.reset()
    pose = open_scene.object_starts()[0]
    goal = open_scene.object_goals()[0]
    assert np.allclose(obs["robots"], open_scene.robot_starts_array - pose[:2], atol=1e-6)
    assert np.allclose(obs["goal"], [*(goal[:2] - pose[:2]), 1.0, 0.0], atol=1e-6)
    assert np.allclose(obs["object"], [1.0, 0.0]) and np.allclose(obs["extent"], [0.15, 0.1])


def _reference_patch(scene, robot, cfg, exclude):
    """Free clearance at the patch samples from the closed form (border, circles, objects
    other than ``exclude`` are circles or axis-aligned rectangles at their starts)."""
    half = (cfg.patch_size - 1) // 2
    g = np.arange(-half, half + 1) * cfg.patch_spacing
    xs, ys = robot[0] + g[None, :], robot[1] + g[:, None]
    xs, ys = np.broadcast_arrays(xs, ys)
    W, H = scene.workspace
    d = np.minimum.reduce([xs, ys, W - xs, H - ys])
    for o in scene.obstacles:
        d = np.minimum(d, np.hypot(xs - o.pose[0], ys - o.pose[1]) - o.shape.radius)
    for k, o in enumerate(scene.objects):
        if k == exclude:
            continue
        x, y, _ = o.start
        if hasattr(o.shape, "radius"):
            d = np.minimum(d, np.hypot(xs - x, ys - y) - o.shape.radius)
        else:
            qx = np.abs(xs - x) - o.shape.size[0] / 2
            qy = np.abs(ys - y) - o.shape.size[1] / 2
            out = np.hypot(np.maximum(qx, 0), np.maximum(qy, 0)) + np.minimum(
                np.maximum(qx, qy), 0)
            d = np.minimum(d, out)
    inside = (xs >= 0) & (xs <= W) & (ys >= 0) & (ys <= H)
    return np.where(inside, np.clip((d - scene.robot_radius) / cfg.patch_range, 0, 1), 0.0)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, 2.0), st.floats(0.0, 2.0)), min_size=3, max_size=3))
def test_patch_matches_the_closed_form_clearance(open_scene, robots):
    env = PushEnv(open_scene)
    obs, _ = env.reset(options={"robot_positions": robots})
    cfg = env.core.config
    # the patch reads the nearest 1 cm grid node, whose clearance is exact and within
    # h / sqrt(2) of the sample's (distance is 1-Lipschitz)
    tol = (0.01 / math.sqrt(2) + 1e-6) / cfg.patch_range
    for i, robot in enumerate(robots):
        ref = _reference_patch(open_scene, np.array(robot), cfg, exclude=0)
        err = np.abs(obs["patch"][i] - ref)
        assert err.max() <= tol, (robot, err.max())


def test_velocity_commands_move_robots_at_max_speed(open_scene):
    """In free space a command of norm >= 1 moves the robot at max_speed (diagonal commands
    are scaled to the unit disk), a zero command holds it."""
    env = PushEnv(open_scene, max_speed=0.4)
    env.reset(options={"robot_positions": [[0.4, 0.4], [0.4, 1.6], [1.2, 1.6]]})
    a = np.array([[1.0, 0.0], [1.0, -1.0], [0.0, 0.0]])
    start = env.core.robot_positions().copy()
    for _ in range(40):  # 0.8 s
        env.step(a)
    moved = env.core.robot_positions() - start
    dist = np.hypot(moved[:, 0], moved[:, 1])
    assert dist[0] == pytest.approx(0.32, rel=0.03) and abs(moved[0, 1]) < 1e-3
    assert dist[1] == pytest.approx(0.32, rel=0.03)
    assert dist[2] < 1e-6


def test_render_draws_the_robots(open_scene):
    env = gymnasium.make("lamp/Push-v0", scene=open_scene, render_mode="rgb_array")
    env.reset()
    img = env.render()
    assert img.shape == (200, 200, 3) and img.dtype == np.uint8
    blue = np.all(img == [0x1F, 0x5F, 0xD6], axis=-1)
    for x, y in open_scene.robot_starts:
        row, col = int((2.0 - y) / 0.01), int(x / 0.01)
        assert blue[row, col]
    assert blue.sum() == pytest.approx(3 * math.pi * 5**2, rel=0.2)
    assert PushEnv(open_scene).render() is None
    assert lamp.env.ENV_ID == "lamp/Push-v0"


def test_settings_override_a_config():
    env = PushEnv("random-01", config=PushConfig(frame_skip=5), max_speed=0.3)
    assert env.core.config == PushConfig(frame_skip=5, max_speed=0.3)
    assert env.core.period == pytest.approx(0.01) and env.metadata["render_fps"] == 100


def test_goal_frame_is_the_world_frame_turned_towards_the_goal(open_scene):
    """frame="goal": the goal lies on +x, every vector is the world one turned by -phi, and
    an action a moves the robots as the world-frame action R(phi) a does."""
    world, goal = PushEnv(open_scene), PushEnv(open_scene, frame="goal")
    ow, _ = world.reset()
    og, _ = goal.reset()
    d = open_scene.object_goals()[0, :2] - open_scene.object_starts()[0, :2]
    phi = math.atan2(d[1], d[0])
    c, s = math.cos(phi), math.sin(phi)
    rot = np.array([[c, -s], [s, c]])
    assert np.allclose(og["goal"][:2], [np.hypot(*d), 0.0], atol=1e-6)
    assert np.allclose(og["robots"], ow["robots"] @ rot, atol=1e-6)
    assert np.allclose(og["object"], [math.cos(-phi), math.sin(-phi)], atol=1e-6)
    # the centre sample of each patch is the same point in both frames
    assert np.array_equal(og["patch"][:, 4, 4], ow["patch"][:, 4, 4])
    rng = np.random.default_rng(5)
    for _ in range(30):
        a = rng.uniform(-1, 1, (3, 2))
        a *= 0.99 / np.maximum(np.hypot(a[:, 0], a[:, 1]), 1.0)[:, None]  # no clipping
        angle = goal.core._axes()
        r = np.array([[angle[0], -angle[1]], [angle[1], angle[0]]])
        goal.step(a)
        world.step(a @ r.T)
        assert np.allclose(goal.core.robot_positions(), world.core.robot_positions(), atol=1e-7)
    with pytest.raises(ValueError, match="frame = 'body'"):
        PushEnv(open_scene, frame="body")
