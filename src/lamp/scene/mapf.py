"""Grid maps of the Moving AI MAPF benchmark as scenes, and random fleet instances on them.

A map file (octile format: ``type``, ``height``, ``width``, ``map`` header lines, then one
character per cell, row 0 at the top) becomes a :class:`~lamp.scene.model.Scene` whose
workspace is ``width * cell`` by ``height * cell`` metres and whose obstacles are the
blocked cells, merged into as few axis-aligned rectangles as a greedy row-then-column
merge finds (the union is exactly the blocked cells; ``random-64-64-20`` has 819 blocked
cells and becomes about 600 rectangles, ``den520d`` far fewer than its 38,000 cells).

Free cells: ``.``, ``G`` and ``S``; blocked: ``@``, ``O``, ``T``, ``W``. Any other
character is refused by name (file, row, column).

Guarantees (tested): every point of a blocked cell is inside an obstacle rectangle; the
centre of every free cell is at distance >= ``cell / 2`` from every obstacle and from the
border; :func:`random_instance` returns distinct free cell centres.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lamp.errors import InputError
from lamp.scene.loader import load_scene
from lamp.scene.model import Obstacle, Rectangle, Scene

__all__ = ["GridMap", "load_grid_map", "load_map", "random_instance"]

_FREE = frozenset(".GS")
_BLOCKED = frozenset("@OTW")


@dataclass(frozen=True)
class GridMap:
    """A MAPF grid map: ``blocked[row, col]`` (row 0 at the top) and its scene."""

    name: str
    blocked: np.ndarray
    cell: float
    scene: Scene

    def cell_centres(self, free: bool = True) -> np.ndarray:
        """(K, 2) centres of the free (or blocked) cells in metres, row-major order."""
        rows, cols = np.nonzero(~self.blocked if free else self.blocked)
        H = self.blocked.shape[0]
        return np.stack([(cols + 0.5) * self.cell, (H - 1 - rows + 0.5) * self.cell], 1)


def _parse(path: Path) -> np.ndarray:
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise InputError(f"{path}: cannot read the map file: {exc.strerror}") from exc
    head: dict[str, str] = {}
    k = 0
    while k < len(lines) and lines[k].strip() != "map":
        parts = lines[k].split()
        if len(parts) == 2:
            head[parts[0]] = parts[1]
        k += 1
    try:
        h, w = int(head["height"]), int(head["width"])
    except (KeyError, ValueError) as exc:
        raise InputError(f"{path}: header needs 'height N' and 'width N' lines before "
                         "'map'") from exc
    rows = lines[k + 1 : k + 1 + h]
    if k >= len(lines) or len(rows) != h or h < 1 or w < 1:
        raise InputError(f"{path}: expected {h} map rows of {w} cells after 'map'")
    blocked = np.zeros((h, w), dtype=bool)
    for r, row in enumerate(rows):
        if len(row) < w:
            raise InputError(f"{path}: map row {r} has {len(row)} cells, expected {w}")
        for c, ch in enumerate(row[:w]):
            if ch in _BLOCKED:
                blocked[r, c] = True
            elif ch not in _FREE:
                raise InputError(f"{path}: row {r}, column {c}: unknown cell {ch!r} "
                                 "(free: . G S; blocked: @ O T W)")
    return blocked


def _rectangles(blocked: np.ndarray) -> list[tuple[int, int, int, int]]:
    """(row0, col0, rows, cols) rectangles whose union is exactly the blocked cells:
    horizontal runs, each grown downwards while the rows below repeat the run."""
    h, w = blocked.shape
    used = np.zeros_like(blocked)
    out: list[tuple[int, int, int, int]] = []
    for r in range(h):
        c = 0
        while c < w:
            if not blocked[r, c] or used[r, c]:
                c += 1
                continue
            c1 = c
            while c1 < w and blocked[r, c1] and not used[r, c1]:
                c1 += 1
            r1 = r + 1
            while r1 < h and blocked[r1, c:c1].all() and not used[r1, c:c1].any():
                r1 += 1
            used[r:r1, c:c1] = True
            out.append((r, c, r1 - r, c1 - c))
            c = c1
    return out


def load_grid_map(path: str | Path, cell: float = 0.15, robot_radius: float = 0.05) -> GridMap:
    """The map at ``path`` with square cells of side ``cell`` metres, as a scene with one
    robot at the first free cell centre and no objects (set robots per instance)."""
    p = Path(path)
    if not (np.isfinite(cell) and cell > 0):
        raise InputError(f"cell must be a positive number of metres, got {cell!r}")
    blocked = _parse(p)
    h, w = blocked.shape
    if blocked.all():
        raise InputError(f"{p}: every cell is blocked")
    obstacles = tuple(
        Obstacle(Rectangle((cols * cell, rows * cell)),
                 ((c0 + cols / 2) * cell, (h - r0 - rows / 2) * cell, 0.0))
        for r0, c0, rows, cols in _rectangles(blocked))
    r, c = (int(v) for v in np.argwhere(~blocked)[0])
    first = ((c + 0.5) * cell, (h - 1 - r + 0.5) * cell)
    scene = Scene(p.stem, (w * cell, h * cell), (first,), (),
                  obstacles, robot_radius, source=str(p))
    return GridMap(p.stem, blocked, float(cell), scene)


def load_map(path: str | Path, cell: float) -> Scene:
    """The map at ``path`` as a scene: a Moving AI grid map (``.map``, cells of ``cell``
    m, :func:`load_grid_map`) or a scene file (:func:`~lamp.scene.loader.load_scene`); ``InputError``
    names what is wrong."""
    if Path(path).suffix.lower() == ".map":
        return load_grid_map(path, cell).scene
    return load_scene(path)


def random_instance(gm: GridMap, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(starts, goals), each (n, 2): distinct free cell centres drawn uniformly with
    ``seed`` (starts distinct from each other, goals distinct from each other)."""
    free = gm.cell_centres()
    if not 1 <= n <= len(free):
        raise InputError(f"{gm.name}: {n} robots do not fit on {len(free)} free cells")
    rng = np.random.default_rng(seed)
    s = rng.choice(len(free), n, replace=False)
    g = rng.choice(len(free), n, replace=False)
    return free[s].copy(), free[g].copy()
