"""The learned proposer: a small CNN + MLP flow-matching network and its sampler.

Architecture (GCo_DC-like, sized for CPUs): a CNN encodes the object mask (64 x 64, see
``lamp.manip.image``) into a vector; embeddings of the noisy contact tokens, the noisy
trajectory, the requested motion, the budget and the flow time are concatenated with it
and fed through a residual MLP trunk with two heads: token logits (clean-token posterior)
and trajectory velocity. See ``lamp.manip.flow`` for the paths and losses; the network
itself (``FlowNet``, ``NetConfig``) is ``lamp.manip.flow_net``, re-exported here.

``FlowProposer.propose`` draws K candidates in one batched pass per step (10 Euler steps),
caching the image embedding per shape, under ``torch.inference_mode``. Contacts come out as
grid cells; they are snapped onto the contact ring (robot radius + 5 mm outside the object)
a robot that would overlap an earlier one slides along the ring to the nearest free spot
within ``REPAIR_SHIFT`` or, failing that, is dropped (so b may be < budget, never 0).
Objects larger than the training data (``lamp.manip.scaling.trained_extent``) are
proposed for scaled down and mapped back (``FlowProposer.sample``, ``lamp.manip.scaling``).
"""

from __future__ import annotations

import json
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from numpy.typing import ArrayLike

from lamp.manip.contact_ring import contact_ring
from lamp.manip.contacts import (
    CONTACT_OFFSET,
    HORIZON,
    MOTION_RANGE,
    ROBOT_RADIUS,
    as_shape,
    check_budget,
    check_motion,
    project_to_contacts,
    rigid_displacements,
    signed_distance,
)
from lamp.manip.flow import (
    NOISE,
    NONE,
    detokenize,
    jump_probability,
    smoothness_grad,
)
from lamp.manip.flow_net import FlowNet, NetConfig
from lamp.manip.geometric import GeometricProposer, wrench_residual
from lamp.manip.image import object_image
from lamp.manip.proposals import Proposal, ShapeLike, check_k, make_rng
from lamp.manip.scaling import model_scale, scale_motions, scale_shape
from lamp.scene.model import Shape

MOTION_SCALE = MOTION_RANGE
"""Requested motions are divided by these before entering the network (training range)."""
DEFAULT_CHECKPOINT = Path(__file__).parent / "checkpoints" / "flow_dc.pt"
REPAIR_SHIFT = 0.15
"""How far (m) a contact that overlaps another robot may slide along the ring to a free spot."""
REPAIR_MARGIN = 0.005
"""Clearance (m) beyond 2r kept between a repaired robot and the others."""
@dataclass
class SamplerConfig:
    """Sampling settings.

    steps: Euler steps; guidance: smoothness guidance weight; temperature: of the token
    posteriors (< 1 sharpens them); rank: return the candidates ordered by the quasi-static
    wrench check of ``lamp.manip.geometric.wrench_residual`` (best first; the planners try
    candidates in order); oversample: draw ``ceil(k * oversample)`` candidates in the same
    batch and keep the ``k`` best-ranked (1 = no extra samples, only ordering).
    """

    steps: int = 10
    guidance: float = 0.05
    temperature: float = 1.0
    rank: bool = True
    oversample: float = 1.0


@dataclass
class RawSamples:
    """Batched sampler output before conversion to ``Proposal`` objects (numpy, object
    frame): contacts (B, S, 2) with NaN rows for dropped slots, pushes (B, S, H, 2)."""

    contacts: np.ndarray
    pushes: np.ndarray


class FlowProposer:
    """The trained discrete-continuous flow-matching proposer (``ProposalModel``).

    ``max_extent``: objects wider than this (``lamp.manip.scaling.shape_extent``) are
    proposed for scaled down to it (see ``sample``); default (None): the training data's
    bound for the object's kind (``trained_extent``); ``math.inf`` turns scaling off.
    For such a scaled object the last ``k // 2`` of the ``k`` proposals are the
    ``GeometricProposer``'s instead of the network's lowest-ranked ones (``mix_geometric``;
    on large objects the geometric strategies are the more accurate, see the README's
    large-object table).
    """

    #: Add geometric proposals for objects beyond the training data (see the class doc).
    mix_geometric: bool = True

    horizon: int = HORIZON

    def __init__(
        self,
        net: FlowNet,
        traj_scale: float,
        sampler: SamplerConfig | None = None,
        meta: dict[str, Any] | None = None,
        cache_size: int = 256,
        max_extent: float | None = None,
    ) -> None:
        if max_extent is not None and not max_extent > 0:
            raise ValueError(f"max_extent must be > 0 or None, got {max_extent!r}")
        self.max_extent = None if max_extent is None else float(max_extent)
        self.net = net.eval()
        self.traj_scale = float(traj_scale)
        self.sampler = sampler or SamplerConfig()
        self.meta = meta or {}
        #: Radius of the robots the training pushes were simulated with: contacts sit
        #: ``robot_radius + CONTACT_GAP`` off the object. Checkpoints written before it was
        #: recorded were all trained with ``ROBOT_RADIUS``.
        self.robot_radius = float(self.meta.get("data_meta", {}).get("robot_radius", ROBOT_RADIUS))
        self._cache: OrderedDict[Any, torch.Tensor] = OrderedDict()
        self._cache_size = cache_size
        self.horizon = net.cfg.horizon

    # ------------------------------------------------------------------ image cache
    def image_embedding(self, shape: Shape) -> torch.Tensor:
        """(1, image_dim) embedding of the shape's mask, cached per shape."""
        try:
            key: Any = shape
            hash(key)
        except TypeError:
            key = json.dumps(shape.to_dict(), sort_keys=True)
        emb = self._cache.get(key)
        if emb is None:
            img = torch.from_numpy(np.array(object_image(shape, self.net.cfg.image_size)))
            with torch.inference_mode():
                emb = self.net.encode_image(img[None])
            self._cache[key] = emb
            if len(self._cache) > self._cache_size:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(key)
        return emb

    # ------------------------------------------------------------------ sampling
    def sample(
        self,
        shape: ShapeLike,
        motions: ArrayLike,
        budget: int,
        k: int,
        seed: int | np.random.Generator | None = None,
    ) -> RawSamples:
        """k candidates for each of M motions (M, 3): arrays of M * k rows, motion-major.

        Objects that fit (``model_scale(shape, max_extent) == 1``) go through the network
        as they are. A larger object is proposed for scaled down by ``s = model_scale``
        about its origin, with the motions' translations scaled by ``s`` (rotations as
        they are); the generated contacts and the generated residual pushes (the
        deviation from carrying the contact rigidly with the object) are divided by ``s``
        and handed to ``_finish`` with the real shape and the real motions. So in both
        cases every used contact lies on the real object's contact ring (snapped as
        ``_finish`` does, overlapping robots repaired or dropped), ``pushes[:, :, 0]`` are
        the contacts, and the pushes are in the real object's frame: the rigid motion of
        the real contacts along the real requested motion plus the residual.
        """
        shp = as_shape(shape)
        b = check_budget(budget)
        k = check_k(k)
        m = np.asarray(motions, dtype=float).reshape(-1, 3)
        for row in m:
            check_motion(row)
        rng = make_rng(seed)
        gen = torch.Generator().manual_seed(int(rng.integers(0, 2**63 - 1)))
        scale = model_scale(shp, self.max_extent)
        net_shape, net_m = (shp, m) if scale == 1.0 else (scale_shape(shp, scale),
                                                          scale_motions(m, scale))
        cfg = self.net.cfg
        n = len(m) * k
        s = cfg.slots
        used = torch.arange(s) < b  # (S,)
        tok_used = used.repeat_interleave(2)  # (2S,)
        with torch.inference_mode():
            emb = self.image_embedding(net_shape).expand(n, -1)
            motion = torch.from_numpy(np.repeat(net_m / np.array(MOTION_SCALE), k,
                                                axis=0)).float()
            bud = torch.full((n,), b, dtype=torch.long)
            tokens = torch.full((n, 2 * s), NOISE, dtype=torch.long)
            tokens[:, ~tok_used] = NONE
            x = torch.randn((n, s, cfg.horizon - 1, 2), generator=gen)
            x[:, ~used] = 0.0
            steps = self.sampler.steps
            h = 1.0 / steps
            for i in range(steps):
                t = i * h
                logits, v = self.net(emb, tokens, x, motion, bud, torch.full((n,), t))
                # continuous: Euler step with smoothness guidance at the predicted endpoint
                if self.sampler.guidance > 0:
                    v = v - self.sampler.guidance * smoothness_grad(x + (1 - t) * v)
                x = x + h * v
                x[:, ~used] = 0.0
                # discrete: NOISE tokens jump to a clean value (never NONE inside the budget)
                p = jump_probability(t, h)
                jump = (tokens == NOISE) & (torch.rand(tokens.shape, generator=gen) < p)
                if jump.any():
                    lg = logits / self.sampler.temperature
                    lg[..., NONE] = float("-inf")
                    u = torch.rand(lg.shape, generator=gen).clamp_(1e-12, 1.0)
                    draw = torch.argmax(lg - torch.log(-torch.log(u)), dim=-1)
                    tokens = torch.where(jump, draw, tokens)
        contacts = detokenize(tokens.numpy())  # (n, S, 2), NaN beyond the budget
        disp = x.numpy().astype(float) * self.traj_scale
        if scale == 1.0:
            return self._finish(shp, contacts, disp, np.repeat(m, k, axis=0))
        if not cfg.residual:  # the generated part as a residual from the scaled rigid motion
            rigid = rigid_displacements(project_to_contacts(net_shape, np.nan_to_num(contacts)),
                                        np.repeat(net_m, k, axis=0), cfg.horizon)
            disp = disp - rigid[:, :, 1:]
        return self._finish(shp, contacts / scale, disp / scale, np.repeat(m, k, axis=0),
                            residual=True)

    def _finish(
        self, shape: Shape, contacts: np.ndarray, disp: np.ndarray, motions: np.ndarray,
        residual: bool | None = None,
    ) -> RawSamples:
        """Snap contacts onto the contact ring, build pushes, drop overlapping robots.

        contacts (n, S, 2) cell centres (NaN: unused), disp (n, S, H-1, 2) the generated
        continuous part in metres, motions (n, 3) the requested motions; ``residual``: disp
        is a residual from the rigid motion of the contacts (default: as the network's
        configuration says).
        """
        n, s, _ = contacts.shape
        used = ~np.isnan(contacts[..., 0])
        snapped = contacts.copy()
        if used.any():
            snapped[used] = project_to_contacts(shape, contacts[used])
            # near a concave corner the projection can land too close to another edge:
            # take the nearest sample of the (valid by construction) contact ring instead
            bad = used & (signed_distance(shape, np.nan_to_num(snapped)) < CONTACT_OFFSET - 1e-4)
            if bad.any():
                ring = contact_ring(shape).points
                d2 = ((snapped[bad][:, None, :] - ring[None]) ** 2).sum(-1)
                snapped[bad] = ring[np.argmin(d2, axis=1)]
        # a robot overlapping an earlier robot of the same candidate slides along the ring
        # to the nearest free spot (at most REPAIR_SHIFT away), else it is dropped
        ring: np.ndarray | None = None
        for j in range(1, s):
            d = np.stack([np.hypot(*(snapped[:, j] - snapped[:, i]).T) for i in range(j)], 1)
            clash = used[:, j] & np.any(used[:, :j] & (d < 2.0 * ROBOT_RADIUS), axis=1)
            for r in np.flatnonzero(clash):
                if ring is None:
                    ring = contact_ring(shape).points
                others = snapped[r, :j][used[r, :j]]
                free = np.all(np.hypot(*(ring[:, None, :] - others[None]).transpose(2, 0, 1))
                              >= 2.0 * ROBOT_RADIUS + REPAIR_MARGIN, axis=1)
                dist = np.where(free, np.hypot(*(ring - snapped[r, j]).T), np.inf)
                best = int(np.argmin(dist))
                if dist[best] <= REPAIR_SHIFT:
                    snapped[r, j] = ring[best]
                else:
                    used[r, j] = False
        snapped[~used] = np.nan
        pushes = np.concatenate([np.zeros((n, s, 1, 2)), disp], axis=2) + snapped[:, :, None, :]
        if self.net.cfg.residual if residual is None else residual:
            pushes = pushes + rigid_displacements(snapped, motions, pushes.shape[2])
        return RawSamples(snapped, pushes)

    @staticmethod
    def _to_proposals(raw: RawSamples, rows: range | np.ndarray) -> list[Proposal]:
        out = []
        for r in rows:
            keep = ~np.isnan(raw.contacts[r, :, 0])
            out.append(Proposal(raw.contacts[r, keep].copy(), raw.pushes[r, keep].copy(), "flow"))
        return out

    def propose(
        self,
        shape: ShapeLike,
        motion: ArrayLike,
        budget: int,
        k: int = 16,
        seed: int | np.random.Generator | None = None,
    ) -> list[Proposal]:
        """``k`` sampled proposals for moving ``shape`` by ``motion`` (object frame)."""
        m = check_motion(motion)
        return self.propose_batch(shape, m[None], budget, k, seed)[0]

    def propose_batch(
        self,
        shape: ShapeLike,
        motions: Sequence[ArrayLike] | np.ndarray,
        budget: int,
        k: int = 16,
        seed: int | np.random.Generator | None = None,
    ) -> list[list[Proposal]]:
        """``k`` proposals for each of several motions, all sampled in one batched pass."""
        shp = as_shape(shape)
        k = check_k(k)
        m = np.asarray(motions, dtype=float).reshape(-1, 3)
        draw = max(k, int(np.ceil(k * self.sampler.oversample))) if self.sampler.rank else k
        rng = make_rng(seed)
        raw = self.sample(shp, m, budget, draw, rng)
        out = []
        for i in range(len(m)):
            rows = np.arange(i * draw, (i + 1) * draw)
            if self.sampler.rank:
                rows = rows[self._rank(shp, raw.contacts[rows], m[i])[:k]]
            out.append(self._to_proposals(raw, rows))
        if self.mix_geometric and model_scale(shp, self.max_extent) < 1.0:
            # beyond the training data the network is out of its depth (a scaled-down
            # bar is thinner than a robot): the hand-made strategies join in
            g = k // 2
            if g:
                extra = GeometricProposer().propose_batch(shp, m, budget, g, rng)
                out = [a[: k - g] + b for a, b in zip(out, extra, strict=True)]
        return out

    @staticmethod
    def _rank(shape: Shape, contacts: np.ndarray, motion: np.ndarray) -> np.ndarray:
        """Order of candidates (n, S, 2) by wrench residual, best first (stable)."""
        used = ~np.isnan(contacts[..., 0])
        count = used.sum(axis=1)
        res = np.empty(len(contacts))
        for c in np.unique(count):
            rows = np.flatnonzero(count == c)
            cs = np.stack([contacts[r][used[r]] for r in rows])
            res[rows] = wrench_residual(shape, cs, motion)
        return np.argsort(res, kind="stable")


# --------------------------------------------------------------------------- checkpoints
@dataclass
class Checkpoint:
    """What a shipped checkpoint holds (all plain types, loadable with weights_only=True)."""

    config: dict[str, Any]
    state_dict: dict[str, torch.Tensor]
    traj_scale: float
    sampler: dict[str, Any] = field(default_factory=lambda: asdict(SamplerConfig()))
    meta: dict[str, Any] = field(default_factory=dict)

    def to_payload(self, half: bool = False) -> dict[str, Any]:
        sd = {k: (v.half() if half and v.is_floating_point() else v).contiguous()
              for k, v in self.state_dict.items()}
        cfg = dict(self.config)
        cfg["channels"] = list(cfg["channels"])
        return {"format": "lamp-flow-dc/1", "config": cfg, "state_dict": sd,
                "traj_scale": float(self.traj_scale), "sampler": dict(self.sampler),
                "meta_json": json.dumps(self.meta)}


def save_checkpoint(ck: Checkpoint, path: str | Path, half: bool = False) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save(ck.to_payload(half), path)


def load_model(path: str | Path | None = None, threads: int | None = 1) -> FlowProposer:
    """Load a ``FlowProposer`` from a checkpoint (default: the shipped one), weights only.

    ``threads``: torch intra-op threads for this process (``torch.set_num_threads``); None
    leaves torch's setting alone. The default is 1: sampling batches are small, and on a
    busy 2-core machine two threads made ``propose`` 20-50x slower (OpenMP threads waiting
    on a core held by another process) while one thread met the speed targets.
    """
    p = Path(path) if path is not None else DEFAULT_CHECKPOINT
    if not p.is_file():
        raise FileNotFoundError(f"no model checkpoint at {p}")
    if threads is not None:
        if isinstance(threads, bool) or int(threads) != threads or threads < 1:
            raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
        torch.set_num_threads(int(threads))
    payload = torch.load(p, map_location="cpu", weights_only=True)
    if payload.get("format") != "lamp-flow-dc/1":
        raise ValueError(f"{p} is not a lamp flow-dc checkpoint (format {payload.get('format')!r})")
    net = FlowNet(NetConfig.from_dict(payload["config"]))
    net.load_state_dict({k: v.float() if v.is_floating_point() else v
                         for k, v in payload["state_dict"].items()})
    sampler = SamplerConfig(**payload.get("sampler", {}))
    return FlowProposer(net, payload["traj_scale"], sampler, json.loads(payload["meta_json"]))
