"""Large objects in the proposers: the scale-aware learned model and the geometric proposer.

Objects wider than the training data (``trained_extent``) are proposed for scaled down by
the learned model and mapped back; these tests check the mapping exactly (against the
network run on the scaled object directly), the guarantees of every proposal on bars of
0.2-1.6 m and L/T shapes up to 1.2 m, and that objects that fit are untouched.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lamp.manip import GeometricProposer, load_model
from lamp.manip.contacts import (
    CONTACT_OFFSET,
    MOTION_RANGE,
    ROBOT_RADIUS,
    rigid_displacements,
    rigid_pushes,
    signed_distance,
)
from lamp.manip.dataset import TRAINED_CIRCLE_EXTENT, TRAINED_EXTENT, sample_shape
from lamp.manip.evaluate import l_shape, large_shape, t_shape
from lamp.manip.network import FlowProposer
from lamp.manip.scaling import (
    model_scale,
    scale_motions,
    scale_shape,
    shape_extent,
    trained_extent,
)
from lamp.scene.model import Circle, Rectangle

RING_TOL = 1e-4 + 1e-9  # _finish replaces any contact further than 1e-4 m off the ring


@pytest.fixture(scope="module")
def shipped() -> FlowProposer:
    return load_model()


@pytest.fixture(scope="module")
def unscaled(shipped) -> FlowProposer:
    """The same network with scaling turned off."""
    return FlowProposer(shipped.net, shipped.traj_scale, shipped.sampler, shipped.meta,
                        max_extent=math.inf)


thickness = st.floats(0.08, 0.25)
bars = st.builds(lambda length, w: Rectangle((length, w)), st.floats(0.2, 1.6), thickness)
lts = st.builds(lambda f, w, hf, t: f(w, w * hf, t), st.sampled_from([l_shape, t_shape]),
                st.floats(0.4, 1.2), st.floats(0.6, 1.0), st.floats(0.1, 0.25))
big_shapes = st.one_of(bars, lts)
motions = st.tuples(*(st.floats(-r, r) for r in MOTION_RANGE)).map(np.array)


def _check_guarantees(props, shape, budget, k):
    assert len(props) == k
    for p in props:
        b = p.n_robots
        assert 1 <= b <= budget
        assert p.pushes.shape == (b, 20, 2)
        assert np.all(np.isfinite(p.pushes))
        np.testing.assert_array_equal(p.pushes[:, 0], p.contacts)
        # on the real object's contact ring
        np.testing.assert_allclose(signed_distance(shape, p.contacts), CONTACT_OFFSET,
                                   atol=RING_TOL)
        if b > 1:
            d = np.hypot(*(p.contacts[:, None] - p.contacts[None]).transpose(2, 0, 1))
            assert d[np.triu_indices(b, 1)].min() >= 2 * ROBOT_RADIUS - 1e-9


# --------------------------------------------------------------------------- geometry
def test_trained_extent_bounds_every_training_object():
    """No training object is ever scaled, and the bound of each kind is tight."""
    rng = np.random.default_rng(0)
    shapes = [sample_shape(rng) for _ in range(2000)]
    assert all(model_scale(s) == 1.0 for s in shapes)
    for kind, bound in ((Circle, TRAINED_CIRCLE_EXTENT), (Rectangle, TRAINED_EXTENT)):
        ext = [shape_extent(s) for s in shapes if isinstance(s, kind)]
        assert all(trained_extent(s) == bound for s in shapes if isinstance(s, kind))
        assert bound * 0.97 < max(ext) <= bound


@given(big_shapes, st.floats(0.2, 1.0))
def test_scale_shape_scales_distances(shape, s):
    pts = np.random.default_rng(1).uniform(-1, 1, (20, 2))
    small = scale_shape(shape, s)
    np.testing.assert_allclose(signed_distance(small, s * pts), s * signed_distance(shape, pts),
                               atol=1e-12)
    assert shape_extent(small) == pytest.approx(s * shape_extent(shape))


@given(big_shapes)
def test_shape_extent_is_the_origin_centred_bounding_square(shape):
    from lamp.geometry.shapes import to_shapely

    assert shape_extent(shape) == pytest.approx(2 * max(map(abs, to_shapely(shape).bounds)))
    assert shape_extent(Circle(0.3)) == pytest.approx(0.6)


def test_bad_scaling_arguments_are_refused(shipped):
    with pytest.raises(ValueError, match="max_extent"):
        model_scale(Rectangle((1.0, 0.1)), 0.0)
    with pytest.raises(ValueError, match="scale"):
        scale_shape(Rectangle((1.0, 0.1)), -0.5)
    with pytest.raises(ValueError, match="max_extent"):
        FlowProposer(shipped.net, shipped.traj_scale, max_extent=-1.0)


@given(big_shapes)
def test_model_scale_brings_objects_to_the_trained_extent(shape):
    s = model_scale(shape)
    if shape_extent(shape) <= trained_extent(shape):
        assert s == 1.0
    else:
        assert 0 < s < 1
        assert shape_extent(scale_shape(shape, s)) == pytest.approx(trained_extent(shape))


def test_scale_motions_keeps_the_rotation():
    m = np.array([[0.2, -0.1, 0.4], [0.0, 0.05, -0.5]])
    out = scale_motions(m, 0.5)
    np.testing.assert_array_equal(out, [[0.1, -0.05, 0.4], [0.0, 0.025, -0.5]])
    np.testing.assert_array_equal(m[:, 0], [0.2, 0.0])  # input untouched


# --------------------------------------------------------------------------- learned model
@pytest.mark.parametrize("shape", [Rectangle((0.4, 0.3)), Rectangle((0.5, 0.5)), Circle(0.3),
                                   l_shape(0.5, 0.4, 0.15)], ids=str)
def test_objects_that_fit_are_proposed_exactly_as_without_scaling(shipped, unscaled, shape):
    assert model_scale(shape) == 1.0
    a = shipped.propose(shape, (0.15, -0.05, 0.3), 3, k=8, seed=3)
    b = unscaled.propose(shape, (0.15, -0.05, 0.3), 3, k=8, seed=3)
    for pa, pb in zip(a, b, strict=True):
        np.testing.assert_array_equal(pa.contacts, pb.contacts)
        np.testing.assert_array_equal(pa.pushes, pb.pushes)


@pytest.mark.parametrize("shape", [Rectangle((1.2, 0.1)), Rectangle((0.55, 0.3)),
                                   Circle(0.35)], ids=str)
def test_larger_objects_are_not_proposed_as_before(shipped, unscaled, shape):
    bar = shape
    assert model_scale(shape) < 1
    a = shipped.propose(bar, (0.15, 0.0, 0.3), 3, k=8, seed=3)
    b = unscaled.propose(bar, (0.15, 0.0, 0.3), 3, k=8, seed=3)
    assert any(pa.contacts.shape != pb.contacts.shape or not np.array_equal(pa.contacts, pb.contacts)
               for pa, pb in zip(a, b, strict=True))


@pytest.mark.parametrize("shape", [Rectangle((1.5, 0.12)), l_shape(1.2, 0.9, 0.2),
                                   t_shape(1.1, 0.8, 0.18)], ids=["bar", "L", "T"])
def test_scaled_proposals_are_the_scaled_objects_mapped_back(shipped, unscaled, shape,
                                                             monkeypatch):
    """The network sees exactly the scaled object and motion; its contacts and residuals
    come back divided by s, and the pushes are the real contacts' rigid motion along the
    real motion plus that residual."""
    s = model_scale(shape)
    assert s < 1
    m = np.array([0.18, -0.06, 0.35])
    seen = []
    real_finish = FlowProposer._finish

    def spy(self, shp, contacts, disp, motions, residual=None):
        seen.append((shp, contacts.copy(), disp.copy(), motions.copy()))
        return real_finish(self, shp, contacts, disp, motions, residual)

    monkeypatch.setattr(FlowProposer, "_finish", spy)
    big = shipped.sample(shape, m[None], 3, 16, seed=5)
    small = unscaled.sample(scale_shape(shape, s), scale_motions(m, s)[None], 3, 16, seed=5)
    (shp_b, c_b, d_b, m_b), (shp_s, c_s, d_s, m_s) = seen
    assert shp_b == shape and shp_s == scale_shape(shape, s)
    np.testing.assert_array_equal(c_b, c_s / s)
    np.testing.assert_array_equal(d_b, d_s / s)
    np.testing.assert_array_equal(m_b, np.repeat(m[None], 16, axis=0))

    def residual(raw, motion):
        return raw.pushes - raw.contacts[:, :, None] - rigid_displacements(
            raw.contacts, np.repeat(motion[None], len(raw.contacts), axis=0), 20)

    both = ~np.isnan(big.contacts[..., 0]) & ~np.isnan(small.contacts[..., 0])
    assert both.sum() > 16
    np.testing.assert_allclose(residual(big, m)[both], residual(small, scale_motions(m, s))[both]
                               / s, atol=1e-12)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(big_shapes, motions, st.integers(1, 3), st.integers(0, 2**16))
def test_learned_proposals_on_large_objects_keep_the_guarantees(shipped, shape, m, budget, seed):
    props = shipped.propose(shape, m, budget, k=4, seed=seed)
    _check_guarantees(props, shape, budget, 4)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(big_shapes, st.lists(motions, min_size=2, max_size=3), st.integers(0, 2**16))
def test_batched_proposals_on_large_objects_keep_the_guarantees(shipped, shape, ms, seed):
    batch = shipped.propose_batch(shape, np.stack(ms), 3, k=4, seed=seed)
    assert len(batch) == len(ms)
    for props in batch:
        _check_guarantees(props, shape, 3, 4)


def test_proposals_reach_the_ends_of_a_long_bar(shipped):
    """A 1.5 m bar pushed along its length: some contacts land beyond the 1 m window the
    model sees (|x| > 0.5 m), which the unscaled model cannot place."""
    bar = Rectangle((1.5, 0.12))
    xs = np.concatenate([p.contacts[:, 0] for seed in range(4)
                         for p in shipped.propose(bar, (0.2, 0.0, 0.0), 2, k=16, seed=seed)])
    assert np.max(np.abs(xs)) > 0.5


# --------------------------------------------------------------------------- geometric
@settings(max_examples=30, deadline=None)
@given(big_shapes, motions, st.integers(1, 3), st.integers(0, 2**16))
def test_geometric_proposals_on_large_objects_keep_the_guarantees(shape, m, budget, seed):
    props = GeometricProposer().propose(shape, m, budget, k=6, seed=seed)
    _check_guarantees(props, shape, budget, 6)
    for p in props:  # the rigid motion of the contacts along the requested motion
        np.testing.assert_allclose(p.pushes, rigid_pushes(p.contacts, m), atol=1e-12)


def test_large_shape_draws_the_documented_sizes():
    rng = np.random.default_rng(0)
    shapes = [large_shape(rng) for _ in range(200)]
    bars_ = [s for s in shapes if isinstance(s, Rectangle)]
    others = [s for s in shapes if not isinstance(s, Rectangle)]
    assert 60 < len(bars_) < 140
    assert all(1.0 <= max(b.size) <= 1.5 for b in bars_)
    assert all(0.8 - 1e-9 <= shape_extent(s) <= 1.2 + 1e-9 for s in others)
    assert all(model_scale(s) < 1 for s in shapes)


# --------------------------------------------------------------------------- evaluation
def test_model_eval_reports_the_large_object_set(tmp_path):
    import json

    from typer.testing import CliRunner

    from lamp.cli import app

    out = tmp_path / "eval.json"
    res = CliRunner().invoke(app, ["model", "eval", "--cases", "2", "--proposals", "2",
                                   "--large", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "held-out large objects" in res.output
    large = json.loads(out.read_text())["large_report"]
    assert large["large"] is True
    assert set(large["results"]) == {"flow", "flow-noscale", "geometric"}
    for per_budget in large["results"].values():
        assert set(per_budget) == {"1", "2", "3"}
        for st_ in per_budget.values():
            assert st_["pushes"] == 4
            assert 0.0 <= st_["within_0.05m_0.1rad"] <= st_["within_0.1m_0.2rad"] <= 1.0
            assert st_["contact_validity"] == 1.0
            assert st_["median_propose_ms"] > 0


def test_displacement_checkpoints_are_mapped_back_as_residuals(monkeypatch):
    """A network that generates raw displacements (older checkpoints): the scaled path turns
    them into residuals from the scaled rigid motion before mapping them back."""
    import torch

    from lamp.manip.contacts import project_to_contacts
    from lamp.manip.network import FlowNet, NetConfig

    torch.manual_seed(0)
    cfg = NetConfig(image_size=32, channels=(4, 8), image_dim=16, token_dim=8, traj_dim=32,
                    cond_dim=16, time_dim=16, hidden=64, blocks=1, trajectory="displacement")
    net = FlowNet(cfg)
    model = FlowProposer(net, traj_scale=0.07)
    ref = FlowProposer(net, traj_scale=0.07, max_extent=math.inf)
    bar, m = Rectangle((1.4, 0.2)), np.array([0.15, 0.05, -0.3])
    s = model_scale(bar)
    _check_guarantees(model.propose(bar, m, 3, k=8, seed=2), bar, 3, 8)
    seen = []
    real_finish = FlowProposer._finish

    def spy(self, shp, contacts, disp, motions, residual=None):
        seen.append(contacts.copy())
        return real_finish(self, shp, contacts, disp, motions, residual)

    monkeypatch.setattr(FlowProposer, "_finish", spy)
    big = model.sample(bar, m[None], 3, 8, seed=4)
    small_shape, m_s = scale_shape(bar, s), scale_motions(m, s)
    small = ref.sample(small_shape, m_s[None], 3, 8, seed=4)
    cells = seen[1]
    reps = np.repeat(m[None], 8, axis=0), np.repeat(m_s[None], 8, axis=0)
    res_big = big.pushes - big.contacts[:, :, None] - rigid_displacements(big.contacts, reps[0])
    res_small = small.pushes - small.contacts[:, :, None] - rigid_displacements(small.contacts,
                                                                                reps[1])
    unmoved = ~np.isnan(big.contacts[..., 0]) & ~np.isnan(small.contacts[..., 0])
    unmoved &= np.all(np.isclose(project_to_contacts(small_shape, np.nan_to_num(cells)),
                                 small.contacts, atol=1e-12), axis=-1)
    assert unmoved.sum() >= 8
    np.testing.assert_allclose(res_big[unmoved], res_small[unmoved] / s, atol=1e-12)


def test_geometric_strategies_join_in_beyond_the_training_data(shipped):
    """A 1.5 m bar: of k proposals the last k // 2 are the geometric proposer's; an object
    the model was trained on gets only the network's."""
    bar = Rectangle((1.5, 0.12))
    props = shipped.propose(bar, (0.1, 0.0, 0.2), 3, k=6, seed=0)
    assert len(props) == 6
    assert [p.source == "flow" for p in props] == [True] * 3 + [False] * 3
    small = shipped.propose(Rectangle((0.4, 0.3)), (0.1, 0.0, 0.2), 3, k=6, seed=0)
    assert all(p.source == "flow" for p in small)
