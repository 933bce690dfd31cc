"""``lamp model ...``: generate push data, train and evaluate the manipulation model.

Commands only parse arguments, call the library (``lamp.manip.dataset`` / ``train`` /
``evaluate``) and write files.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Optional

import typer

from lamp.cli.support import fail_input, lamp_typer

model_app = lamp_typer(
    help="The learned manipulation model: push data, training, evaluation.",
    no_args_is_help=True,
    add_completion=False,
)

DEFAULT_DATA = Path("data/manip_train.npz")


def _threads(n: int) -> None:
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        os.environ.setdefault(var, str(n))
    import torch

    torch.set_num_threads(n)


@model_app.command("data")
def data_cmd(
    out: Path = typer.Option(DEFAULT_DATA, "--out", "-o", help="Dataset file (.npz) to write."),
    attempts: int = typer.Option(26000, help="Pushes to simulate (about 80% are kept)."),
    seed: int = typer.Option(0, "--seed", "-s", help="Seed of the generator."),
    workers: int = typer.Option(max(1, os.cpu_count() or 1), "--workers", "-j",
                                help="Worker processes."),
    accept_translation: float = typer.Option(0.1, help="Keep pushes within this error \\[m]."),
    accept_rotation: float = typer.Option(0.3, help="... and within this error \\[rad]."),
) -> None:
    """Simulate pushes with the contact strategies and keep those that land near the request."""
    from lamp.manip.dataset import generate

    if attempts < 1 or workers < 1:
        fail_input("--attempts and --workers must be >= 1")
    ds = generate(attempts, seed=seed, workers=workers, accept_translation=accept_translation,
                  accept_rotation=accept_rotation)
    ds.save(out)
    typer.echo(json.dumps(ds.meta, indent=1))
    typer.echo(f"wrote {len(ds)} samples to {out}")


@model_app.command("train")
def train_cmd(
    data: Path = typer.Option(DEFAULT_DATA, "--data", help="Dataset (.npz from `lamp model data`)."),
    run_dir: Path = typer.Option(Path("data/manip_run"), "--run-dir",
                                 help="Run directory (resumes from it if it holds a state)."),
    epochs: int = typer.Option(30, help="Total epochs (a resumed run continues up to this)."),
    seed: int = typer.Option(0, "--seed", "-s", help="Seed (initialisation, split, batches)."),
    threads: int = typer.Option(1, help="Torch threads."),
    max_minutes: float = typer.Option(None, help="Stop after the epoch crossing this budget.",
                                      show_default="no budget"),
    export_to: Path = typer.Option(None, "--export", help="Also write the model here "
                                   "(plus a .json with its metadata next to it).",
                                   show_default="RUN_DIR/model.pt only"),
    guidance: float = typer.Option(None, help="Smoothness guidance stored in the export.",
                                   show_default="the sampler's default"),
    temperature: float = typer.Option(None, help="Token temperature stored in the export.",
                                      show_default="the sampler's default"),
    oversample: float = typer.Option(None, help="Candidates drawn per proposal returned "
                                     "(best-ranked kept), stored in the export.",
                                     show_default="the sampler's default"),
) -> None:
    """Train (or resume training) the flow-matching proposer; logs losses per epoch."""
    _threads(threads)
    from lamp.manip.dataset import PushDataset
    from lamp.manip.train import TrainConfig, train

    if not data.is_file():
        fail_input(f"no dataset at {data} (run `lamp model data` first)")
    ds = PushDataset.load(data)
    summary = train(ds, run_dir, TrainConfig(epochs=epochs, seed=seed, threads=threads),
                    max_minutes=max_minutes)
    if export_to is not None:
        from lamp.manip.network import load_model
        from lamp.manip.train import export

        model = load_model(run_dir / "model.pt")
        if guidance is not None:
            model.sampler.guidance = guidance
        if temperature is not None:
            model.sampler.temperature = temperature
        if oversample is not None:
            model.sampler.oversample = oversample
        summary.pop("wall_time_s_this_run", None)
        meta = {"checkpoint": export_to.name, "data_file": str(data), "data_meta": ds.meta,
                "sampler": vars(model.sampler), "parameters": sum(
                    p.numel() for p in model.net.parameters()), **summary}
        export(model.net, model.traj_scale, export_to, meta, model.sampler)
        export_to.with_suffix(".json").write_text(json.dumps(meta, indent=1) + "\n")
        typer.echo(f"exported {export_to} and {export_to.with_suffix('.json').name}")
    typer.echo(json.dumps(summary, indent=1))


@model_app.command("eval")
def eval_cmd(
    model: str = typer.Option("learned", "--model", "-m", help="learned (the shipped "
                              "checkpoint) or a checkpoint file from `lamp model train`."),
    cases: int = typer.Option(60, help="Held-out (shape, motion) cases per budget."),
    proposals: int = typer.Option(4, "--proposals", help="Proposals executed per case."),
    k_alias: int = typer.Option(None, "--k", hidden=True, help="Old spelling of --proposals."),
    seed: int = typer.Option(12345, "--seed", "-s", help="Seed of the held-out cases."),
    threads: int = typer.Option(1, help="Torch threads."),
    out: Path = typer.Option(None, "--out", "-o", help="Write the report as JSON here.",
                             show_default="printed only"),
    geometric: bool = typer.Option(True, help="Run the geometric proposer side by side."),
    record: bool = typer.Option(False, "--store-in-checkpoint/--no-store-in-checkpoint",
                                help="Add the figures to the checkpoint's .json."),
    record_alias: Optional[bool] = typer.Option(  # noqa: UP045 (typer reads the annotation)
        None, "--record/--no-record", hidden=True, help="Old spelling of "
        "--store-in-checkpoint (lamp bench --record saves recordings)."),
    polygons: bool = typer.Option(False, help="Also evaluate on random convex polygons "
                                  "(out of the training distribution)."),
    large: bool = typer.Option(False, help="Also evaluate on large objects (bars 1.0-1.5 m, "
                               "L/T shapes 0.8-1.2 m), which the learned model proposes for "
                               "scaled down; with the learned model unscaled beside it "
                               "(flow-noscale)."),
) -> None:
    """Execute proposals for held-out shapes and motions in the simulator; report accuracy."""
    from lamp.cli.support import check_model_option, check_writable_file, fail_input

    k = k_alias if k_alias is not None else proposals
    record = record_alias if record_alias is not None else record
    if k < 1 or cases < 1:
        fail_input(f"--proposals and --cases must be >= 1, got {k} and {cases}")
    if model == "geometric":
        fail_input("--model: eval measures a learned checkpoint; the geometric proposer runs "
                   "beside it unless --no-geometric")
    checkpoint = check_model_option(model)
    if out is not None:
        check_writable_file(out)
    _threads(threads)
    from lamp.manip import GeometricProposer, load_model
    from lamp.manip.evaluate import evaluate, format_report
    from lamp.manip.network import DEFAULT_CHECKPOINT

    model_path = DEFAULT_CHECKPOINT if checkpoint == "learned" else Path(checkpoint)
    proposers = {"flow": load_model(model_path, threads=threads)}
    if geometric:
        proposers["geometric"] = GeometricProposer()
    report = evaluate(proposers, cases_per_budget=cases, k=k, seed=seed)
    typer.echo(format_report(report))
    if polygons:
        report_poly = evaluate(proposers, cases_per_budget=cases, k=k, seed=seed, polygons=True)
        typer.echo(format_report(report_poly))
        report = {**report, "polygons_report": report_poly}
    if large:
        import math

        from lamp.manip.network import FlowProposer

        flow = proposers["flow"]
        large_props = {"flow": flow, "flow-noscale": FlowProposer(
            flow.net, flow.traj_scale, flow.sampler, flow.meta, max_extent=math.inf)}
        if geometric:
            large_props["geometric"] = proposers["geometric"]
        report_large = evaluate(large_props, cases_per_budget=cases, k=k, seed=seed, large=True)
        typer.echo(format_report(report_large))
        report = {**report, "large_report": report_large}
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(report, indent=1))
        typer.echo(f"wrote {out}")
    if record:
        meta_path = model_path.with_suffix(".json")
        meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
        meta["evaluation"] = report
        meta_path.write_text(json.dumps(meta, indent=1) + "\n")
        typer.echo(f"recorded the figures in {meta_path}")
