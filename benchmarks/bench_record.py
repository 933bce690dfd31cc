"""Recording sizes and render times of ``lamp render`` for a 4 m and a 50 m run.

Run: ``python benchmarks/bench_record.py [--model learned|geometric] [--reps 3]``. Each
scene is planned and executed once (LAMP-Lazy, seed 0) and recorded; then the recording is
saved (npz + json sizes) and rendered to GIF, MP4, PNG, HTML and MCAP ``--reps`` times each at the
defaults of ``lamp render`` (640 px, 15 fps, auto speed). Prints medians.

Runs: the 4 m run is the first scene of the ``random`` suite; the 50 m planner run is a
50 m x 50 m map with a few obstacles and a box to carry 12 m (LAMP-Lazy solves it; a
failed run would be recorded all the same); the 50 m scripted run executes 100 straight 0.4 m pushes of
a box across the same map in the simulator, recorded through the same per-segment
observer, to size a 100-segment recording on a large map.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from lamp import solve
from lamp.planners.config import PlannerConfig
from lamp.record import save_recording
from lamp.scene import scene_from_dict
from lamp.suites import suite_scenes
from lamp.viz.animation import mp4_available
from lamp.viz.replay import render
from lamp.viz.replay_mcap import mcap_available

LARGE = {
    "format": "lamp-scene/1",
    "name": "open-50m",
    "workspace": [50.0, 50.0],
    "robots": {"radius": 0.05, "starts": [[18.6, 20.2], [18.6, 20.5], [18.6, 20.8]]},
    "obstacles": [
        {"type": "rectangle", "center": [25.0, 27.0], "size": [1.0, 6.0], "angle": 0.0},
        {"type": "circle", "center": [10.0, 40.0], "radius": 2.0},
        {"type": "rectangle", "center": [40.0, 12.0], "size": [4.0, 1.0], "angle": 0.5},
        {"type": "circle", "center": [30.0, 19.0], "radius": 0.6},
    ],
    "objects": [{"type": "rectangle", "size": [0.4, 0.3], "start": [19.2, 20.5, 0.0],
                 "goal": [31.2, 21.0, 0.0]}],
}


def scripted_run(scene, segments: int = 100, step: float = 0.4):
    """Push the scene's box ``segments`` times by ``step`` metres along +x, straight, in the
    simulator; returns (Recording, success)."""
    from lamp.contract.plan import Plan, PlanStatus
    from lamp.contract.trajectory import straight_moves
    from lamp.contract.transition import Transition
    from lamp.planners.closed_loop import RENDER_EVERY, SegmentEvent
    from lamp.record import Recorder
    from lamp.sim import Simulator
    from lamp.sim.mjcf import TIMESTEP

    sim = Simulator(scene)
    recorder = Recorder(scene, RENDER_EVERY * TIMESTEP)
    q = scene.object_starts()[0]
    robots = sim.robot_positions
    transitions = []
    for _ in range(segments):
        q_to = q + np.array([step, 0.0, 0.0])
        ends = robots + np.array([step, 0.0])
        push = straight_moves(robots, ends)
        local = robots - q[:2]
        pushes_local = np.stack([local, local + [step, 0.0]], axis=1)
        transitions.append(Transition(q, q_to, robots.copy(), pushes_local, push[:, :1], push))
        q, robots = q_to, ends
    plan = Plan(PlanStatus.SOLVED, transitions,
                [(t.q_from[:2], t.q_to[:2]) for t in transitions], [])
    for g, trans in enumerate(transitions):
        out = sim.execute(trans.robot_paths, record_every=RENDER_EVERY)
        got = out.object_poses[0]
        drift = (float(np.hypot(*(got[:2] - trans.q_to[:2]))), float(abs(got[2] - trans.q_to[2])))
        recorder(SegmentEvent(0, g, trans, out, plan, 0.0, g == 0, drift, "continue"))
    final = sim.object_poses[0]
    success = bool(np.hypot(*(final[:2] - scene.objects[0].goal[:2])) < 0.1)
    result = {"scene": scene.name, "planner": "scripted", "seed": 0, "success": success,
              "objects": [{"success": success, "final_pose": final.tolist()}],
              "segments": segments, "total_planning_time_s": 0.0, "wall_time_s": 0.0,
              "replans": 0, "makespan": 0}
    return recorder.finish("scripted", 0, result), success


def measure(name: str, scene, model: str, reps: int, time_limit: float) -> None:
    t0 = time.perf_counter()
    if model == "scripted":
        rec, success = scripted_run(scene)
    else:
        result = solve(scene, "lazy", seed=0, model=model,
                       config=PlannerConfig.of(planning_time_limit=time_limit))
        rec, success = result.recording, result.success
    run_s = time.perf_counter() - t0
    W, H = scene.workspace
    print(f"\n{name}: {scene.name} ({W:g} m x {H:g} m), success {success}, "
          f"{rec.n_segments} segments, {rec.n_rows} rows, "
          f"{rec.arrays['times'][-1]:.1f} s simulated, run {run_s:.1f} s")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        t0 = time.perf_counter()
        npz, index = save_recording(rec, out)
        save_s = time.perf_counter() - t0
        print(f"  recording: {npz.stat().st_size / 1e3:.1f} kB npz + "
              f"{index.stat().st_size / 1e3:.1f} kB json, saved in {save_s * 1e3:.0f} ms")
        kinds = (["gif", "png", "html"] + (["mp4"] if mp4_available() else [])
                 + (["mcap"] if mcap_available() else []))
        for kind in kinds:
            times, size, frames = [], 0, 0
            for _ in range(reps):
                stats = render(rec, out / f"replay.{kind}")
                times.append(stats.seconds)
                frames = stats.frames
                size = stats.path.stat().st_size
            per = f", {np.median(times) / frames * 1e3:.1f} ms/frame" if frames > 1 else ""
            print(f"  {kind:4s}: median {np.median(times):.2f} s over {reps} "
                  f"({frames} frames{per}), {size / 1e3:.0f} kB")
        if not mp4_available():
            print("  mp4 : skipped (pip install imageio-ffmpeg)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="learned", choices=("learned", "geometric"))
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--time-limit", type=float, default=10.0,
                    help="planning limit per object [s]")
    ap.add_argument("--skip-large-planner-run", action="store_true",
                    help="leave out the 50 m planner run")
    args = ap.parse_args()
    small = suite_scenes("random")[0]
    measure("4 m run", small, args.model, args.reps, args.time_limit)
    if not args.skip_large_planner_run:
        measure("50 m planner run", scene_from_dict(LARGE), args.model, args.reps,
                args.time_limit)
    line = dict(LARGE, name="line-50m", objects=[dict(
        LARGE["objects"][0], start=[3.0, 10.0, 0.0], goal=[43.0, 10.0, 0.0])],
        robots={"radius": 0.05, "starts": [[2.74, 9.88], [2.74, 10.0], [2.74, 10.12]]})
    measure("50 m scripted run", scene_from_dict(line), "scripted", args.reps, args.time_limit)


if __name__ == "__main__":
    main()
