"""How the bench report shows each planner: its row label, its place in the paper's tables,
its colour and marker in the figures, the paper's own numbers for it (Table I and II) and
whether it is a row of Table II.

What a planner *is* (its name, factory, parameters, limits) is the registry's
(``lamp.pipeline.registry``); this module holds one :class:`Presentation` per registered
planner, keyed by the registry name. A name without one (a planner registered without a
:func:`register` here, or one recorded in old results and since removed) is shown under
its own name, grey, after the others: the report of any ``results.jsonl`` still renders.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from lamp.pipeline import registry

__all__ = ["DEFAULT_COLOR", "DEFAULT_MARKER", "MARKER_CODES", "Presentation", "color",
           "label", "marker", "paper_full_horizon", "paper_success", "presentations", "rank",
           "register", "table_ii_planners", "table_order", "unregister"]

#: Colour of a planner in the bench figures when it has no presentation of its own.
DEFAULT_COLOR = "#7f7f7f"
#: Marker of a planner in the bench figures when it has no presentation of its own.
DEFAULT_MARKER = "o"
#: Matplotlib marker codes a planner may use.
MARKER_CODES = frozenset(("o", "s", "^", "v", "<", ">", "D", "d", "p", "h", "H", "*", "P",
                          "X", "8", "x", "+"))
#: The table row of a planner without a presentation: after every other.
UNKNOWN_RANK = 1 << 30

_COLOR = re.compile(r"^#[0-9a-fA-F]{6}$")


def _percentages(value: Mapping[str, float], what: str) -> Mapping[str, float]:
    """``value`` as a read-only family -> percentage map (``ValueError`` naming ``what``)."""
    out = {}
    for family, rate in dict(value).items():
        if not isinstance(family, str) or not family:
            raise ValueError(f"{what}: family names must be strings, got {family!r}")
        if not (isinstance(rate, int | float) and 0 <= rate <= 100):
            raise ValueError(f"{what}[{family!r}]: a percentage in [0, 100], got {rate!r}")
        out[family] = float(rate)
    return MappingProxyType(out)


@dataclass(frozen=True, eq=False)
class Presentation:
    """How the report shows one planner. Validated on construction (``ValueError`` naming
    the field): a non-empty ``label``, an integer ``row``, ``color`` as ``#rrggbb``,
    ``marker`` one of :data:`MARKER_CODES`, paper figures as percentages, Table II figures
    only for a row of Table II."""

    #: Row label in the report's tables and the figures' legends (e.g. ``LAMP-Lazy``).
    label: str
    #: Position in the paper's tables (rows sorted by it, then by name).
    row: int = 100
    color: str = DEFAULT_COLOR
    marker: str = DEFAULT_MARKER
    #: Table I of the paper: success rate (%) per map family.
    paper_success: Mapping[str, float] = field(default_factory=dict)
    #: Table II of the paper: full-horizon plan rate (%) per map family.
    paper_full_horizon: Mapping[str, float] = field(default_factory=dict)
    #: A row of Table II (full-horizon plan rate): the LAMP planners.
    table_ii: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.label, str) and self.label.strip()):
            raise ValueError(f"label: a non-empty string, got {self.label!r}")
        if not isinstance(self.row, int) or isinstance(self.row, bool):
            raise ValueError(f"row: an integer, got {self.row!r}")
        if not (isinstance(self.color, str) and _COLOR.match(self.color)):
            raise ValueError(f"color: '#rrggbb', got {self.color!r}")
        if self.marker not in MARKER_CODES:
            raise ValueError(f"marker: one of {' '.join(sorted(MARKER_CODES))}, "
                             f"got {self.marker!r}")
        object.__setattr__(self, "paper_success",
                           _percentages(self.paper_success, "paper_success"))
        object.__setattr__(self, "paper_full_horizon",
                           _percentages(self.paper_full_horizon, "paper_full_horizon"))
        if self.paper_full_horizon and not self.table_ii:
            raise ValueError("paper_full_horizon: only rows of Table II (table_ii=True) "
                             "have Table II figures")


# The paper's single LAMP-A* row of Table II holds for both LAMP-A* variants (they plan
# identically before the first segment).
_LAMP_ASTAR_FULL_HORIZON = {"random": 100, "maze": 8, "tilt": 32, "warehouse": 40}

_PRESENTATIONS: dict[str, Presentation] = {
    "lazy": Presentation(
        "LAMP-Lazy", row=5, color="#2ca02c", marker="o", table_ii=True,
        paper_success={"random": 100, "maze": 96, "tilt": 100, "warehouse": 88},
        paper_full_horizon={"random": 100, "maze": 100, "tilt": 100, "warehouse": 100}),
    "astar": Presentation(
        "LAMP-A*_ori", row=3, color="#1f77b4", marker="^", table_ii=True,
        paper_success={"random": 24, "maze": 0, "tilt": 0, "warehouse": 12},
        paper_full_horizon=_LAMP_ASTAR_FULL_HORIZON),
    "astar-replan": Presentation(
        "LAMP-A*_replan", row=4, color="#9467bd", marker="D", table_ii=True,
        paper_success={"random": 88, "maze": 0, "tilt": 8, "warehouse": 0},
        paper_full_horizon=_LAMP_ASTAR_FULL_HORIZON),
    "gco-ori": Presentation(
        "GCo_ori", row=1, color="#8c564b", marker="o",
        paper_success={"random": 0, "maze": 0, "tilt": 0, "warehouse": 0}),
    "gco-var": Presentation(
        "GCo_var", row=2, color="#d62728", marker="s",
        paper_success={"random": 68, "maze": 12, "tilt": 28, "warehouse": 20}),
    "mapush": Presentation(
        "MAPush", row=0, color="#7f7f7f", marker="o",
        paper_success={"random": 8, "maze": 0, "tilt": 0, "warehouse": 0}),
}


def register(name: str, presentation: Presentation) -> Presentation:
    """Show the registered planner ``name`` as ``presentation`` (``InputError`` for a name
    the registry does not know, ``ValueError`` if it has one already)."""
    if not isinstance(presentation, Presentation):
        raise TypeError(f"register takes a Presentation, got {type(presentation).__name__}")
    name = registry.get(name).name
    if name in _PRESENTATIONS:
        raise ValueError(f"planner {name!r} has a presentation already")
    _PRESENTATIONS[name] = presentation
    return presentation


def unregister(name: str) -> Presentation:
    """Remove and return the presentation of ``name`` (``KeyError`` if it has none)."""
    return _PRESENTATIONS.pop(name)


def presentations() -> Mapping[str, Presentation]:
    """Planner name -> its presentation (read-only)."""
    return MappingProxyType(_PRESENTATIONS)


def label(planner: str) -> str:
    """The planner's row label (its name when it has no presentation)."""
    p = _PRESENTATIONS.get(planner)
    return p.label if p is not None else planner


def color(planner: str) -> str:
    """The planner's colour in the figures (:data:`DEFAULT_COLOR` when it has none)."""
    p = _PRESENTATIONS.get(planner)
    return p.color if p is not None else DEFAULT_COLOR


def marker(planner: str) -> str:
    """The planner's marker in the figures (:data:`DEFAULT_MARKER` when it has none)."""
    p = _PRESENTATIONS.get(planner)
    return p.marker if p is not None else DEFAULT_MARKER


def rank(planner: str) -> int:
    """The planner's row in the paper's tables (:data:`UNKNOWN_RANK`, last, when it has
    no presentation)."""
    p = _PRESENTATIONS.get(planner)
    return p.row if p is not None else UNKNOWN_RANK


def paper_success(planner: str) -> dict[str, float]:
    """Table I of the paper (success rate, %) per family for ``planner`` ({} if none)."""
    p = _PRESENTATIONS.get(planner)
    return dict(p.paper_success) if p is not None else {}


def paper_full_horizon(planner: str) -> dict[str, float]:
    """Table II of the paper (full-horizon plan rate, %) per family ({} if none)."""
    p = _PRESENTATIONS.get(planner)
    return dict(p.paper_full_horizon) if p is not None else {}


def table_order() -> tuple[str, ...]:
    """The planners with a presentation in the paper's row order (``row``, then name)."""
    return tuple(sorted(_PRESENTATIONS, key=lambda n: (_PRESENTATIONS[n].row, n)))


def table_ii_planners() -> tuple[str, ...]:
    """The rows of Table II (the LAMP planners), in table order."""
    return tuple(n for n in table_order() if _PRESENTATIONS[n].table_ii)
