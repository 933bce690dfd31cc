"""The grid maps of ``benchmarks/grid_maps.py`` (maze, rooms, warehouse): deterministic,
every free cell reachable from every other (no room or corridor cut off), the kinds'
shapes, and read by ``lamp.scene.mapf.load_map`` as scenes' obstacles."""

from __future__ import annotations

import random
import sys
from collections import deque
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))
from grid_maps import maze, rooms, warehouse, write  # noqa: E402

from lamp.scene.mapf import load_map  # noqa: E402


def free_cells(g: list[list[str]]) -> set[tuple[int, int]]:
    return {(y, x) for y, row in enumerate(g) for x, c in enumerate(row) if c == "."}


def connected(g: list[list[str]]) -> bool:
    free = free_cells(g)
    start = next(iter(free))
    seen, todo = {start}, deque([start])
    while todo:
        y, x = todo.popleft()
        for n in ((y + 1, x), (y - 1, x), (y, x + 1), (y, x - 1)):
            if n in free and n not in seen:
                seen.add(n)
                todo.append(n)
    return seen == free


@pytest.mark.parametrize("seed", [0, 3, 11])
def test_maps_are_deterministic_and_connected(seed):
    for make in (lambda r: maze(6, 4, r), lambda r: rooms(4, 9, 2, r)):
        g = make(random.Random(seed))
        assert g == make(random.Random(seed))
        assert connected(g)
    assert connected(warehouse(57, 33))


def test_the_maze_is_perfect_and_the_rooms_have_one_door_per_wall():
    g = maze(6, 4, random.Random(3))
    # a perfect maze of 36 rooms opens exactly 35 walls, each 4 cells
    assert len(free_cells(g)) == 36 * 16 + 35 * 4
    r = rooms(4, 9, 2, random.Random(3))
    assert len(free_cells(r)) == 16 * 81 + 24 * 2  # 24 inner walls, one 2-cell door each
    w = warehouse(57, 33)
    assert sum(row.count("@") for row in w) == 7 * 2 * 39  # 7 rows of 2 x (4 x 10 - 1)


def test_load_map_reads_them(tmp_path):
    write(tmp_path / "maze.map", maze(6, 4, random.Random(3)))
    scene = load_map(tmp_path / "maze.map", 0.5)
    assert scene.workspace == pytest.approx((15.5, 15.5))
    assert scene.obstacles
