"""The ``lifelong`` family: fleet maps on which tasks keep arriving while the robots work.

12 scenes, ``lifelong-00`` .. ``lifelong-11``. Scene ``i`` is the ``fleet`` family's scene
``BASES[i]`` (its map, robots, objects and their own goals: the first tasks; the smaller
maps of every kind, 6-17 m, 2-8 objects, 7-24 robots) plus a stream of ``N_TASKS`` tasks:

* **Arrivals**: a Poisson process: the gaps between releases are exponential with mean
  ``MEAN_GAP_S`` simulated seconds, the first counted from 0.
* **What each asks**: an object drawn uniformly, to a *station* drawn uniformly among
  those it may go to. The stations are the base scene's object starts and goals (each
  clear of the obstacles and apart from the others by the fleet family's gap); object
  ``k`` may go to a station whose footprint, for ``k``'s shape, lies inside the map,
  ``STATION_CLEARANCE`` from every obstacle, and ``STATION_CLEARANCE`` from the footprint
  of every other object at the station it was last sent to (so a stream never sends two
  objects to one place), and which is not where ``k`` was last sent. An object with no
  such station is redrawn.

Every scene is a pure function of its index (``np.random.default_rng([SUITE_SEED,
STREAM, index])``) and loads (``scene_from_dict``: every task's goal inside the map and
clear of the obstacles). What the stream cannot rule out: an object still standing at a
station it has not been sent away from yet when another is sent there (its task waits
for it to leave), and free robots standing on a station (they join the team that needs
the way, ``fleet.teams.near_way``).
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import shapely

from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene.loader import scene_from_dict
from lamp.scene.model import Scene
from lamp.suites.generators import SUITE_SEED
from lamp.suites.registry import suite_dir

__all__ = ["BASES", "MEAN_GAP_S", "NAME", "N_SCENES", "N_TASKS", "STATION_CLEARANCE",
           "STREAM", "generate_scene", "scene_name", "task_stream"]

NAME = "lifelong"
#: The fleet scenes the family's maps come from (the 6-17 m ones of every kind).
BASES = ("fleet-00", "fleet-01", "fleet-02", "fleet-05", "fleet-06", "fleet-09", "fleet-13",
         "fleet-14", "fleet-17", "fleet-18", "fleet-21", "fleet-22")
N_SCENES = len(BASES)
#: Tasks per scene beyond the objects' own goals.
N_TASKS = 20
#: Mean gap (simulated s) between two releases.
MEAN_GAP_S = 8.0
#: Clearance (m) of a station from the obstacles and from the other objects' stations.
STATION_CLEARANCE = 0.1
#: The generator's random stream (``lamp.suites.generators.SUITE_SEED`` is the seed).
STREAM = 14


def scene_name(index: int) -> str:
    return f"{NAME}-{index:02d}"


def _fits(shape: Any, pose: np.ndarray, workspace: tuple[float, float],
          walls: shapely.Geometry | None) -> bool:
    """Whether ``shape`` at ``pose`` lies inside the map and ``STATION_CLEARANCE`` from
    the obstacles (``walls``)."""
    foot = to_shapely(shape, pose)
    x0, y0, x1, y1 = foot.bounds
    inside = x0 >= 0.0 and y0 >= 0.0 and x1 <= workspace[0] and y1 <= workspace[1]
    return inside and (walls is None or foot.distance(walls) >= STATION_CLEARANCE)


def task_stream(scene: Scene, rng: np.random.Generator, n_tasks: int = N_TASKS,
                mean_gap_s: float = MEAN_GAP_S) -> list[dict[str, Any]]:
    """``n_tasks`` tasks for ``scene``'s objects (module docstring), as scene-file dicts
    in release order."""
    stations = np.concatenate([scene.object_starts(), scene.object_goals()])
    walls = (shapely.union_all([obstacle_geometry(o) for o in scene.obstacles])
             if scene.obstacles else None)
    fits = [[_fits(o.shape, s, scene.workspace, walls) for s in stations]
            for o in scene.objects]
    sent = [len(scene.objects) + k for k in range(len(scene.objects))]  # own goals
    tasks: list[dict[str, Any]] = []
    release = 0.0
    while len(tasks) < n_tasks:
        release += float(rng.exponential(mean_gap_s))
        for _ in range(100):  # an object with somewhere to go
            k = int(rng.integers(len(scene.objects)))
            others = [to_shapely(scene.objects[j].shape, stations[sent[j]])
                      for j in range(len(scene.objects)) if j != k]
            free = [s for s in range(len(stations)) if fits[k][s] and s != sent[k] and all(
                to_shapely(scene.objects[k].shape, stations[s]).distance(g)
                >= STATION_CLEARANCE for g in others)]
            if free:
                break
        else:
            raise RuntimeError(f"{scene.name}: no object has a free station")
        s = free[int(rng.integers(len(free)))]
        sent[k] = s
        tasks.append({"object": k, "goal": [round(float(v), 4) for v in stations[s]],
                      "release_s": round(release, 3)})
    return tasks


def generate_scene(index: int) -> dict[str, Any]:
    """The scene-file dict of ``lifelong-<index>`` (module docstring)."""
    if not 0 <= index < N_SCENES:
        raise ValueError(f"lifelong scene index in 0..{N_SCENES - 1}, got {index}")
    import yaml

    base_name = BASES[index]
    base = yaml.safe_load((suite_dir("fleet") / f"{base_name}.yaml").read_text("utf-8"))
    scene = scene_from_dict(copy.deepcopy(base), source=base_name)
    rng = np.random.default_rng([SUITE_SEED, STREAM, index])
    d = dict(base, name=scene_name(index), schedule="concurrent",
             tasks=task_stream(scene, rng))
    scene_from_dict(copy.deepcopy(d))  # it loads: SceneError otherwise
    return d
