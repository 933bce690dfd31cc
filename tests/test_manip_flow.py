"""Flow-matching building blocks: tokens, slot order, paths, guidance, images, batches."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from lamp.manip.contacts import rigid_displacements, rigid_pushes
from lamp.manip.dataset import synthetic_dataset
from lamp.manip.flow import (
    GRID_EXTENT,
    N_BINS,
    NOISE,
    NONE,
    canonical_order,
    detokenize,
    flow_losses,
    jump_probability,
    noise_tokens,
    noise_trajectory,
    smoothness_grad,
    tokenize,
)
from lamp.manip.image import batch_images, object_image
from lamp.manip.train import make_batch, trajectory_scale
from lamp.scene.model import Circle, Polygon, Rectangle

coord = st.floats(-0.49, 0.49)


@settings(max_examples=50, deadline=None)
@given(pts=st.lists(st.tuples(coord, coord), min_size=3, max_size=3), unused=st.integers(0, 3))
def test_tokens_round_trip_within_half_a_cell(pts, unused):
    c = np.array(pts)
    c[3 - unused:] = np.nan
    tok = tokenize(c)
    assert tok.shape == (6,)
    assert np.all(tok[2 * (3 - unused):] == NONE)
    back = detokenize(tok)
    used = slice(0, 3 - unused)
    np.testing.assert_array_less(np.abs(back[used] - c[used]), 0.5 * GRID_EXTENT / N_BINS + 1e-12)
    assert np.all(np.isnan(back[3 - unused:]))


def test_canonical_order_starts_behind_and_puts_unused_last():
    # motion +x: 'behind' is -x; angles measured from there, counter-clockwise
    c = np.array([[0.0, 0.3], [np.nan, np.nan], [-0.3, 0.0], [0.0, -0.3]])
    order = canonical_order(c, np.array([0.2, 0.0, 0.0]))
    # angles from -x: (0, 0.3) -> -90 deg, (-0.3, 0) -> 0, (0, -0.3) -> +90 deg
    np.testing.assert_array_equal(order, [0, 2, 3, 1])


def test_masked_path_marginal_is_kappa():
    gen = torch.Generator().manual_seed(0)
    x1 = torch.randint(0, N_BINS, (20000, 6), generator=gen)
    for t in (0.0, 0.3, 0.7, 1.0):
        xt = noise_tokens(x1, torch.full((20000,), t), gen)
        kept = (xt == x1).float().mean().item()
        assert kept == pytest.approx(t * t, abs=0.01)
        assert torch.all((xt == x1) | (xt == NOISE))
    # NONE tokens are known to the sampler (the budget fixes them): never noised
    x1[:, 4:] = NONE
    xt = noise_tokens(x1, torch.zeros(20000), gen)
    assert torch.all(xt[:, 4:] == NONE)


def test_jump_probabilities_reproduce_kappa():
    # simulate the sampler's jumps on many tokens: the share unmasked at t must be t^2
    rng = np.random.default_rng(0)
    n, steps = 200_000, 10
    masked = np.ones(n, dtype=bool)
    for i in range(steps):
        t = i / steps
        masked &= ~(rng.random(n) < jump_probability(t, 1 / steps))
        assert 1 - masked.mean() == pytest.approx(((i + 1) / steps) ** 2, abs=0.005)
    assert not masked.any()


def test_straight_path_and_velocity():
    gen = torch.Generator().manual_seed(0)
    x1 = torch.randn(5, 3, 19, 2, generator=gen)
    t = torch.tensor([0.0, 0.25, 0.5, 0.75, 1.0])
    xt, v = noise_trajectory(x1, t, gen)
    x0 = x1 - v
    tt = t.view(-1, 1, 1, 1)
    torch.testing.assert_close(xt, (1 - tt) * x0 + tt * x1)
    torch.testing.assert_close(xt[-1], x1[-1])


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 1000))
def test_smoothness_gradient_matches_autograd(seed):
    x = torch.randn(2, 3, 19, 2, generator=torch.Generator().manual_seed(seed),
                    dtype=torch.float64, requires_grad=True)
    z = torch.cat([torch.zeros_like(x[..., :1, :]), x], dim=-2)
    s = ((z[..., 2:, :] - 2 * z[..., 1:-1, :] + z[..., :-2, :]) ** 2).sum()
    (g,) = torch.autograd.grad(s, x)
    torch.testing.assert_close(smoothness_grad(x.detach()), g)


def test_flow_losses_ignore_known_tokens_and_unused_slots():
    logits = torch.zeros(1, 6, N_BINS + 1)
    x1 = torch.tensor([[5, 6, 7, 8, NONE, NONE]])
    xt = torch.tensor([[NOISE, 6, 7, 8, NONE, NONE]])  # only the first token is noised
    v = torch.zeros(1, 3, 19, 2)
    target = torch.zeros(1, 3, 19, 2)
    target[:, 2] = 100.0  # an unused slot: must not count
    used = torch.tensor([[True, True, False]])
    ce, mse = flow_losses(logits, v, x1, xt, target, used)
    assert ce.item() == pytest.approx(np.log(N_BINS + 1), rel=1e-6)
    assert mse.item() == 0.0


@pytest.mark.parametrize("shape", [Circle(0.2), Rectangle((0.4, 0.3)), Rectangle((0.15, 0.5))])
def test_batch_images_match_object_image(shape):
    kind = 0 if isinstance(shape, Circle) else 1
    params = [shape.radius] * 2 if kind == 0 else list(shape.size)
    img = batch_images(np.array([kind]), np.array([params]))[0]
    np.testing.assert_allclose(img, object_image(shape), atol=1e-6)
    # area of the mask ~ area of the shape
    area = img.sum() * (1.0 / 64) ** 2
    ref = np.pi * shape.radius**2 if kind == 0 else shape.size[0] * shape.size[1]
    assert area == pytest.approx(ref, rel=0.03)


def test_object_image_axes_and_polygons():
    img = object_image(Rectangle((0.5, 0.1)))  # wide along x: many columns, few rows
    rows, cols = np.nonzero(img > 0.5)
    assert np.ptp(cols) > 3 * np.ptp(rows)
    tri = object_image(Polygon(((0.0, 0.3), (-0.2, -0.1), (0.2, -0.1))))
    assert tri[:, :].sum() * (1 / 64) ** 2 == pytest.approx(0.5 * 0.4 * 0.4, rel=0.05)
    # row i is at y = -0.5 + (i + 0.5) / 64: the apex (y = 0.3) side is at high rows
    assert tri[45, 32] == 1.0 and tri[10, 32] == 0.0 and tri[60, 32] == 0.0


def test_make_batch_symmetries_preserve_geometry():
    ds = synthetic_dataset(40, seed=1)
    scale = trajectory_scale(ds, residual=False)
    idx = np.arange(40)
    plain = make_batch(ds, idx, scale, None, 64, residual=False)
    aug = make_batch(ds, idx, scale, np.random.default_rng(0), 64, residual=False)
    # symmetries keep lengths: |motion_xy|, |dtheta|, each slot's displacement norms, areas
    np.testing.assert_allclose(np.linalg.norm(aug.motion[:, :2], axis=1),
                               np.linalg.norm(plain.motion[:, :2], axis=1), rtol=1e-5)
    np.testing.assert_allclose(aug.motion[:, 2].abs(), plain.motion[:, 2].abs(), rtol=1e-5)
    np.testing.assert_allclose(aug.images.sum(dim=(1, 2)), plain.images.sum(dim=(1, 2)),
                               rtol=1e-5)
    np.testing.assert_array_equal(aug.used.sum(1), plain.used.sum(1))
    assert torch.all(plain.used.sum(1) == plain.budget)
    # used slots first
    assert torch.all(plain.used[:, :-1] >= plain.used[:, 1:])
    # displacements of an augmented sample are still a rigid motion of its contacts:
    # the final displacement d = R(dtheta) c - c + t for the transformed contact/motion
    c = detokenize(aug.tokens.numpy())
    m = aug.motion.numpy() * np.array([0.2, 0.2, 0.5])
    d = aug.traj.numpy()[:, :, -1] * scale
    th = m[:, 2:3]
    ex = np.cos(th) * c[..., 0] - np.sin(th) * c[..., 1] - c[..., 0] + m[:, 0:1]
    ey = np.sin(th) * c[..., 0] + np.cos(th) * c[..., 1] - c[..., 1] + m[:, 1:2]
    used = aug.used.numpy()
    # tokens are cell centres: allow the cell error times the rotation
    np.testing.assert_allclose(d[..., 0][used], ex[used], atol=0.004)
    np.testing.assert_allclose(d[..., 1][used], ey[used], atol=0.004)


def test_residual_encoding_of_rigid_pushes_is_zero_under_symmetries():
    # synthetic labels are exact rigid pushes: their residual is 0 for every D4 symmetry
    ds = synthetic_dataset(30, seed=2)
    b = make_batch(ds, np.arange(30), 0.01, np.random.default_rng(1), 64, residual=True)
    assert float(b.traj.abs().max()) < 1e-5
    assert float(b.traj[b.used].abs().max()) < 1e-5


@settings(max_examples=30, deadline=None)
@given(pts=st.lists(st.tuples(coord, coord), min_size=1, max_size=3),
       motion=st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-0.5, 0.5)))
def test_rigid_displacements_match_rigid_pushes(pts, motion):
    c = np.array(pts)
    ref = rigid_pushes(c, motion) - c[:, None, :]
    np.testing.assert_allclose(rigid_displacements(c, np.array(motion)), ref, atol=1e-12)
