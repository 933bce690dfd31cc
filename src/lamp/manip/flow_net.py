"""The flow-matching network of the learned proposer and its hyper-parameters.

:class:`FlowNet` is a joint denoiser: a CNN (:class:`ImageEncoder`) encodes the object mask
(``lamp.manip.image``); embeddings of the noisy contact tokens, the noisy trajectory, the
requested motion, the budget and the flow time are concatenated with it and fed through a
residual MLP trunk with two heads, token logits (clean-token posterior) and trajectory
velocity. :class:`NetConfig` holds the hyper-parameters a checkpoint stores. Sampling,
snapping onto the contact ring and checkpoints are ``lamp.manip.network``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import torch
from torch import nn

from lamp.manip.contacts import HORIZON, MAX_ROBOTS
from lamp.manip.flow import N_CLASSES, N_INPUT_TOKENS, time_embedding
from lamp.manip.image import IMAGE_SIZE

TRAJECTORY_PARAMS = ("residual", "displacement")
"""How the continuous part encodes a push (both are displacements from the contact,
divided by a data scale): ``displacement`` is the raw displacement of each waypoint;
``residual`` subtracts the displacement the contact would have if carried rigidly with the
object along the requested motion (``rigid_displacements``), which is known in closed form
once the contact is, so the flow only has to generate the (small) deviation from it."""


@dataclass(frozen=True)
class NetConfig:
    """Hyper-parameters of ``FlowNet`` (stored in checkpoints)."""

    image_size: int = IMAGE_SIZE
    channels: tuple[int, ...] = (8, 16, 32, 32)
    image_dim: int = 128
    token_dim: int = 32
    traj_dim: int = 256
    cond_dim: int = 64
    time_dim: int = 64
    hidden: int = 384
    blocks: int = 3
    slots: int = MAX_ROBOTS
    horizon: int = HORIZON
    trajectory: str = "residual"

    def __post_init__(self) -> None:
        if self.trajectory not in TRAJECTORY_PARAMS:
            raise ValueError(f"trajectory must be one of {TRAJECTORY_PARAMS}, "
                             f"got {self.trajectory!r}")

    @property
    def residual(self) -> bool:
        return self.trajectory == "residual"

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> NetConfig:
        d = dict(d)
        d["channels"] = tuple(d["channels"])
        d.setdefault("trajectory", "displacement")  # checkpoints from before the option
        return cls(**d)


class ImageEncoder(nn.Module):
    """Strided 3x3 convolutions (each halves the resolution), then a linear projection."""

    def __init__(self, cfg: NetConfig) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        c_in, size = 1, cfg.image_size
        for c in cfg.channels:
            layers += [nn.Conv2d(c_in, c, 3, stride=2, padding=1), nn.SiLU()]
            c_in, size = c, (size + 1) // 2
        self.conv = nn.Sequential(*layers)
        self.proj = nn.Sequential(nn.Flatten(), nn.Linear(c_in * size * size, cfg.image_dim),
                                  nn.SiLU())

    def forward(self, img: torch.Tensor) -> torch.Tensor:
        return self.proj(self.conv(img))


class ResBlock(nn.Module):
    def __init__(self, width: int) -> None:
        super().__init__()
        self.net = nn.Sequential(nn.LayerNorm(width), nn.Linear(width, width), nn.SiLU(),
                                 nn.Linear(width, width))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.net(x)


class FlowNet(nn.Module):
    """Joint denoiser: (image embedding, x_t tokens, x_t trajectory, motion, budget, t) ->
    (clean-token logits (B, 2S, N_CLASSES), velocity (B, S, H-1, 2))."""

    def __init__(self, cfg: NetConfig | None = None) -> None:
        super().__init__()
        self.cfg = cfg = cfg or NetConfig()
        n_tok = 2 * cfg.slots
        self.traj_numel = cfg.slots * (cfg.horizon - 1) * 2
        self.image = ImageEncoder(cfg)
        self.tok_emb = nn.Embedding(N_INPUT_TOKENS, cfg.token_dim)
        self.tok_pos = nn.Parameter(torch.zeros(n_tok, cfg.token_dim))
        self.traj_in = nn.Sequential(nn.Linear(self.traj_numel, cfg.traj_dim), nn.SiLU())
        self.cond_in = nn.Sequential(nn.Linear(3 + cfg.slots, cfg.cond_dim), nn.SiLU(),
                                     nn.Linear(cfg.cond_dim, cfg.cond_dim), nn.SiLU())
        self.time_in = nn.Sequential(nn.Linear(cfg.time_dim, cfg.time_dim), nn.SiLU())
        width_in = (cfg.image_dim + n_tok * cfg.token_dim + cfg.traj_dim + cfg.cond_dim
                    + cfg.time_dim + 3)
        self.trunk_in = nn.Linear(width_in, cfg.hidden)
        self.trunk = nn.Sequential(*[ResBlock(cfg.hidden) for _ in range(cfg.blocks)],
                                   nn.LayerNorm(cfg.hidden), nn.SiLU())
        self.token_head = nn.Linear(cfg.hidden, n_tok * N_CLASSES)
        self.vel_head = nn.Linear(cfg.hidden, self.traj_numel)
        nn.init.normal_(self.tok_pos, std=0.02)

    def encode_image(self, img: torch.Tensor) -> torch.Tensor:
        """(B, S, S) or (B, 1, S, S) masks -> (B, image_dim)."""
        if img.dim() == 3:
            img = img[:, None]
        return self.image(img)

    def forward(
        self,
        img_emb: torch.Tensor,
        tokens: torch.Tensor,
        traj: torch.Tensor,
        motion: torch.Tensor,
        budget: torch.Tensor,
        t: torch.Tensor,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        b = tokens.shape[0]
        tok = (self.tok_emb(tokens) + self.tok_pos).reshape(b, -1)
        onehot = nn.functional.one_hot(budget.long() - 1, self.cfg.slots).to(motion.dtype)
        cond = self.cond_in(torch.cat([motion, onehot], dim=-1))
        h = torch.cat([img_emb, tok, self.traj_in(traj.reshape(b, -1)), cond,
                       self.time_in(time_embedding(t, self.cfg.time_dim)), motion], dim=-1)
        h = self.trunk(self.trunk_in(h))
        logits = self.token_head(h).view(b, 2 * self.cfg.slots, N_CLASSES)
        vel = self.vel_head(h).view(b, self.cfg.slots, self.cfg.horizon - 1, 2)
        return logits, vel
