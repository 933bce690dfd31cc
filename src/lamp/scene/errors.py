"""``SceneError`` and the message helpers every part of the scene loader reports through.

Messages read ``<file>: <field>: <reason>, got <value>``; values are shown abbreviated.
"""

from __future__ import annotations

import numbers
import reprlib
from collections.abc import Mapping, Sequence
from typing import Any, NoReturn

import numpy as np

from lamp.errors import InputError

__all__ = ["Ctx", "SceneError", "fmt_xy", "is_number", "show", "value_kind"]


class SceneError(InputError):
    """A scene file or dict is invalid; the message names the file, the field and the value.

    ``str(err)`` is ``"<file>: <field>: <reason>"``; the parts are also attributes:
    ``path`` (the file as given, ``None`` for a dict validated without ``source``),
    ``field`` (e.g. ``"objects[1].size[0]"``, or ``"(file)"`` for file-level problems) and
    ``reason``.
    """

    def __init__(self, message: str, *, path: str | None = None, field: str | None = None,
                 reason: str | None = None) -> None:
        super().__init__(message)
        self.path = path
        self.field = field
        self.reason = reason

    def __reduce__(self):  # keep the attributes across pickling (worker processes)
        return (_rebuild_scene_error, (str(self), self.path, self.field, self.reason))


def _rebuild_scene_error(message: str, path: str | None, field: str | None,
                         reason: str | None) -> SceneError:
    return SceneError(message, path=path, field=field, reason=reason)


# --------------------------------------------------------------------------- messages

_repr = reprlib.Repr()
_repr.maxstring = 40
_repr.maxother = 40
_repr.maxlist = _repr.maxtuple = _repr.maxdict = 6
_repr.maxlevel = 3


def show(value: Any) -> str:
    """Short, bounded repr of a user value (safe for huge or self-referencing structures)."""
    if isinstance(value, float):
        return repr(value)
    return _repr.repr(value)


def value_kind(value: Any) -> str:
    """Human name of a value's type for 'wrong type' messages."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, str):
        return "string"
    if isinstance(value, Mapping):
        return "mapping"
    if isinstance(value, (list, tuple)):
        return "list"
    if is_number(value):
        return "number"
    return type(value).__name__


def fmt_xy(v: Sequence[float]) -> str:
    return "(" + ", ".join(f"{float(c):.6g}" for c in v) + ")"


class Ctx:
    """Carries the file label so that every check can raise a complete message."""

    def __init__(self, label: str, path: str | None) -> None:
        self.label = label
        self.path = path

    def fail(self, field: str, reason: str) -> NoReturn:
        raise SceneError(f"{self.label}: {field}: {reason}", path=self.path, field=field,
                         reason=reason)


def is_number(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))
