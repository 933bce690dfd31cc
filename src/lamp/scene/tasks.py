"""The ``tasks:`` list of a lifelong scene: what it may hold, the order tasks are served
in, and a lower bound on when the last can be done.

A task ``{object: k, goal: [x, y, theta], release_s: t}`` says that from simulated time
``t`` (default 0) object ``k`` must go to ``goal``, after every earlier task of that
object. An object's own ``goal`` is its first task, released at 0. Tasks are numbered
(:func:`numbered`): the objects' own goals first (task ``k`` is object ``k``'s goal), then
the file's tasks in the file's order; an object's tasks are served by release time, then
number.

Rules (checked by :func:`parse_tasks` and ``geometry_checks.check_geometry``, each failure naming
``tasks[i].<field>``): ``object`` an index of the scene's objects; ``goal`` a pose whose
footprint lies inside the workspace and overlaps no obstacle (the scene format's
``EPS``); ``release_s`` a finite number >= 0; no unknown keys.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from lamp.contract.goals import SUCCESS_POSITION_TOL
from lamp.scene.errors import Ctx, is_number, show, value_kind
from lamp.scene.fields import field_items, field_mapping, field_number, field_pose
from lamp.scene.model import Scene, SceneObject, Task

__all__ = ["TASK_KEYS", "chain_lower_bound", "numbered", "parse_tasks", "served_order"]

#: Allowed keys of a task: (required, optional).
TASK_KEYS = (("object", "goal"), ("release_s",))


def parse_tasks(ctx: Ctx, raw: Any, objects: Sequence[SceneObject]) -> tuple[Task, ...]:
    """The ``tasks`` list of a scene file (structure and values; the goals' geometry is
    checked with the scene's, ``geometry_checks.check_geometry``)."""
    tasks = []
    for i, v in enumerate(field_items(ctx, raw, "tasks")):
        field = f"tasks[{i}]"
        d = field_mapping(ctx, v, field, TASK_KEYS)
        k = _index(d["object"])
        if k is None:
            ctx.fail(f"{field}.object", f"must be an object index (an integer), got "
                     f"{show(d['object'])} ({value_kind(d['object'])})")
        if not 0 <= k < len(objects):
            ctx.fail(f"{field}.object", f"no object {k} (the scene has {len(objects)}: "
                     f"0..{len(objects) - 1})")
        goal = field_pose(ctx, d["goal"], f"{field}.goal")
        release = field_number(ctx, d.get("release_s", 0.0), f"{field}.release_s")
        if release < 0.0:
            ctx.fail(f"{field}.release_s", f"must be >= 0 (seconds of simulated time), got "
                     f"{show(d['release_s'])}")
        tasks.append(Task(k, goal, release))
    return tuple(tasks)


def _index(v: Any) -> int | None:
    """``v`` as an integer index (an int, or a float with an integer value), else None."""
    if isinstance(v, bool) or not is_number(v):
        return None
    if isinstance(v, (int, np.integer)):
        return int(v)
    x = float(v)
    return int(x) if math.isfinite(x) and x.is_integer() else None


def numbered(scene: Scene) -> list[Task]:
    """Every task of ``scene`` by number: the objects' own goals (released at 0), then
    ``scene.tasks`` in order."""
    return [Task(k, o.goal, 0.0) for k, o in enumerate(scene.objects)] + list(scene.tasks)


def served_order(scene: Scene) -> list[int]:
    """The task numbers in the order they are released: by release time, then number (so
    an object's tasks come in the order it serves them)."""
    tasks = numbered(scene)
    return sorted(range(len(tasks)), key=lambda i: (tasks[i].release_s, i))


def chain_lower_bound(scene: Scene, first: Sequence[float], later: Sequence[Task]) -> float:
    """A lower bound (s) on when the last task of ``scene`` can be done, given ``first[k]``,
    one on when object ``k``'s own goal can be reached (``bounds.makespan_lower_bound``'s
    ``per_object``), and the ``later`` tasks in the order they are served: a later task
    ``j`` of an object is done no sooner than
    ``max(release_j, done_{j-1}) + max(0, |g_j - g_{j-1}| - 2 tol) / v``, with ``tol``
    the success tolerance and ``v`` the robots' speed. It assumes what the fleet does: an
    object stands (within ``tol``) at its last goal until its next task is released."""
    speed = float(scene.physics.robot_speed)
    done = [float(t) for t in first]
    where = [np.asarray(o.goal[:2], float) for o in scene.objects]
    for t in later:
        gap = math.dist(where[t.object], t.goal[:2]) - 2.0 * SUCCESS_POSITION_TOL
        done[t.object] = max(t.release_s, done[t.object]) + max(0.0, gap) / speed
        where[t.object] = np.asarray(t.goal[:2], float)
    return max(done) if done else 0.0
