"""Discrete + continuous flow matching for contact formations (our own equations).

Two coupled probability paths share one time t in [0, 1] (GCo's discrete-continuous
flow, GCo_DC, the manipulation model the LAMP paper uses):

* **Contacts** are discrete. Each robot slot has two tokens (the x and the y cell of an
  object-centred grid of ``N_BINS`` cells over ``GRID_EXTENT`` metres) or the pair
  ``(NONE, NONE)`` for an unused slot (a MASK token for unused slots, as in GCo).
  The path is the *masked mixture*
  ``p_t(x | x1) = kappa(t) delta_{x1}(x) + (1 - kappa(t)) delta_{NOISE}(x)`` per token with
  ``kappa(t) = t^2``: a token shows its clean value with probability kappa(t) and the
  absorbing ``NOISE`` state otherwise. The network predicts p(x1 | x_t) (logits over the
  ``N_BINS + 1`` clean values) and is trained with cross-entropy on the noised tokens. The
  sampler's probability velocity moves a NOISE token to a clean value at rate
  ``kappa'(t) / (1 - kappa(t)) = 2t / (1 - t^2)``; over a step [t, t + h] we use the exact
  jump probability of that rate, ``(kappa(t + h) - kappa(t)) / (1 - kappa(t))``, which is 1
  on the last step, so every token is clean at t = 1.
* **Push trajectories** are continuous: per slot the H - 1 displacements of waypoints
  1..H-1 from the contact (waypoint 0 is the contact itself), divided by a data scale.
  The path is the straight Gaussian-to-data line ``x_t = (1 - t) x0 + t x1``,
  ``x0 ~ N(0, I)``; the network predicts the velocity ``x1 - x0`` (MSE on used slots).
  Sampling is Euler with a *smoothness guidance* term: the gradient of
  ``S(x) = sum_h |x_{h+1} - 2 x_h + x_{h-1}|^2`` (with the fixed zero displacement at h = 0)
  evaluated at the predicted endpoint ``x1_hat = x_t + (1 - t) v`` is subtracted from v.

Slots are stored in a canonical order: used slots first, sorted by the angle of the
contact around the object measured from the direction opposite to the motion (the "behind"
direction). Budget b forces slots b..2 to NONE, so the budget is always respected.
"""

from __future__ import annotations

import math

import numpy as np
import torch
import torch.nn.functional as F

N_BINS = 128
"""Grid cells per axis for contact tokens."""
GRID_EXTENT = 1.0
"""Side of the contact grid (m), centred on the object (7.8 mm cells)."""
NONE = N_BINS
"""Clean token value meaning 'no robot in this slot'."""
NOISE = N_BINS + 1
"""Absorbing state of the masked path (a token not generated yet)."""
N_CLASSES = N_BINS + 1
"""Clean values the network predicts (cells + NONE)."""
N_INPUT_TOKENS = N_BINS + 2
"""Values a noisy token can take (cells + NONE + NOISE)."""


# --------------------------------------------------------------------------- tokens
def tokenize(contacts: np.ndarray) -> np.ndarray:
    """(..., S, 2) contacts (NaN rows = unused) -> (..., 2 S) int64 tokens."""
    c = np.asarray(contacts, dtype=float)
    cell = np.floor((c + 0.5 * GRID_EXTENT) * (N_BINS / GRID_EXTENT))
    cell = np.clip(np.nan_to_num(cell, nan=0.0), 0, N_BINS - 1).astype(np.int64)
    unused = np.isnan(c).any(axis=-1, keepdims=True)
    cell = np.where(unused, NONE, cell)
    return cell.reshape(*c.shape[:-2], -1)


def detokenize(tokens: np.ndarray) -> np.ndarray:
    """(..., 2 S) tokens -> (..., S, 2) cell-centre contacts; NaN where a coordinate is not a
    cell (NONE or NOISE), i.e. the slot is unused."""
    t = np.asarray(tokens).reshape(*np.shape(tokens)[:-1], -1, 2)
    xy = (t + 0.5) * (GRID_EXTENT / N_BINS) - 0.5 * GRID_EXTENT
    bad = (t >= N_BINS).any(axis=-1, keepdims=True)
    return np.where(bad, np.nan, xy)


def canonical_order(contacts: np.ndarray, motion: np.ndarray) -> np.ndarray:
    """Slot permutation (..., S): used slots first, by angle from the 'behind' direction.

    ``contacts`` (..., S, 2) with NaN rows for unused slots; ``motion`` (..., 3). For
    (near) pure rotations the reference direction is the object's -x axis.
    """
    c = np.asarray(contacts, dtype=float)
    m = np.asarray(motion, dtype=float)
    trans = np.hypot(m[..., 0], m[..., 1])
    ref = np.where(trans > 0.02, np.arctan2(-m[..., 1], -m[..., 0]), np.pi)
    ang = np.arctan2(c[..., 1], c[..., 0]) - ref[..., None]
    ang = (ang + np.pi) % (2 * np.pi) - np.pi
    key = np.where(np.isnan(ang), 10.0, ang)
    return np.argsort(key, axis=-1, kind="stable")


# --------------------------------------------------------------------------- paths
def kappa(t: torch.Tensor) -> torch.Tensor:
    """Scheduler of the masked mixture path, kappa(t) = t^2."""
    return t * t


def noise_tokens(x1: torch.Tensor, t: torch.Tensor, gen: torch.Generator | None) -> torch.Tensor:
    """Sample x_t ~ p_t(. | x1): keep each token with probability kappa(t), else NOISE.

    Tokens that are forced by the budget (NONE beyond the budget) are known to the sampler
    from the start, so they are never noised here either.
    """
    keep = torch.rand(x1.shape, generator=gen, device=x1.device) < kappa(t)[:, None]
    keep = keep | (x1 == NONE)
    return torch.where(keep, x1, torch.full_like(x1, NOISE))


def noise_trajectory(
    x1: torch.Tensor, t: torch.Tensor, gen: torch.Generator | None
) -> tuple[torch.Tensor, torch.Tensor]:
    """x_t = (1 - t) x0 + t x1 and the target velocity x1 - x0, x0 ~ N(0, I)."""
    x0 = torch.randn(x1.shape, generator=gen, device=x1.device, dtype=x1.dtype)
    tt = t.view(-1, *([1] * (x1.dim() - 1)))
    return (1 - tt) * x0 + tt * x1, x1 - x0


def flow_losses(
    logits: torch.Tensor,
    velocity: torch.Tensor,
    x1_tokens: torch.Tensor,
    xt_tokens: torch.Tensor,
    target_velocity: torch.Tensor,
    slot_used: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:
    """(token cross-entropy, trajectory MSE) of one batch.

    logits (B, 2S, N_CLASSES); velocity and target_velocity (B, S, H-1, 2); tokens (B, 2S);
    slot_used (B, S) bool. The cross-entropy is averaged over noised tokens (the others are
    known); the MSE over the waypoints of used slots.
    """
    noised = xt_tokens == NOISE
    ce = F.cross_entropy(logits.reshape(-1, logits.shape[-1]), x1_tokens.reshape(-1),
                         reduction="none").view_as(x1_tokens)
    ce = (ce * noised).sum() / noised.sum().clamp(min=1)
    w = slot_used[:, :, None, None].to(velocity.dtype)
    se = ((velocity - target_velocity) ** 2 * w).sum()
    mse = se / (w.sum() * velocity.shape[-2] * velocity.shape[-1]).clamp(min=1)
    return ce, mse


# --------------------------------------------------------------------------- sampling
def smoothness_grad(x: torch.Tensor) -> torch.Tensor:
    """Gradient of S(x) = sum_h |x_{h+1} - 2 x_h + x_{h-1}|^2 over waypoints (dim -2), where
    the displacement sequence is prefixed by the fixed zero of waypoint 0."""
    z = torch.cat([torch.zeros_like(x[..., :1, :]), x], dim=-2)
    d2 = z[..., 2:, :] - 2 * z[..., 1:-1, :] + z[..., :-2, :]  # (.., H-2, 2)
    g = torch.zeros_like(z)
    g[..., 2:, :] += 2 * d2
    g[..., 1:-1, :] -= 4 * d2
    g[..., :-2, :] += 2 * d2
    return g[..., 1:, :]


def jump_probability(t: float, h: float) -> float:
    """P(NOISE -> clean) over [t, t + h] under rate kappa'/(1 - kappa): exact for the path."""
    k0, k1 = t * t, min(1.0, (t + h) ** 2)
    return 1.0 if k0 >= 1.0 else (k1 - k0) / (1.0 - k0)


def time_embedding(t: torch.Tensor, dim: int) -> torch.Tensor:
    """Sinusoidal features of t in [0, 1] (B,) -> (B, dim)."""
    half = dim // 2
    freq = torch.exp(-math.log(1000.0) * torch.arange(half, device=t.device) / max(half - 1, 1))
    a = t[:, None] * 1000.0 * freq[None] / 10.0
    return torch.cat([torch.sin(a), torch.cos(a)], dim=-1)
