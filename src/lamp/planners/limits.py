"""What the planners and the simulator can serve beyond the scene format: shapes they are
not made for are refused before anything runs, naming the field and the limit.

The scene format accepts any positive size; these limits are the machinery's:

- an object narrower than ``MIN_OBJECT_WIDTH`` (2 cm) in some direction: the planners'
  object checks shrink and grow footprints by up to 1 cm (the lattice join's tolerances,
  the narrow-passage refinement), so a thinner object vanishes under them, and a
  pushing robot 10 cm across cannot hold a contact on it;
- an obstacle narrower than ``MIN_OBSTACLE_WIDTH`` (2 mm): the simulator's soft contacts
  let a robot press up to 1 mm into a surface, so a thinner wall can be pushed through.

``RunRequest`` (``lamp run``, ``lamp.solve``, ``lamp bench``) and ``lamp validate`` apply
:func:`check_scene_limits`; the error is a :class:`~lamp.scene.SceneError` (exit 2).
"""

from __future__ import annotations

from lamp.geometry.shapes import narrowest_width
from lamp.scene.errors import SceneError
from lamp.scene.model import Circle, Rectangle, Scene, Shape

__all__ = ["MIN_OBJECT_WIDTH", "MIN_OBSTACLE_WIDTH", "check_scene_limits"]

MIN_OBJECT_WIDTH = 0.02
MIN_OBSTACLE_WIDTH = 0.002


def _size_field(shape: Shape) -> str:
    return "radius" if isinstance(shape, Circle) else "size" if isinstance(shape, Rectangle) \
        else "points"


def check_scene_limits(scene: Scene) -> None:
    """``SceneError`` naming the first object or obstacle narrower than its limit."""
    where = scene.source or scene.name
    for what, items, limit in (("objects", [o.shape for o in scene.objects], MIN_OBJECT_WIDTH),
                               ("obstacles", [o.shape for o in scene.obstacles],
                                MIN_OBSTACLE_WIDTH)):
        for k, shape in enumerate(items):
            width = narrowest_width(shape)
            if width < limit:
                field = f"{what}[{k}].{_size_field(shape)}"
                reason = (f"{width:.3g} m across at its narrowest; the planners and the "
                          f"simulator serve {what} at least {limit:g} m across")
                raise SceneError(f"{where}: {field}: {reason}", path=scene.source,
                                 field=field, reason=reason)
