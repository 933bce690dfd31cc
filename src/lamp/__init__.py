"""lamp: long-horizon adaptive manipulation planning for multi-robot collaborative pushing.

Public entry points (see ``docs``/README): ``load_scene``, ``SceneError``, ``solve``.
They are imported on first use (PEP 562), so that importing a leaf module such as
``lamp.geometry.se2`` does not load the scene format's YAML parser or Shapely, and heavy
dependencies (MuJoCo, PyTorch) are imported only by the modules that use them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from lamp._version import __version__

#: Public name -> module that defines it.
_EXPORTS = {
    "Scene": "lamp.scene.model",
    "SceneError": "lamp.scene.loader",
    "load_scene": "lamp.scene.loader",
}

if TYPE_CHECKING:
    from lamp.scene.loader import SceneError, load_scene
    from lamp.scene.model import Scene


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'lamp' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def solve(scene: Scene, planner: str = "lazy", seed: int = 0, **kwargs):
    """Plan and execute ``scene`` with ``planner``; returns a ``RunResult`` (``.to_dict()``)."""
    from lamp.planners.run import solve as _solve

    return _solve(scene, planner=planner, seed=seed, **kwargs)


__all__ = ["Scene", "SceneError", "load_scene", "solve", "__version__"]
