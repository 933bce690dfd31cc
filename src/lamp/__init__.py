"""lamp: long-horizon adaptive manipulation planning for multi-robot collaborative pushing.

Public entry points (see the README's "Using it"): ``load_scene``, ``scene_from_dict``,
``save_scene``, ``SceneError``, ``solve``, and for recorded runs ``load_recording`` and
``render`` (``docs/recording-format.md``). They are imported on first use (PEP 562), so
that importing a leaf module such as ``lamp.geometry.se2`` does not load the scene
format's YAML parser or Shapely, and heavy dependencies (MuJoCo, PyTorch) are imported
only by the modules that use them.
"""

from __future__ import annotations

from collections.abc import Mapping
from importlib import metadata as _metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

try:
    __version__ = _metadata.version("lamp")
except _metadata.PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

# Light imports (NumPy at most): the types of ``solve``'s signature, so that
# ``typing.get_type_hints(lamp.solve)`` resolves.
from lamp.contract.disturb import Disturbances
from lamp.contract.result import RunResult
from lamp.lazy_exports import lazy_getattr
from lamp.planners.config import PlannerConfig
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


def solve(scene: Scene | str | Path, planner: str = "lazy", seed: int = 0, *,
          model: str | Path | Any = "learned", config: PlannerConfig | None = None,
          params: Mapping[str, Any] | None = None, time_limit: float | None = None,
          max_segments: int | None = None, disturbances: Disturbances | None = None,
          schedule: str | None = None, progress: ProgressCallback | None = None) -> RunResult:
    """Plan and execute ``scene`` with ``planner``; ``result.to_dict()`` is result.json and
    ``result.recording`` the run's recording (every picture is drawn from it).

    Args:
        scene: a ``Scene``, the path of a scene file or a built-in suite scene by name
            (``"maze-07"``); ``SceneError`` if it is invalid or unknown.
        planner: ``"lazy"`` (LAMP-Lazy, default), ``"astar"`` (LAMP-A*, open loop),
            ``"astar-replan"`` (LAMP-A*, replanning on drift), ``"gco-ori"`` (GCo with its
            0.2 m buffer), ``"gco-var"`` (GCo with zero buffer) or ``"mapush"`` (the
            MAPush-style RL baseline: lattice subgoals and a PPO pushing policy): a name
            of ``lamp.pipeline.registry.names()``.
        seed: random seed; the same scene, planner and seed give the same result.
        model: ``"learned"`` (the shipped checkpoint), ``"geometric"``, the path of a
            checkpoint written by ``lamp model train``, or a proposer object.
        config: all planner parameters (``lamp.planners.config.PlannerConfig``); default:
            the planner's own (cumulative planning limit 300 s per object, 500 s for
            LAMP-A*).
        params: instead of ``config``, overrides of the planner's declared parameters by
            name (``{"max_plan_iterations": 400}``; ``lamp run --planner P --help-params``
            lists them).
        time_limit: cumulative planning limit per object in seconds (overrides both).
        max_segments: executed segments allowed per object (overrides both).
        disturbances: what goes wrong during the run: noisy sensing, imprecise robots,
            robots that stop, knocked pushes (``lamp.contract.disturb.Disturbances``;
            deterministic for the seed, recorded in result.json).
        schedule: ``"sequential"`` (one object after another by the whole team, the
            paper's) or ``"concurrent"`` (several at once by sub-teams); default: the
            scene's (``schedule:`` in the file, else sequential).
        progress: called with a ``lamp.progress.ProgressEvent`` as the run advances.

    Raises ``InputError`` (a ``ValueError``) for an unknown planner, model or parameter
    (``ModelError`` for a bad checkpoint file), ``SceneError`` for a scene the model cannot
    serve (robots of another radius). Numba compilation happens before the planning clock
    starts. See ``lamp.pipeline`` for the request and observers behind this call.
    """
    from lamp.contract.disturb import NO_DISTURBANCE
    from lamp.errors import InputError
    from lamp.pipeline import RunRequest, run

    if config is not None and params is not None:
        raise InputError("solve: give config or params, not both")
    request = RunRequest.build(scene, planner, seed, model=model,
                               params=config if config is not None else params,
                               planning_limit=time_limit, max_segments=max_segments,
                               disturbances=disturbances or NO_DISTURBANCE,
                               schedule=schedule)
    return run(request, progress=progress)


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
