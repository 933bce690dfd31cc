"""lamp: long-horizon adaptive manipulation planning for multi-robot collaborative pushing.

Public entry points (see ``docs``/README): ``load_scene``, ``SceneError``, ``solve``.
Heavy dependencies (MuJoCo, PyTorch) are imported only by the modules that use them.
"""

from lamp._version import __version__
from lamp.scene import Scene, SceneError, load_scene


def solve(scene: Scene, planner: str = "lazy", seed: int = 0, **kwargs):
    """Plan and execute ``scene`` with ``planner``; returns a ``RunResult`` (``.to_dict()``)."""
    from lamp.planners.run import solve as _solve

    return _solve(scene, planner=planner, seed=seed, **kwargs)


__all__ = ["Scene", "SceneError", "load_scene", "solve", "__version__"]
