"""What ``POST /tasks`` accepts: ``{"object": k, "goal": [x, y, theta]}``, checked by the
scene format's own rules.

:class:`TaskIntake` checks a posted body as the scene loader checks a ``tasks:`` entry
(``lamp.scene.tasks``: ``object`` an index of the scene's objects, ``goal`` a finite pose
whose footprint lies inside the workspace and overlaps no obstacle): it loads the scene's
own dict with the one task through ``scene_from_dict`` and reports the loader's field,
``tasks[0].goal[1]`` say, as the request's, ``goal[1]``. So a task the service takes is a
task a scene file could hold, and its message is the loader's.
"""

from __future__ import annotations

from typing import Any

from lamp.scene.model import Scene

__all__ = ["ALLOWED_KEYS", "BadTask", "TaskIntake"]

#: The keys of a posted task (``release_s`` is the service's: the time of the post).
ALLOWED_KEYS = ("object", "goal")


class BadTask(ValueError):
    """A posted task is not valid: ``field`` (``object``, ``goal``, ``goal[2]``, ``body``)
    and ``reason``; ``str()`` is ``"<field>: <reason>"``."""

    def __init__(self, field: str, reason: str) -> None:
        super().__init__(f"{field}: {reason}")
        self.field = field
        self.reason = reason


class TaskIntake:
    """Checks posted tasks against ``scene``."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self._base = scene.to_dict()
        self._base.pop("tasks", None)
        self._base["schedule"] = scene.schedule

    def check(self, body: Any) -> tuple[int, tuple[float, float, float]]:
        """The object index and goal of a posted ``body`` (a decoded JSON value);
        :class:`BadTask` naming the field otherwise."""
        from lamp.scene import SceneError, scene_from_dict

        if not isinstance(body, dict):
            raise BadTask("body", f"must be a JSON object {{\"object\": k, \"goal\": "
                          f"[x, y, theta]}}, got {type(body).__name__}")
        for key in body:
            if key not in ALLOWED_KEYS:
                raise BadTask(str(key), f"unknown field (a task has {', '.join(ALLOWED_KEYS)};"
                              " its release time is the time of the post)")
        for key in ALLOWED_KEYS:
            if key not in body:
                raise BadTask(key, "missing")
        try:
            scene = scene_from_dict({**self._base, "tasks": [
                {"object": body["object"], "goal": body["goal"]}]})
        except SceneError as exc:
            field = exc.field or "body"
            field = field.removeprefix("tasks[0]").lstrip(".") or "body"
            reason = (exc.reason or str(exc)).replace("the goal of tasks[0]", "the goal")
            raise BadTask(field, reason) from None
        task = scene.tasks[0]
        return int(task.object), tuple(float(v) for v in task.goal)  # type: ignore[return-value]
