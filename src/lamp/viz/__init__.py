"""Pictures and animations of scenes and runs (matplotlib, imported only when drawing).

- ``draw_scene(ax, scene, object_poses, robot_positions, highlight_object=...)`` and
  ``save_scene_png(scene, path, dpi)``: ``lamp.viz.scene_plot``;
- ``Frame`` and ``write_animation(scene, frames, path, fps, max_frames)``:
  ``lamp.viz.animation``;
- ``render(recording, path, ...)``: recorded runs as GIF, MP4, PNG (``lamp.viz.replay``)
  or the self-contained HTML viewer (``lamp.viz.replay_html``).
"""

from lamp.viz.animation import AnimationStats, Frame, write_animation
from lamp.viz.scene_plot import ScenePainter, draw_scene, save_scene_png

__all__ = [
    "AnimationStats",
    "Frame",
    "ScenePainter",
    "draw_scene",
    "save_scene_png",
    "write_animation",
]
