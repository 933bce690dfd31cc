"""The planner registry: one :class:`PlannerSpec` per planner name.

Everything that depends on which planners exist reads it: ``lamp.solve`` and ``lamp run``
(names, factories, loop policies, parameters, default limits), ``lamp bench`` (names, which
planners ``--planning-limit`` applies to). Adding a planner is one :func:`register` call;
:func:`unregister` takes it away again. How the bench report shows a planner (label,
colour, marker, table row, the paper's figures) is ``lamp.bench.presentation``'s, keyed by
the name registered here.

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
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from lamp.contract.params import infos
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

_NAME = re.compile(r"^[a-z][a-z0-9]*(-[a-z0-9]+)*$")


class RunnerFactory(Protocol):
    """Builds the object runner of a planner outside the closed loop for one run of
    ``scene`` (``InputError`` for a scene it cannot run)."""

    def __call__(self, scene: Scene, config: PlannerConfig) -> ObjectRunner: ...



@dataclass(frozen=True, eq=False)
class PlannerSpec:
    """What one planner is: its name, how it is built and run, what it reads.

    Validated on construction (``ValueError`` naming the planner and field): ``name`` is a
    lower-case, dash-separated word; exactly one of ``factory`` (with a ``policy``) and
    ``runner`` is given; ``planning_limit`` is positive.
    """

    name: str
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
    #: The ``PlannerConfig`` fields the planner reads (``--param NAME.FIELD=VALUE``).
    params: tuple[str, ...] = LOOP_PARAMS
    #: Whether the planner uses the manipulation model (``--model``; its robot radius is
    #: then checked against the scene's).
    uses_model: bool = True

    def __post_init__(self) -> None:
        name = self.name
        if not (isinstance(name, str) and _NAME.match(name)):
            raise ValueError(f"planner name: lower-case words joined by '-', got {name!r}")
        if not (isinstance(self.description, str) and self.description.strip()):
            raise ValueError(f"planner {name!r}: description: a non-empty string, "
                             f"got {self.description!r}")
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
        known = infos(PlannerConfig)
        unknown = [p for p in self.params if p not in known]
        if unknown:
            raise ValueError(f"planner {name!r}: params: not PlannerConfig fields: "
                             f"{', '.join(unknown)}")
        object.__setattr__(self, "params", tuple(self.params))

    @property
    def closed_loop(self) -> bool:
        """Whether ``lamp.planners.closed_loop.run_object`` drives this planner."""
        return self.factory is not None

    def default_config(self) -> PlannerConfig:
        """The planner's defaults: ``PlannerConfig`` with its own planning limit."""
        return PlannerConfig.of(planning_time_limit=self.planning_limit)


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


def bench_defaults() -> tuple[str, ...]:
    """What ``lamp bench`` runs without ``--planners`` (``bench_default``), in registration order."""
    return tuple(s.name for s in _SPECS.values() if s.bench_default)


def bench_limited() -> tuple[str, ...]:
    """The planners whose limit ``lamp bench --planning-limit`` sets."""
    return tuple(s.name for s in _SPECS.values() if s.bench_limited)


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
_GCO_POLICY = LoopPolicy(replan_on_drift=False, replan_when_done=True, full_horizon=False,
                         failure_is_final=False)

for _spec in (
    PlannerSpec(
        "lazy", "LAMP-Lazy (default)", factory=_lazy,
        policy=LoopPolicy(replan_on_drift=True, replan_when_done=True, replan_on_stall=True),
        params=_LAZY),
    # The paper gives LAMP-A* 500 s.
    PlannerSpec(
        "astar", "LAMP-A*, open loop", factory=_astar,
        policy=LoopPolicy(replan_on_drift=False, replan_when_done=False),
        planning_limit=500.0, bench_limited=True, params=_ASTAR),
    PlannerSpec(
        "astar-replan", "LAMP-A*, replanning on drift", factory=_astar,
        policy=LoopPolicy(replan_on_drift=True, replan_when_done=True),
        planning_limit=500.0, bench_limited=True, params=_ASTAR),
    PlannerSpec(
        "gco-ori", "GCo with its 0.2 m buffer", factory=_gco(0.2), policy=_GCO_POLICY,
        params=_GCO),
    PlannerSpec(
        "gco-var", "GCo with zero buffer", factory=_gco(0.0), policy=_GCO_POLICY,
        params=_GCO),
    PlannerSpec(
        "mapush", "MAPush-style RL baseline (lattice subgoals + PPO pushing policy)",
        runner=_mapush, check_scene=_mapush_check, bench_default=False, params=(),
        uses_model=False),
):
    register(_spec)
del _spec
