"""The planner registry: one :class:`PlannerSpec` per planner name.

Everything that depends on which planners exist reads it: ``lamp.solve`` and ``lamp run``
(names, factories, loop policies, parameters, default limits), ``lamp bench`` (names, which
planners ``--planning-limit`` applies to) and the bench report (row order, labels, colours,
markers, the paper's Table I and II figures). Adding a planner is one :func:`register`
call; :func:`unregister` takes it away again.

A planner is either closed-loop (a ``factory`` that builds an
:class:`~lamp.contract.plan.ObjectPlanner` per object, driven by
``lamp.planners.closed_loop.run_object`` under its ``policy``) or has its own object
runner (``runner``: builds a :class:`~lamp.contract.runner.ObjectRunner` for a scene, as
``mapush`` does). Either way the run pipeline (``lamp.pipeline``) schedules the objects.

This module imports no planner: factories and runners import their module when called,
so reading the registry (the CLI's help, the report) stays cheap.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Protocol

from lamp.contract.plan import LoopPolicy, ObjectPlanner
from lamp.errors import InputError
from lamp.planners.config import (
    ASTAR_PARAMS,
    DEFAULT_PLANNING_LIMIT,
    LATTICE_PARAMS,
    LAZY_PARAMS,
    LOOP_PARAMS,
    VERIFY_PARAMS,
    PlannerConfig,
)

if TYPE_CHECKING:
    from lamp.contract.runner import ObjectRunner
    from lamp.planners.task import ManipulationTask
    from lamp.scene.model import Scene

__all__ = ["PlannerSpec", "RunnerFactory", "get", "names", "register", "specs", "unregister"]

#: Colour of a planner in the bench figures when it does not set its own.
DEFAULT_COLOR = "#7f7f7f"

_NAME = re.compile(r"^[a-z][a-z0-9]*(-[a-z0-9]+)*$")
_COLOR = re.compile(r"^#[0-9a-fA-F]{6}$")
#: Matplotlib marker codes a planner may use.
MARKER_CODES = frozenset(("o", "s", "^", "v", "<", ">", "D", "d", "p", "h", "H", "*", "P",
                          "X", "8", "x", "+"))


class RunnerFactory(Protocol):
    """Builds the object runner of a planner outside the closed loop for one run of
    ``scene`` (``InputError`` for a scene it cannot run)."""

    def __call__(self, scene: Scene, config: PlannerConfig) -> ObjectRunner: ...


def _figures(value: Mapping[str, float], what: str, name: str) -> Mapping[str, float]:
    out = {}
    for family, rate in dict(value).items():
        if not isinstance(family, str) or not family:
            raise ValueError(f"planner {name!r}: {what}: family names must be strings, "
                             f"got {family!r}")
        if not (isinstance(rate, int | float) and 0 <= rate <= 100):
            raise ValueError(f"planner {name!r}: {what}[{family!r}]: a percentage in "
                             f"[0, 100], got {rate!r}")
        out[family] = float(rate)
    return MappingProxyType(out)


@dataclass(frozen=True, eq=False)
class PlannerSpec:
    """What the package knows about one planner.

    Validated on construction (``ValueError`` naming the planner and field): ``name`` is a
    lower-case, dash-separated word; exactly one of ``factory`` (with a ``policy``) and
    ``runner`` is given; ``planning_limit`` is positive; ``color`` is ``#rrggbb``;
    ``marker`` a matplotlib marker code; paper figures are percentages; only LAMP
    planners have Table II figures.
    """

    name: str
    #: Row label in the bench report (e.g. ``LAMP-Lazy``).
    label: str
    #: One line for ``--help`` and ``lamp.solve``'s documentation.
    description: str
    #: Builds the planner for one object (closed-loop planners).
    factory: Callable[[ManipulationTask], ObjectPlanner] | None = None
    #: When the closed loop replans (closed-loop planners).
    policy: LoopPolicy | None = None
    #: Builds the object runner (planners outside the closed loop).
    runner: RunnerFactory | None = None
    #: Refuses a scene the planner cannot run (a ``ValueError`` saying why), before any
    #: output is written; None: every valid scene.
    check_scene: Callable[[Scene], None] | None = None
    #: Default cumulative planning limit per object (s).
    planning_limit: float = DEFAULT_PLANNING_LIMIT
    #: Whether ``lamp bench --planning-limit`` sets this planner's limit.
    bench_limited: bool = False
    #: Whether ``lamp bench`` runs this planner when ``--planners`` is not given.
    bench_default: bool = True
    #: Position in the paper's tables (rows sorted by it, then by name).
    row: int = 100
    color: str = DEFAULT_COLOR
    marker: str = "o"
    #: Table I of the paper: success rate (%) per map family.
    paper_success: Mapping[str, float] = field(default_factory=dict)
    #: Table II of the paper: full-horizon plan rate (%) per map family (LAMP planners).
    paper_full_horizon: Mapping[str, float] = field(default_factory=dict)
    #: A LAMP planner: a row of Table II (full-horizon plan rate).
    lamp: bool = False
    #: The ``PlannerConfig`` fields the planner reads (``--param NAME.FIELD=VALUE``).
    params: tuple[str, ...] = LOOP_PARAMS
    #: Whether the planner uses the manipulation model (``--model``; its robot radius is
    #: then checked against the scene's).
    uses_model: bool = True

    def __post_init__(self) -> None:
        name = self.name
        if not (isinstance(name, str) and _NAME.match(name)):
            raise ValueError(f"planner name: lower-case words joined by '-', got {name!r}")
        for attr in ("label", "description"):
            value = getattr(self, attr)
            if not (isinstance(value, str) and value.strip()):
                raise ValueError(f"planner {name!r}: {attr}: a non-empty string, got {value!r}")
        closed = self.factory is not None
        if closed == (self.runner is not None):
            raise ValueError(f"planner {name!r}: give exactly one of factory (closed loop) "
                             "and runner (whole scene)")
        if closed and not isinstance(self.policy, LoopPolicy):
            raise ValueError(f"planner {name!r}: policy: a LoopPolicy for a closed-loop "
                             f"planner, got {self.policy!r}")
        if not closed and self.policy is not None:
            raise ValueError(f"planner {name!r}: policy: only closed-loop planners have one")
        for attr in ("factory", "runner", "check_scene"):
            value = getattr(self, attr)
            if value is not None and not callable(value):
                raise ValueError(f"planner {name!r}: {attr}: not callable: {value!r}")
        limit = self.planning_limit
        if not (isinstance(limit, int | float) and not isinstance(limit, bool) and limit > 0
                and limit < float("inf")):
            raise ValueError(f"planner {name!r}: planning_limit: positive seconds, got {limit!r}")
        object.__setattr__(self, "planning_limit", float(limit))
        if not (isinstance(self.color, str) and _COLOR.match(self.color)):
            raise ValueError(f"planner {name!r}: color: '#rrggbb', got {self.color!r}")
        if self.marker not in MARKER_CODES:
            raise ValueError(f"planner {name!r}: marker: one of {' '.join(sorted(MARKER_CODES))}, "
                             f"got {self.marker!r}")
        if not isinstance(self.row, int) or isinstance(self.row, bool):
            raise ValueError(f"planner {name!r}: row: an integer, got {self.row!r}")
        object.__setattr__(self, "paper_success",
                           _figures(self.paper_success, "paper_success", name))
        object.__setattr__(self, "paper_full_horizon",
                           _figures(self.paper_full_horizon, "paper_full_horizon", name))
        known = PlannerConfig.__dataclass_fields__
        unknown = [p for p in self.params if p not in known]
        if unknown:
            raise ValueError(f"planner {name!r}: params: not PlannerConfig fields: "
                             f"{', '.join(unknown)}")
        object.__setattr__(self, "params", tuple(self.params))
        if self.paper_full_horizon and not self.lamp:
            raise ValueError(f"planner {name!r}: paper_full_horizon: only LAMP planners "
                             "(lamp=True) are rows of Table II")

    @property
    def closed_loop(self) -> bool:
        """Whether ``lamp.planners.closed_loop.run_object`` drives this planner."""
        return self.factory is not None


    def default_config(self) -> PlannerConfig:
        """The planner's defaults: ``PlannerConfig`` with its own planning limit."""
        return PlannerConfig(planning_time_limit=self.planning_limit)


_SPECS: dict[str, PlannerSpec] = {}


def register(spec: PlannerSpec) -> PlannerSpec:
    """Add ``spec``; ``ValueError`` if its name is taken. Returns ``spec``."""
    if not isinstance(spec, PlannerSpec):
        raise TypeError(f"register takes a PlannerSpec, got {type(spec).__name__}")
    if spec.name in _SPECS:
        raise ValueError(f"planner {spec.name!r} is already registered")
    _SPECS[spec.name] = spec
    return spec


def unregister(name: str) -> PlannerSpec:
    """Remove and return the planner ``name`` (``ValueError`` if there is none)."""
    return _SPECS.pop(get(name).name)


def names() -> tuple[str, ...]:
    """The registered planner names, in registration order (the built-ins first)."""
    return tuple(_SPECS)


def specs() -> tuple[PlannerSpec, ...]:
    """The registered planners, in registration order."""
    return tuple(_SPECS.values())


def get(name: str) -> PlannerSpec:
    """The planner ``name``; else ``ValueError`` with the names and the closest match."""
    spec = _SPECS.get(name) if isinstance(name, str) else None
    if spec is None:
        hint = difflib.get_close_matches(str(name), names(), n=1)
        did = f"; did you mean {hint[0]!r}?" if hint else ""
        raise InputError(f"unknown planner {name!r}; expected one of: {', '.join(names())}{did}")
    return spec


def descriptions() -> dict[str, str]:
    """Planner name -> one-line description, in registration order."""
    return {s.name: s.description for s in _SPECS.values()}


def default_planning_limit(planner: str) -> float:
    """The cumulative planning limit per object that ``planner`` runs under by default."""
    return get(planner).planning_limit


def planning_limit_help() -> str:
    """The per-planner defaults in words, e.g. ``300 s; 500 s for astar, astar-replan``."""
    by_value: dict[float, list[str]] = {}
    for spec in _SPECS.values():
        if spec.planning_limit != DEFAULT_PLANNING_LIMIT:
            by_value.setdefault(spec.planning_limit, []).append(spec.name)
    return f"{DEFAULT_PLANNING_LIMIT:g} s" + "".join(
        f"; {v:g} s for {', '.join(names)}" for v, names in by_value.items())


def table_order() -> tuple[str, ...]:
    """Planner names in the paper's row order (``row``, then name)."""
    return tuple(s.name for s in sorted(_SPECS.values(), key=lambda s: (s.row, s.name)))


def bench_defaults() -> tuple[str, ...]:
    """What ``lamp bench`` runs without ``--planners`` (``bench_default``), in registration order."""
    return tuple(s.name for s in _SPECS.values() if s.bench_default)


def bench_limited() -> tuple[str, ...]:
    """The planners whose limit ``lamp bench --planning-limit`` sets."""
    return tuple(s.name for s in _SPECS.values() if s.bench_limited)


def lamp_planners() -> tuple[str, ...]:
    """The LAMP planners (rows of Table II), in table order."""
    return tuple(n for n in table_order() if _SPECS[n].lamp)


# ----------------------------------------------------------------------------- built-ins
def _lazy(task: ManipulationTask) -> ObjectPlanner:
    from lamp.planners.lazy import LazyPlanner

    return LazyPlanner.from_task(task)


def _astar(task: ManipulationTask) -> ObjectPlanner:
    from lamp.planners.lamp_astar import LampAStar

    return LampAStar.from_task(task)


def _gco(inflation: float) -> Callable[[ManipulationTask], ObjectPlanner]:
    def factory(task: ManipulationTask) -> ObjectPlanner:
        from lamp.baselines.gco import GCoPlanner

        return GCoPlanner.from_task(task, inflation=inflation)

    return factory


def _mapush(scene: Scene, config: PlannerConfig) -> ObjectRunner:
    """MAPush ignores the manipulation model and the planner parameters (docs/mapush.md):
    its limit is simulated time per object."""
    from lamp.baselines.mapush import MapushRunner

    return MapushRunner(scene)


def _mapush_check(scene: Scene) -> None:
    from lamp.baselines.mapush import check_scene

    check_scene(scene)


_LAZY = LOOP_PARAMS + VERIFY_PARAMS + LATTICE_PARAMS + LAZY_PARAMS
_ASTAR = LOOP_PARAMS + VERIFY_PARAMS + LATTICE_PARAMS + ASTAR_PARAMS
_GCO = LOOP_PARAMS + VERIFY_PARAMS
_LAMP_FULL_HORIZON = {"random": 100, "maze": 8, "tilt": 32, "warehouse": 40}
_GCO_POLICY = LoopPolicy(replan_on_drift=False, replan_when_done=True, full_horizon=False,
                         failure_is_final=False)

for _spec in (
    PlannerSpec(
        "lazy", "LAMP-Lazy", "LAMP-Lazy (default)", factory=_lazy,
        policy=LoopPolicy(replan_on_drift=True, replan_when_done=True, replan_on_stall=True),
        row=5, color="#2ca02c", marker="o", lamp=True, params=_LAZY,
        paper_success={"random": 100, "maze": 96, "tilt": 100, "warehouse": 88},
        paper_full_horizon={"random": 100, "maze": 100, "tilt": 100, "warehouse": 100}),
    # The paper's single LAMP-A* row of Table II holds for both LAMP-A* variants (they
    # plan identically before the first segment); the paper gives LAMP-A* 500 s.
    PlannerSpec(
        "astar", "LAMP-A*_ori", "LAMP-A*, open loop", factory=_astar,
        policy=LoopPolicy(replan_on_drift=False, replan_when_done=False),
        planning_limit=500.0, bench_limited=True, row=3, color="#1f77b4", marker="^",
        lamp=True, params=_ASTAR, paper_success={"random": 24, "maze": 0, "tilt": 0, "warehouse": 12},
        paper_full_horizon=_LAMP_FULL_HORIZON),
    PlannerSpec(
        "astar-replan", "LAMP-A*_replan", "LAMP-A*, replanning on drift", factory=_astar,
        policy=LoopPolicy(replan_on_drift=True, replan_when_done=True),
        planning_limit=500.0, bench_limited=True, row=4, color="#9467bd", marker="D",
        lamp=True, params=_ASTAR, paper_success={"random": 88, "maze": 0, "tilt": 8, "warehouse": 0},
        paper_full_horizon=_LAMP_FULL_HORIZON),
    PlannerSpec(
        "gco-ori", "GCo_ori", "GCo with its 0.2 m buffer", factory=_gco(0.2),
        policy=_GCO_POLICY, params=_GCO, row=1, color="#8c564b", marker="o",
        paper_success={"random": 0, "maze": 0, "tilt": 0, "warehouse": 0}),
    PlannerSpec(
        "gco-var", "GCo_var", "GCo with zero buffer", factory=_gco(0.0),
        policy=_GCO_POLICY, params=_GCO, row=2, color="#d62728", marker="s",
        paper_success={"random": 68, "maze": 12, "tilt": 28, "warehouse": 20}),
    PlannerSpec(
        "mapush", "MAPush",
        "MAPush-style RL baseline (lattice subgoals + PPO pushing policy)",
        runner=_mapush, check_scene=_mapush_check, bench_default=False, row=0,
        color="#7f7f7f", marker="o", params=(), uses_model=False,
        paper_success={"random": 8, "maze": 0, "tilt": 0, "warehouse": 0}),
):
    register(_spec)
del _spec
