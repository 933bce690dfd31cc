"""The ``lifelong`` family: fleet maps on which tasks keep arriving while the robots work.

10 scenes, ``lifelong-00`` .. ``lifelong-09``. Scene ``i`` is the ``fleet`` family's scene
``BASES[i]`` (its map, robots, objects and their own goals: the first tasks; the smaller
maps of the rooms, aisles, yard and swap kinds, 6-17 m, 2-8 objects, 7-24 robots) plus a
stream of ``N_TASKS`` tasks:

* **Arrivals**: a Poisson process: the gaps between releases are exponential with mean
  ``MEAN_GAP_S`` simulated seconds, the first counted from 0.
* **What each asks**: an object drawn uniformly goes to the other of its two *stations*:
  its start and its goal in the base scene (a load shuttled between where it is picked and
  where it is put). Its first task, its own goal, takes it to its goal; so its later tasks
  alternate: start, goal, start...

Every scene is a pure function of its index (``np.random.default_rng([SUITE_SEED,
STREAM, index])``) and loads (``scene_from_dict``). No two objects share a station, so no
task waits for a place another object will only leave later (an earlier draw sent
objects to any free start or goal: a station left free when drawn could be taken before
the task came up, and the task failed); the fleet family's checks certify each object's
route between its stations with the others standing at theirs.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from lamp.scene.loader import scene_from_dict
from lamp.scene.model import Scene
from lamp.suites.generators import SUITE_SEED
from lamp.suites.registry import suite_dir

__all__ = ["BASES", "MEAN_GAP_S", "NAME", "N_SCENES", "N_TASKS", "STREAM", "generate_scene",
           "scene_name", "task_stream"]

NAME = "lifelong"
#: The fleet scenes the family's maps come from: the 6-17 m ones of every kind but
#: ``after`` (a blocker sent back to its start would shut its load in again).
BASES = ("fleet-00", "fleet-01", "fleet-02", "fleet-05", "fleet-06", "fleet-13", "fleet-17",
         "fleet-18", "fleet-21", "fleet-22")
N_SCENES = len(BASES)
#: Tasks per scene beyond the objects' own goals.
N_TASKS = 20
#: Mean gap (simulated s) between two releases.
MEAN_GAP_S = 8.0
#: The generator's random stream (``lamp.suites.generators.SUITE_SEED`` is the seed).
STREAM = 14


def scene_name(index: int) -> str:
    return f"{NAME}-{index:02d}"


def task_stream(scene: Scene, rng: np.random.Generator, n_tasks: int = N_TASKS,
                mean_gap_s: float = MEAN_GAP_S) -> list[dict[str, Any]]:
    """``n_tasks`` tasks for ``scene``'s objects (module docstring), as scene-file dicts
    in release order."""
    at_goal = [True] * len(scene.objects)  # where each was last sent: its goal first
    tasks: list[dict[str, Any]] = []
    release = 0.0
    for _ in range(n_tasks):
        release += float(rng.exponential(mean_gap_s))
        k = int(rng.integers(len(scene.objects)))
        at_goal[k] = not at_goal[k]
        o = scene.objects[k]
        tasks.append({"object": k, "goal": [float(v) for v in (o.goal if at_goal[k]
                                                               else o.start)],
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
