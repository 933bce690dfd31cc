"""Parameters declared per planner (as OMPL planners declare theirs): typed, documented,
validated, and settable by name from the CLI and the bench.

A parameter set is a frozen dataclass whose fields are declared with :func:`param`: a
default, one line of documentation and the range of valid values. :func:`check_fields`
validates every field of such an instance (call it from ``__post_init__``); a planner names
the fields it reads (``PlannerSpec.params``), and :func:`apply_overrides` sets some of them
from ``NAME=VALUE`` text, refusing a name the planner does not read. A set may also be
made of groups, each a parameter set of its own owner (fields declared with
:func:`group`): its parameters are its groups', by their names (unique across groups),
read with :func:`value_of` and set with :func:`replaced`.

Guarantees (tested): every declared field is validated on construction (an
:class:`~lamp.errors.InputError` naming the class, the field, the rule and the value);
:func:`parse_value` reads back what :func:`format_value` writes; an override of a name the
planner does not declare, or with a value of the wrong type, is refused by name.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from lamp.errors import InputError

__all__ = ["ParamInfo", "apply_overrides", "check_fields", "format_value", "group", "param",
           "param_table", "parse_assignments", "parse_value", "replaced", "value_of"]

_KEY = "lamp.param"
_GROUP = "lamp.param-group"


@dataclass(frozen=True)
class ParamInfo:
    """One declared parameter: its type (``int`` or ``float``), whether ``None`` is allowed
    (it then means "derived", as the docs say), its lower bound, and its documentation."""

    name: str
    kind: type
    default: Any
    doc: str
    low: float | None = None
    #: The bound itself is excluded (``> low``) rather than included (``>= low``).
    low_open: bool = False
    optional: bool = False
    #: Infinity is allowed (a limit that never fires).
    unbounded: bool = False

    def rule(self) -> str:
        what = ("an integer" if self.kind is int else
                "a number (inf allowed)" if self.unbounded else "a finite number")
        if self.low is not None:
            what += f" {'>' if self.low_open else '>='} {self.low:g}"
        return what + (" or none" if self.optional else "")

    def check(self, owner: str, value: Any) -> Any:
        """``value`` (floats for a float parameter) if valid, else ``InputError``."""
        if value is None and self.optional:
            return None
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        if self.kind is int:
            ok = ok and isinstance(value, int)
        ok = ok and (math.isfinite(value) or (self.unbounded and value == math.inf))
        if ok and self.low is not None:
            ok = value > self.low if self.low_open else value >= self.low
        if not ok:
            raise InputError(f"{owner}.{self.name}: {self.rule()}, got {value!r}")
        return float(value) if self.kind is float else int(value)


def param(default: Any, doc: str, *, kind: type | None = None, low: float | None = None,
          low_open: bool = False, optional: bool = False, unbounded: bool = False) -> Any:
    """A dataclass field declared as a parameter (see the module docstring); ``kind``
    defaults to the type of ``default``."""
    kind = kind or type(default)
    if kind not in (int, float):
        raise TypeError(f"param: int or float parameters only, got {kind.__name__}")
    info = dict(kind=kind, doc=" ".join(doc.split()), low=low, low_open=low_open,
                optional=optional, unbounded=unbounded)
    return dataclasses.field(default=default, metadata={_KEY: info})


def group(cls: type) -> Any:
    """A dataclass field holding a group of parameters: an instance of the parameter-set
    class ``cls`` (default: its defaults)."""
    return dataclasses.field(default_factory=cls, metadata={_GROUP: cls})


def _owners(cls_or_obj: Any) -> dict[str, str | None]:
    """Each declared parameter's group field (None: declared on the set itself)."""
    out: dict[str, str | None] = {}
    for f in dataclasses.fields(cls_or_obj):
        if _KEY in f.metadata:
            out[f.name] = None
        elif _GROUP in f.metadata:
            for name in infos(f.metadata[_GROUP]):
                if name in out:
                    raise TypeError(f"parameter {name!r} declared twice")
                out[name] = f.name
    return out


def infos(cls_or_obj: Any) -> dict[str, ParamInfo]:
    """The declared parameters of a parameter-set class (or instance), in field order,
    those of its groups included."""
    out = {}
    for f in dataclasses.fields(cls_or_obj):
        meta = f.metadata.get(_KEY)
        if meta is not None:
            out[f.name] = ParamInfo(f.name, default=f.default, **meta)
        elif _GROUP in f.metadata:
            out.update(infos(f.metadata[_GROUP]))
    return out


def value_of(params: Any, name: str) -> Any:
    """The value of parameter ``name`` of ``params`` (in its group, if it has one)."""
    owner = _owners(params)[name]
    return getattr(params if owner is None else getattr(params, owner), name)


def replaced(params: Any, **changes: Any) -> Any:
    """``params`` with ``changes`` (parameter name -> value) applied, each in the group
    that declares it; validated like a new set (``InputError``); ``TypeError`` for a
    name it does not declare."""
    owners = _owners(params)
    unknown = [n for n in changes if n not in owners]
    if unknown:
        raise TypeError(f"{type(params).__name__}: no parameter {', '.join(unknown)}")
    own = {n: v for n, v in changes.items() if owners[n] is None}
    for g in dict.fromkeys(o for n in changes if (o := owners[n]) is not None):
        own[g] = dataclasses.replace(getattr(params, g), **{
            n: v for n, v in changes.items() if owners[n] == g})
    return dataclasses.replace(params, **own) if own else params


def check_fields(obj: Any) -> None:
    """Validate every declared field of ``obj`` (floats stored as floats); call it from
    ``__post_init__`` of a frozen dataclass."""
    owner = type(obj).__name__
    for name, info in infos(obj).items():
        object.__setattr__(obj, name, info.check(owner, getattr(obj, name)))


def format_value(value: Any) -> str:
    return "none" if value is None else f"{value:g}" if isinstance(value, float) else str(value)


def parse_value(info: ParamInfo, text: str, owner: str = "") -> Any:
    """``text`` read as a value of ``info`` (``none`` for an optional one); ``InputError``
    naming the parameter otherwise."""
    where = f"{owner}.{info.name}" if owner else info.name
    t = str(text).strip()
    if info.optional and t.lower() in ("none", "null", ""):
        return None
    try:
        value: Any = int(t) if info.kind is int else float(t)
        return info.check(owner or "param", value)
    except ValueError:  # InputError included: name the text as typed
        raise InputError(f"{where}: {info.rule()}, got {text!r}") from None


def parse_assignments(items: Iterable[str], option: str = "--param") -> list[tuple[str, str, str]]:
    """``PLANNER.NAME=VALUE`` texts as (planner, name, value) triples, in order;
    ``InputError`` naming the option and the text for any other shape."""
    out = []
    for item in items:
        key, eq, value = str(item).partition("=")
        planner, dot, name = key.strip().partition(".")
        if not (eq and dot and planner and name):
            raise InputError(f"{option}: expected PLANNER.NAME=VALUE (for example "
                             f"lazy.max_plan_iterations=400), got {item!r}")
        out.append((planner, name.strip(), value.strip()))
    return out


def apply_overrides(params: Any, declared: Iterable[str], overrides: Mapping[str, Any],
                    owner: str) -> Any:
    """``params`` (a frozen parameter set) with ``overrides`` applied; values may be text
    (parsed) or numbers. Every name must be one of ``declared`` (the parameters the planner
    ``owner`` reads): ``InputError`` naming it and listing them otherwise."""
    declared = tuple(declared)
    table = infos(params)
    changes = {}
    for name, value in overrides.items():
        if name not in declared:
            raise InputError(f"planner {owner}: no parameter {name!r}; it reads: "
                             f"{', '.join(declared) or '(none)'}")
        info = table[name]
        changes[name] = (parse_value(info, value, owner) if isinstance(value, str)
                         else info.check(owner, value))
    return replaced(params, **changes) if changes else params


def param_table(params: Any, declared: Iterable[str]) -> list[tuple[str, str, str, str]]:
    """(name, value, rule, doc) of each declared parameter, for ``--help-params``."""
    table = infos(params)
    return [(n, format_value(value_of(params, n)), table[n].rule(), table[n].doc)
            for n in declared]
