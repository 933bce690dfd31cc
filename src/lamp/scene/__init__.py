"""Scenes: the data model and the validating file loader (format ``lamp-scene/1``)."""

from lamp.scene.loader import SceneError, load_scene, scene_from_dict
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
from lamp.scene.save import save_scene

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
