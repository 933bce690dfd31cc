"""Training the flow-matching proposer on a ``PushDataset`` (resumable, logged).

Each step draws ``images_per_step`` samples, applies a random symmetry of the square (the
8 rotations/reflections of D4: circles and rectangles map to circles and rectangles, and
contacts, paths and motions transform with them, a reflection flipping dtheta), encodes
their masks once, and pairs every encoding with ``draws_per_image`` independent flow times
and noises (the CNN is most of the cost, so this makes a batch of
``images_per_step * draws_per_image`` rows cheap). Loss = token cross-entropy +
``mse_weight`` * trajectory velocity MSE (``lamp.manip.flow.flow_losses``), AdamW with a
cosine learning-rate decay. A training checkpoint (model, optimiser, epoch) is written after
every epoch into the run directory and picked up again on restart; ``losses.jsonl`` logs
every epoch. Determinism: each epoch's randomness comes from (seed, epoch).
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from lamp.manip.contacts import HORIZON, MAX_ROBOTS, rigid_displacements
from lamp.manip.dataset import PushDataset
from lamp.manip.flow import (
    NOISE,
    canonical_order,
    flow_losses,
    noise_tokens,
    noise_trajectory,
    tokenize,
)
from lamp.manip.flow_net import FlowNet, NetConfig
from lamp.manip.image import batch_images
from lamp.manip.network import (
    MOTION_SCALE,
    Checkpoint,
    SamplerConfig,
    save_checkpoint,
)

log = logging.getLogger(__name__)


@dataclass
class TrainConfig:
    """Optimisation settings (stored in the run directory and the shipped metadata)."""

    epochs: int = 30
    images_per_step: int = 64
    draws_per_image: int = 4
    lr: float = 1e-3
    weight_decay: float = 1e-4
    mse_weight: float = 1.0
    seed: int = 0
    val_fraction: float = 0.05
    threads: int = 1
    augment: bool = True


# --------------------------------------------------------------------------- batches
_D4 = [np.array([[c, -s], [s, c]], dtype=float) @ np.diag([1.0, f])
       for c, s in ((1, 0), (0, 1), (-1, 0), (0, -1)) for f in (1.0, -1.0)]


@dataclass
class Batch:
    """Network-ready arrays for a set of samples (float32 / int64 torch tensors)."""

    images: torch.Tensor  # (B, S, S)
    tokens: torch.Tensor  # (B, 2 slots) clean tokens
    traj: torch.Tensor  # (B, slots, H-1, 2) normalised displacements (0 for unused slots)
    used: torch.Tensor  # (B, slots) bool
    motion: torch.Tensor  # (B, 3) normalised achieved motion
    budget: torch.Tensor  # (B,) long


def make_batch(
    ds: PushDataset,
    idx: np.ndarray,
    traj_scale: float,
    rng: np.random.Generator | None,
    image_size: int,
    residual: bool = True,
) -> Batch:
    """Assemble samples ``idx`` (with a random D4 symmetry each when ``rng`` is given).

    ``residual``: encode the pushes as deviations from the rigid displacement of the
    contact along the (achieved) motion, see ``lamp.manip.flow_net.TRAJECTORY_PARAMS``.
    """
    kind = ds.shape_kind[idx].astype(int)
    params = ds.shape_params[idx].copy()
    motion = ds.achieved[idx].copy()
    contacts = ds.contacts[idx].copy()
    paths = ds.paths[idx].copy()
    if rng is not None:
        g = rng.integers(0, 8, size=len(idx))
        a = np.stack([_D4[i] for i in g])  # (B, 2, 2)
        det = np.linalg.det(a)
        swap = (g // 2) % 2 == 1  # 90/270-degree rotations swap a rectangle's sides
        params[swap] = params[swap][:, ::-1]
        motion[:, :2] = np.einsum("bij,bj->bi", a, motion[:, :2])
        motion[:, 2] *= det
        contacts = np.einsum("bij,bsj->bsi", a, contacts)
        paths = np.einsum("bij,bshj->bshi", a, paths)
    order = canonical_order(contacts, motion)
    contacts = np.take_along_axis(contacts, order[..., None], axis=1)
    paths = np.take_along_axis(paths, order[..., None, None], axis=1)
    used = ~np.isnan(contacts[..., 0])
    disp = paths[:, :, 1:] - paths[:, :, :1]
    if residual:
        disp = disp - rigid_displacements(contacts, motion, paths.shape[2])[:, :, 1:]
    disp = np.nan_to_num(disp / traj_scale)
    return Batch(
        images=torch.from_numpy(batch_images(kind, params, image_size)),
        tokens=torch.from_numpy(tokenize(contacts)),
        traj=torch.from_numpy(disp.astype(np.float32)),
        used=torch.from_numpy(used),
        motion=torch.from_numpy((motion / np.array(MOTION_SCALE)).astype(np.float32)),
        budget=torch.from_numpy(ds.budget[idx].astype(np.int64)),
    )


def trajectory_scale(ds: PushDataset, residual: bool = True) -> float:
    """Root mean square of the encoded pushes over all used waypoints (normalisation)."""
    disp = ds.paths[:, :, 1:] - ds.paths[:, :, :1]
    if residual:
        disp = disp - rigid_displacements(ds.contacts, ds.achieved, ds.paths.shape[2])[:, :, 1:]
    return float(max(np.sqrt(np.nanmean(disp**2)), 1e-3))


# --------------------------------------------------------------------------- steps
def batch_losses(
    net: FlowNet, batch: Batch, draws: int, gen: torch.Generator | None
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """(cross-entropy, MSE, token accuracy on noised tokens) for ``draws`` times per sample."""
    emb = net.encode_image(batch.images).repeat_interleave(draws, dim=0)
    x1_tok = batch.tokens.repeat_interleave(draws, dim=0)
    x1 = batch.traj.repeat_interleave(draws, dim=0)
    used = batch.used.repeat_interleave(draws, dim=0)
    motion = batch.motion.repeat_interleave(draws, dim=0)
    budget = batch.budget.repeat_interleave(draws, dim=0)
    n = len(x1)
    t = torch.rand(n, generator=gen)
    xt_tok = noise_tokens(x1_tok, t, gen)
    xt, target = noise_trajectory(x1, t, gen)
    xt = xt * used[:, :, None, None]
    logits, vel = net(emb, xt_tok, xt, motion, budget, t)
    ce, mse = flow_losses(logits, vel, x1_tok, xt_tok, target, used)
    with torch.no_grad():
        noised = xt_tok == NOISE
        acc = ((logits.argmax(-1) == x1_tok) & noised).sum() / noised.sum().clamp(min=1)
    return ce, mse, acc


@torch.no_grad()
def evaluate_losses(
    net: FlowNet, ds: PushDataset, idx: np.ndarray, traj_scale: float, seed: int,
    batch_size: int = 256,
) -> dict[str, float]:
    """Mean validation losses with fixed noise (comparable across epochs)."""
    net.eval()
    gen = torch.Generator().manual_seed(seed)
    tot = {"ce": 0.0, "mse": 0.0, "acc": 0.0}
    count = 0
    for s in range(0, len(idx), batch_size):
        part = idx[s:s + batch_size]
        b = make_batch(ds, part, traj_scale, None, net.cfg.image_size, net.cfg.residual)
        ce, mse, acc = batch_losses(net, b, 2, gen)
        for key, v in zip(("ce", "mse", "acc"), (ce, mse, acc), strict=True):
            tot[key] += float(v) * len(part)
        count += len(part)
    net.train()
    return {k: v / max(count, 1) for k, v in tot.items()}


def split_indices(n: int, val_fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    perm = np.random.default_rng(seed).permutation(n)
    n_val = int(round(val_fraction * n))
    return np.sort(perm[n_val:]), np.sort(perm[:n_val])


# --------------------------------------------------------------------------- the loop
def _resume_state(state_path: Path, cfg: TrainConfig, net_cfg: NetConfig | None
                  ) -> tuple[dict[str, Any] | None, TrainConfig, NetConfig | None, float | None, int]:
    """What a run directory's saved state fixes: (state or None, train config with the
    asked epochs, net config, trajectory scale, epochs done); unchanged when none is saved."""
    if not state_path.is_file():
        return None, cfg, net_cfg, None, 0
    st = torch.load(state_path, map_location="cpu", weights_only=True)
    net_cfg = NetConfig.from_dict(st["net_config"])
    saved = TrainConfig(**st["train_config"])
    if saved.epochs != cfg.epochs:
        log.info("resuming with epochs %d (was %d)", cfg.epochs, saved.epochs)
    cfg = TrainConfig(**{**asdict(saved), "epochs": cfg.epochs})
    return st, cfg, net_cfg, float(st["traj_scale"]), int(st["epoch"])


def _lr_schedule(cfg: TrainConfig, total_steps: int) -> Callable[[int], float]:
    """Learning rate per step: linear warm-up, then cosine decay to 0 at ``total_steps``."""

    def lr_at(step: int) -> float:
        warm = min(1.0, (step + 1) / max(1, min(200, total_steps // 10)))
        return cfg.lr * warm * 0.5 * (1 + math.cos(math.pi * min(step, total_steps) / total_steps))

    return lr_at


def _load_history(run: Path, start_epoch: int) -> list[dict[str, Any]]:
    """The loss records of the epochs already done; the log is cut back to them."""
    if not ((run / "losses.jsonl").is_file() and start_epoch):
        return []
    history = [json.loads(x) for x in (run / "losses.jsonl").read_text().splitlines()
               if x.strip()][:start_epoch]
    # drop log lines of an epoch whose state was never saved (killed in between)
    (run / "losses.jsonl").write_text("".join(json.dumps(h) + "\n" for h in history))
    return history


def _train_epoch(net: FlowNet, opt: torch.optim.Optimizer, ds: PushDataset,
                 train_idx: np.ndarray, epoch: int, steps_per_epoch: int, traj_scale: float,
                 cfg: TrainConfig, net_cfg: NetConfig, lr_at: Callable[[int], float],
                 progress: bool) -> np.ndarray:
    """One epoch of optimisation (batches and noise seeded by ``(cfg.seed, epoch)``);
    returns the summed (cross-entropy, MSE, token accuracy) over its steps."""
    from tqdm import tqdm

    rng = np.random.default_rng([cfg.seed, epoch])
    gen = torch.Generator().manual_seed(cfg.seed * 100_003 + epoch)
    perm = rng.permutation(train_idx)
    sums = np.zeros(3)
    bar = tqdm(range(steps_per_epoch), desc=f"epoch {epoch + 1}/{cfg.epochs}",
               disable=not progress, leave=False)
    for i in bar:
        step = epoch * steps_per_epoch + i
        for grp in opt.param_groups:
            grp["lr"] = lr_at(step)
        part = perm[i * cfg.images_per_step:(i + 1) * cfg.images_per_step]
        batch = make_batch(ds, part, traj_scale, rng if cfg.augment else None,
                           net_cfg.image_size, net_cfg.residual)
        ce, mse, acc = batch_losses(net, batch, cfg.draws_per_image, gen)
        loss = ce + cfg.mse_weight * mse
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
        opt.step()
        sums += (ce.item(), mse.item(), acc.item())
        if i % 10 == 0:
            bar.set_postfix(ce=f"{sums[0] / (i + 1):.3f}", mse=f"{sums[1] / (i + 1):.4f}")
    return sums


def _save_epoch(run: Path, rec: dict[str, Any], net: FlowNet, opt: torch.optim.Optimizer,
                epoch: int, net_cfg: NetConfig, cfg: TrainConfig, traj_scale: float,
                summary: dict[str, Any]) -> None:
    """Append the epoch's record to ``losses.jsonl``, save the resumable state and export
    the current model."""
    with open(run / "losses.jsonl", "a") as fh:
        fh.write(json.dumps(rec) + "\n")
    torch.save({
        "model": net.state_dict(), "optimizer": opt.state_dict(), "epoch": epoch + 1,
        "net_config": _cfg_dict(net_cfg), "train_config": asdict(cfg),
        "traj_scale": traj_scale,
    }, run / "train_state.pt")
    export(net, traj_scale, run / "model.pt", summary)


def train(
    ds: PushDataset,
    run_dir: str | Path,
    cfg: TrainConfig | None = None,
    net_cfg: NetConfig | None = None,
    progress: bool = True,
    max_minutes: float | None = None,
) -> dict[str, Any]:
    """Train (or resume) in ``run_dir``; returns a summary (losses, epochs, timings).

    ``run_dir/train_state.pt`` holds the resumable state, ``run_dir/losses.jsonl`` one line
    per epoch, ``run_dir/model.pt`` the current model in the shipped checkpoint format.
    ``max_minutes`` stops cleanly after the epoch that crosses that wall-clock budget.
    """
    cfg = cfg or TrainConfig()
    run = Path(run_dir)
    run.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(cfg.threads)
    st, cfg, net_cfg, traj_scale, start_epoch = _resume_state(run / "train_state.pt", cfg,
                                                               net_cfg)
    net_cfg = net_cfg or NetConfig()
    if traj_scale is None:
        traj_scale = trajectory_scale(ds, net_cfg.residual)
    torch.manual_seed(cfg.seed)  # parameter initialisation only
    net = FlowNet(net_cfg)
    opt = torch.optim.AdamW(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    if start_epoch:
        net.load_state_dict(st["model"])  # type: ignore[index]
        opt.load_state_dict(st["optimizer"])  # type: ignore[index]
    train_idx, val_idx = split_indices(len(ds), cfg.val_fraction, cfg.seed)
    steps_per_epoch = max(1, len(train_idx) // cfg.images_per_step)
    lr_at = _lr_schedule(cfg, steps_per_epoch * cfg.epochs)
    from tqdm import tqdm

    history = _load_history(run, start_epoch)
    t_start = time.perf_counter()
    net.train()
    for epoch in range(start_epoch, cfg.epochs):
        t_ep = time.perf_counter()
        sums = _train_epoch(net, opt, ds, train_idx, epoch, steps_per_epoch, traj_scale, cfg,
                            net_cfg, lr_at, progress)
        val = evaluate_losses(net, ds, val_idx, traj_scale, cfg.seed + 1) if len(val_idx) else {}
        rec = {
            "epoch": epoch + 1,
            "train_ce": sums[0] / steps_per_epoch,
            "train_mse": sums[1] / steps_per_epoch,
            "train_token_acc": sums[2] / steps_per_epoch,
            **{f"val_{k}": v for k, v in val.items()},
            "lr": lr_at((epoch + 1) * steps_per_epoch - 1),
            "epoch_s": time.perf_counter() - t_ep,
        }
        history.append(rec)
        log.info("epoch %d: %s", epoch + 1, rec)
        if progress:
            tqdm.write(json.dumps({k: round(v, 5) if isinstance(v, float) else v
                                   for k, v in rec.items()}))
        _save_epoch(run, rec, net, opt, epoch, net_cfg, cfg, traj_scale,
                    _summary(ds, cfg, history))
        if max_minutes is not None and time.perf_counter() - t_start > 60 * max_minutes:
            log.info("stopping after epoch %d: time budget of %.1f min used", epoch + 1,
                     max_minutes)
            break
    if not history:
        raise RuntimeError(f"nothing trained in {run} (epochs={cfg.epochs})")
    if start_epoch >= cfg.epochs:
        log.info("%s already holds %d epochs: nothing to train", run, start_epoch)
    summary = _summary(ds, cfg, history)
    summary["wall_time_s_this_run"] = time.perf_counter() - t_start
    return summary


def _cfg_dict(net_cfg: NetConfig) -> dict[str, Any]:
    d = asdict(net_cfg)
    d["channels"] = list(d["channels"])
    return d


def _summary(ds: PushDataset, cfg: TrainConfig, history: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "data": {"samples": len(ds), "seed": ds.meta.get("seed"),
                 "accept_translation": ds.meta.get("accept_translation"),
                 "accept_rotation": ds.meta.get("accept_rotation")},
        "train_config": asdict(cfg),
        "epochs_done": history[-1]["epoch"] if history else 0,
        "final": history[-1] if history else {},
        "train_time_s": float(sum(h["epoch_s"] for h in history)),
    }


def export(net: FlowNet, traj_scale: float, path: str | Path, meta: dict[str, Any],
           sampler: SamplerConfig | None = None, half: bool = False) -> None:
    """Write ``net`` in the shipped checkpoint format (see ``lamp.manip.network``)."""
    ck = Checkpoint(_cfg_dict(net.cfg), {k: v.detach().clone() for k, v in
                                         net.state_dict().items()}, traj_scale,
                    asdict(sampler or SamplerConfig()), meta)
    save_checkpoint(ck, path, half=half)


__all__ = ["HORIZON", "MAX_ROBOTS", "TrainConfig", "export", "make_batch", "train"]
