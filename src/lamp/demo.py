"""The built-in default scene of ``lamp demo``: a box carried through a doorway and turned."""

from __future__ import annotations

from importlib import resources

from lamp.scene import Scene, load_scene


def demo_scene_path() -> str:
    return str(resources.files("lamp") / "data" / "demo.yaml")


def demo_scene() -> Scene:
    return load_scene(demo_scene_path())
