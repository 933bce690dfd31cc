"""Writing scenes back to files: ``save_scene(scene, path)``.

The file is the scene-file form of ``Scene.to_dict()`` (format ``lamp-scene/1``): YAML for
``.yaml``/``.yml``, JSON for ``.json``, written atomically (a reader never sees half a
file). The guarantee the tests assert: ``load_scene(save_scene(scene, path)) == scene``.
"""

from __future__ import annotations

import json
from pathlib import Path

import yaml

from lamp.io import write_text_atomic
from lamp.scene.model import Scene

#: File extensions ``save_scene`` writes, and the format each one gets.
SCENE_SUFFIXES = {".yaml": "yaml", ".yml": "yaml", ".json": "json"}


def save_scene(scene: Scene, path: str | Path) -> Path:
    """Write ``scene`` to ``path`` (YAML or JSON by its extension); returns the path.

    Raises ``ValueError`` for any other extension (before anything is written).
    """
    path = Path(path)
    kind = SCENE_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise ValueError(f"{path}: unknown scene file extension {path.suffix!r}; expected "
                         f"one of {', '.join(SCENE_SUFFIXES)}")
    data = scene.to_dict()
    if kind == "json":
        text = json.dumps(data, indent=2) + "\n"
    else:
        text = yaml.safe_dump(data, sort_keys=False, default_flow_style=None)
    write_text_atomic(path, text)
    return path
