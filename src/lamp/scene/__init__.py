"""Scenes: the data model and the validating file loader (format ``lamp-scene/1``).

The model is imported at once; the loader and writer (YAML, Shapely) on first use.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from lamp.lazy_exports import lazy_getattr
from lamp.scene.model import (
    Circle,
    Obstacle,
    Polygon,
    Pose,
    Rectangle,
    Scene,
    SceneObject,
    Shape,
    shape_from_dict,
)

#: Names defined by the loader and the writer, imported when first asked for.
_LAZY = {"SceneError": "lamp.scene.loader", "load_scene": "lamp.scene.loader",
         "scene_from_dict": "lamp.scene.loader", "save_scene": "lamp.scene.save"}

if TYPE_CHECKING:
    from lamp.scene.loader import SceneError, load_scene, scene_from_dict
    from lamp.scene.save import save_scene


__getattr__ = lazy_getattr("lamp.scene", _LAZY, globals())


__all__ = [
    "Circle",
    "Obstacle",
    "Polygon",
    "Pose",
    "Rectangle",
    "Scene",
    "SceneError",
    "SceneObject",
    "Shape",
    "load_scene",
    "save_scene",
    "scene_from_dict",
    "shape_from_dict",
]
