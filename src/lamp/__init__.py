"""lamp: long-horizon adaptive manipulation planning for multi-robot collaborative pushing.

Public entry points (see the README's "Using it"): ``load_scene``, ``scene_from_dict``,
``save_scene``, ``SceneError``, ``solve``, and for recorded runs ``load_recording`` and
``render`` (``docs/recording-format.md``). They are imported on first use (PEP 562), so
that importing a leaf module such as ``lamp.geometry.se2`` does not load the scene
format's YAML parser or Shapely, and heavy dependencies (MuJoCo, PyTorch) are imported
only by the modules that use them.
"""

from __future__ import annotations

from importlib import metadata as _metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

try:
    __version__ = _metadata.version("lamp")
except _metadata.PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

# Light imports (NumPy at most): the types of ``solve``'s signature, so that
# ``typing.get_type_hints(lamp.solve)`` resolves.
from lamp._lazy import lazy_getattr
from lamp.contract.result import RunResult
from lamp.planners.config import PlannerConfig, PlannerName
from lamp.progress import ProgressCallback
from lamp.scene.model import Scene

#: Public name -> module that defines it (loaded on first use: YAML, Shapely).
_EXPORTS = {
    "SceneError": "lamp.scene.loader",
    "load_scene": "lamp.scene.loader",
    "scene_from_dict": "lamp.scene.loader",
    "save_scene": "lamp.scene.save",
}

if TYPE_CHECKING:
    from lamp.scene.loader import SceneError, load_scene, scene_from_dict
    from lamp.scene.save import save_scene


__getattr__ = lazy_getattr("lamp", _EXPORTS, globals())


def solve(scene: Scene | str | Path, planner: PlannerName = "lazy", seed: int = 0, *,
          model: str | Path | Any = "learned", config: PlannerConfig | None = None,
          render: bool = False, time_limit: float | None = None,
          progress: ProgressCallback | None = None) -> RunResult:
    """Plan and execute ``scene`` with ``planner``; ``result.to_dict()`` is result.json.

    Args:
        scene: a ``Scene``, the path of a scene file or a built-in suite scene by name
            (``"maze-07"``); ``SceneError`` if it is invalid or unknown.
        planner: ``"lazy"`` (LAMP-Lazy, default), ``"astar"`` (LAMP-A*, open loop),
            ``"astar-replan"`` (LAMP-A*, replanning on drift), ``"gco-ori"`` (GCo with its
            0.2 m buffer), ``"gco-var"`` (GCo with zero buffer) or ``"mapush"`` (the
            MAPush-style RL baseline: lattice subgoals and a PPO pushing policy).
        seed: random seed; the same scene, planner and seed give the same result.
        model: ``"learned"`` (the shipped checkpoint), ``"geometric"``, the path of a
            checkpoint written by ``lamp model train``, or a proposer object.
        config: planner parameters (``lamp.planners.config.PlannerConfig``); default: the
            planner's own (cumulative planning limit 300 s per object, 500 s for LAMP-A*).
        render: also record animation frames (see ``lamp.planners.run.solve_with_frames``).
        time_limit: cumulative planning limit per object in seconds (overrides ``config``).
        progress: called with a ``lamp.progress.ProgressEvent`` as the run advances.

    Raises ``ValueError`` for an unknown planner or model (``ModelError`` for a bad
    checkpoint file), ``SceneError`` for a scene the model cannot serve (robots of another
    radius). Numba compilation happens before the planning clock starts.
    """
    from lamp.planners.run import solve as _solve

    return _solve(scene, planner=planner, seed=seed, model=model, config=config, render=render,
                  time_limit=time_limit, progress=progress)


def load_recording(run_dir):
    """The ``lamp.record.Recording`` of a run folder (``recording.json`` + ``.npz``)."""
    from lamp.record import load_recording as _load

    return _load(run_dir)


def render(recording, path, **options):
    """Draw a recording to ``path`` (.gif, .mp4, .png or .html); see ``lamp.viz.replay``."""
    from lamp.viz.replay import render as _render

    return _render(recording, path, **options)


__all__ = ["Scene", "SceneError", "load_recording", "load_scene", "render", "save_scene",
           "scene_from_dict", "solve",
           "__version__"]


def __dir__() -> list[str]:
    """The public names only (``dir(lamp)``), not the imports this module needs."""
    return sorted(__all__)
