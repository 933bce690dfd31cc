"""lamp: long-horizon adaptive manipulation planning for multi-robot collaborative pushing.

Public entry points (see ``docs``/README): ``load_scene``, ``SceneError``, ``solve``,
``load_recording`` and ``render`` (recorded runs, ``docs/recording-format.md``).
Heavy dependencies (MuJoCo, PyTorch) are imported only by the modules that use them.
"""

from lamp.scene import Scene, SceneError, load_scene

__version__ = "0.1.0"


def solve(scene: Scene, planner: str = "lazy", seed: int = 0, **kwargs):
    """Plan and execute ``scene`` with ``planner``; returns a ``RunResult`` (``.to_dict()``)."""
    from lamp.planners.run import solve as _solve

    return _solve(scene, planner=planner, seed=seed, **kwargs)


def load_recording(run_dir):
    """The ``lamp.record.Recording`` of a run folder (``recording.json`` + ``.npz``)."""
    from lamp.record import load_recording as _load

    return _load(run_dir)


def render(recording, path, **options):
    """Draw a recording to ``path`` (.gif, .mp4, .png or .html); see ``lamp.viz.replay``."""
    from lamp.viz.replay import render as _render

    return _render(recording, path, **options)


__all__ = ["Scene", "SceneError", "load_recording", "load_scene", "render", "solve",
           "__version__"]
