"""RGB frames of a pushing episode, rasterised with NumPy (no OpenGL, no display).

One pixel per ``PIXEL`` (1 cm) of workspace, row 0 at the top (y = H), so a W x H m
workspace gives an image of ``round(H / PIXEL)`` x ``round(W / PIXEL)`` x 3 ``uint8``.
Colours (the ones ``lamp.viz`` uses): obstacles dark grey, robots blue disks, objects in
their own colours, the active object's goal a green outline.
"""

from __future__ import annotations

import numpy as np

from lamp.geometry.robot_space import RobotSpace
from lamp.geometry.shapes import signed_distance
from lamp.scene.model import Scene
from lamp.viz.scene_plot import GOAL_COLOR, OBSTACLE_COLOR, ROBOT_COLOR, object_color

#: Size of one pixel [m].
PIXEL = 0.01
_OUTLINE = 0.015  # width of the goal outline [m]


def _rgb(color: str) -> np.ndarray:
    c = color.lstrip("#")
    return np.array([int(c[i : i + 2], 16) for i in (0, 2, 4)], np.uint8)


class FrameRenderer:
    """Draws frames of one scene; the static background is computed once."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        W, H = scene.workspace
        self.shape = (round(H / PIXEL), round(W / PIXEL))
        ys = (self.shape[0] - 0.5 - np.arange(self.shape[0])) * PIXEL  # row -> y (top = H)
        xs = (np.arange(self.shape[1]) + 0.5) * PIXEL
        self._xs, self._ys = xs, ys
        space = RobotSpace(scene.workspace, scene.obstacles, radius=scene.robot_radius,
                           resolution=PIXEL)
        ny, nx = space.field.shape
        jj = np.clip(np.rint(ys / PIXEL).astype(int), 0, ny - 1)
        ii = np.clip(np.rint(xs / PIXEL).astype(int), 0, nx - 1)
        blocked = space.field[jj[:, None], ii[None, :]] < 0.0
        self._background = np.full((*self.shape, 3), 255, np.uint8)
        self._background[blocked] = _rgb(OBSTACLE_COLOR)

    def _window(self, x: float, y: float, r: float):
        """Pixel index ranges (rows, cols) covering the disk (x, y, r)."""
        c0 = max(int((x - r) / PIXEL), 0)
        c1 = min(int((x + r) / PIXEL) + 2, self.shape[1])
        r0 = max(int((self.scene.workspace[1] - y - r) / PIXEL), 0)
        r1 = min(int((self.scene.workspace[1] - y + r) / PIXEL) + 2, self.shape[0])
        return slice(r0, r1), slice(c0, c1)

    def _paint(self, img, k_shape, pose, color, band: float | None = None) -> None:
        bound = k_shape.bounding_radius + _OUTLINE
        rows, cols = self._window(pose[0], pose[1], bound)
        if rows.start >= rows.stop or cols.start >= cols.stop:
            return
        px, py = np.meshgrid(self._xs[cols] - pose[0], self._ys[rows] - pose[1])
        c, s = np.cos(pose[2]), np.sin(pose[2])
        local = np.stack([c * px + s * py, -s * px + c * py], axis=-1)
        d = signed_distance(k_shape, local)
        mask = (d <= 0) if band is None else (np.abs(d) <= band)
        img[rows, cols][mask] = color

    def frame(
        self,
        robot_positions: np.ndarray,
        object_poses: np.ndarray,
        goal: np.ndarray | None = None,
        active: int | None = None,
    ) -> np.ndarray:
        """(H_px, W_px, 3) uint8 image of the given state; ``goal`` is outlined for object
        ``active``."""
        img = self._background.copy()
        objects = self.scene.objects
        if goal is not None and active is not None:
            self._paint(img, objects[active].shape, goal, _rgb(GOAL_COLOR), band=_OUTLINE / 2)
        for k, (obj, pose) in enumerate(zip(objects, object_poses, strict=True)):
            self._paint(img, obj.shape, pose, _rgb(object_color(k)))
        r = self.scene.robot_radius
        blue = _rgb(ROBOT_COLOR)
        for x, y in robot_positions:
            rows, cols = self._window(x, y, r)
            px, py = np.meshgrid(self._xs[cols] - x, self._ys[rows] - y)
            img[rows, cols][px * px + py * py <= r * r] = blue
        return img

    def frame_of(self, core) -> np.ndarray:
        """The frame of a ``PushCore``'s current state (goal of its active object)."""
        k = min(core.active, core.n_objects - 1)
        return self.frame(core.robot_positions(), core.object_poses(), core.goals[k], k)
