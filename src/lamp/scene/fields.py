"""The leaf checks of the scene format: numbers, lists, vectors, angles, poses, strings and
mappings read from a scene file, each failing through ``Ctx`` with a message that names
the field and the value (``lamp.scene.errors``). ``lamp.scene.loader`` and
``lamp.scene.tasks`` read every field through these."""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from typing import Any

from lamp.scene.errors import Ctx, is_number, show, value_kind

__all__ = ["MAX_ANGLE", "field_angle", "field_items", "field_mapping", "field_number",
           "field_pose", "field_string", "field_vector"]

#: Largest |angle| (rad) of a pose or an obstacle: float64 holds such an angle to 1e-10 rad;
#: far beyond it a heading is rounding noise (at 1e308 every digit is) and the simulator's
#: hinge joints go unstable (MuJoCo's limit on a joint's value is 1e10).
MAX_ANGLE = 1e6


def field_number(ctx: Ctx, v: Any, field: str, *, positive: bool = False) -> float:
    """A finite real number (not a bool, not a string); ``positive`` demands > 0."""
    if not is_number(v):
        ctx.fail(field, f"must be a number, got {show(v)} ({value_kind(v)})")
    try:
        x = float(v)
    except (OverflowError, ValueError, TypeError):
        ctx.fail(field, f"must be a finite number, got {show(v)}")
    if not math.isfinite(x):
        ctx.fail(field, f"must be a finite number, got {show(v)}")
    if positive and x <= 0.0:
        ctx.fail(field, f"must be > 0, got {show(v)}")
    return x


def field_items(ctx: Ctx, v: Any, field: str, *, min_len: int = 0, what: str = "items") -> list:
    if not isinstance(v, (list, tuple)):
        ctx.fail(field, f"must be a list, got {show(v)} ({value_kind(v)})")
    if len(v) < min_len:
        ctx.fail(field, f"must have at least {min_len} {what}, got {len(v)}")
    return list(v)


def field_vector(ctx: Ctx, v: Any, field: str, n: int, names: str, **kw: Any) -> tuple[float, ...]:
    """A list of exactly ``n`` finite numbers, e.g. ``[x, y]`` (``names`` says which)."""
    if not isinstance(v, (list, tuple)) or len(v) != n:
        ctx.fail(field, f"must be a list of {n} numbers [{names}], got {show(v)}")
    return tuple(field_number(ctx, c, f"{field}[{i}]", **kw) for i, c in enumerate(v))


def field_angle(ctx: Ctx, v: Any, field: str) -> float:
    """A finite angle of at most ``MAX_ANGLE`` in magnitude."""
    a = field_number(ctx, v, field)
    if abs(a) > MAX_ANGLE:
        ctx.fail(field, f"an angle of at most {MAX_ANGLE:g} rad in magnitude (radians, "
                 f"counter-clockwise), got {show(v)}")
    return a


def field_pose(ctx: Ctx, v: Any, field: str) -> tuple[float, float, float]:
    """``[x, y, theta]`` with ``theta`` an angle (``_angle``)."""
    x, y, _ = field_vector(ctx, v, field, 3, "x, y, theta")
    return x, y, field_angle(ctx, v[2], f"{field}[2]")


def field_string(ctx: Ctx, v: Any, field: str) -> str:
    if not isinstance(v, str):
        ctx.fail(field, f"must be a string (quote it in YAML), got {show(v)} ({value_kind(v)})")
    return v


def field_mapping(
    ctx: Ctx, v: Any, field: str, keys: tuple[tuple[str, ...], tuple[str, ...]]
) -> dict[str, Any]:
    """Check that ``v`` is a mapping with all required keys and no unknown ones.

    Optional keys whose value is ``None`` are dropped (null means "use the default").
    """
    if not isinstance(v, Mapping):
        ctx.fail(field or "(top level)", f"must be a mapping, got {show(v)} ({value_kind(v)})")
    required, optional = keys
    allowed = required + optional
    prefix = f"{field}." if field else ""
    for k in v:
        if k not in allowed:
            hint = difflib.get_close_matches(str(k), allowed, n=1)
            did = f"; did you mean {hint[0]!r}?" if hint else ""
            ctx.fail(
                f"{prefix}{show(k) if not isinstance(k, str) else k}",
                f"unknown key (allowed here: {', '.join(allowed)}){did}",
            )
    for k in required:
        if k not in v:
            ctx.fail(f"{prefix}{k}", "missing required field")
    return {k: val for k, val in v.items() if not (k in optional and val is None)}
