"""The run request: everything that decides a run, built once, frozen and validated.

``lamp run``, ``lamp bench``, ``lamp.solve`` and the warm-up all build a :class:`RunRequest`
(:meth:`RunRequest.build` resolves names and applies the shortcuts) and hand it to
:func:`lamp.pipeline.run`. Validation happens here, before anything is planned or written:
an unknown planner or model, parameters the planner does not read or values out of range,
a scene the planner cannot run (MAPush: another number of robots), shapes too thin for the
planners or the simulator (``lamp.planners.limits``) or robots of a radius the
manipulation model does not serve are each an :class:`~lamp.errors.InputError` naming what
is wrong.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import lamp.pipeline.registry as registry
from lamp.contract.disturb import NO_DISTURBANCE, Disturbances
from lamp.contract.params import apply_overrides, format_value, param_table, value_of
from lamp.errors import InputError
from lamp.fleet.config import PARAMS as FLEET_PARAMS
from lamp.fleet.config import PREFIX, FleetConfig, split_overrides
from lamp.manip.models import check_model, check_robot_radius, model_robot_radius
from lamp.planners.config import PlannerConfig
from lamp.planners.limits import check_scene_limits
from lamp.scene.model import Scene

__all__ = ["RunRequest", "configure", "param_names", "param_rows"]


@dataclass(frozen=True)
class RunRequest:
    """One run: ``scene`` moved by ``planner`` with ``seed``.

    ``model``: the manipulation model, a name (``learned``, ``geometric``), a checkpoint
    path (stored resolved) or a proposer object; ``params``: the planner's parameters
    (None: its defaults, ``PlannerSpec.default_config``); ``fleet``: the concurrent
    schedule's settings (``lamp.fleet.config``; set with the ``fleet_`` parameters of a
    closed-loop planner). The same request gives the same result: budgets are counts,
    wall-clock limits only outer caps.
    """

    scene: Scene
    planner: str = "lazy"
    seed: int = 0
    model: Any = "learned"
    params: PlannerConfig | None = None
    #: What goes wrong during the run (``lamp.contract.disturb``; default: nothing).
    disturbances: Disturbances = NO_DISTURBANCE
    fleet: FleetConfig = FleetConfig()

    def __post_init__(self) -> None:
        spec = registry.get(self.planner)  # InputError naming the planners
        if not isinstance(self.scene, Scene):
            raise InputError(f"scene: a lamp Scene, got {type(self.scene).__name__}")
        if not (isinstance(self.seed, int) and not isinstance(self.seed, bool)):
            raise InputError(f"seed: an integer, got {self.seed!r}")
        if self.params is None:
            object.__setattr__(self, "params", spec.default_config())
        elif not isinstance(self.params, PlannerConfig):
            raise InputError(f"params: a PlannerConfig, got {type(self.params).__name__}")
        if not isinstance(self.fleet, FleetConfig):
            raise InputError(f"fleet: a FleetConfig, got {type(self.fleet).__name__}")
        check_scene_limits(self.scene)
        if not isinstance(self.disturbances, Disturbances):
            raise InputError(f"disturbances: a Disturbances, got {self.disturbances!r}")
        self.disturbances.check_robots(self.scene.n_robots)
        if self.disturbances.active and not spec.closed_loop:
            raise InputError(f"planner {spec.name}: disturbances are supported for the "
                             "closed-loop planners only")
        if self.scene.schedule == "concurrent" and spec.factory is None:
            raise InputError(f"planner {spec.name}: the concurrent schedule runs the "
                             "closed-loop planners only (use --schedule sequential)")
        if self.scene.tasks and spec.factory is None:
            raise InputError(f"planner {spec.name}: a scene with tasks (lifelong) runs the "
                             "closed-loop planners only")
        if spec.check_scene is not None:
            try:
                spec.check_scene(self.scene)
            except InputError:
                raise
            except ValueError as exc:
                raise InputError(str(exc)) from None
        if spec.uses_model:
            if isinstance(self.model, (str, Path)):
                object.__setattr__(self, "model", check_model(self.model))
                check_robot_radius(self.scene, model_robot_radius(self.model))
            else:
                check_robot_radius(self.scene, self.model)

    @property
    def spec(self) -> registry.PlannerSpec:
        return registry.get(self.planner)

    @classmethod
    def build(cls, scene: Scene | str | Path, planner: str = "lazy", seed: int = 0, *,
              model: Any = "learned", params: PlannerConfig | Mapping[str, Any] | None = None,
              planning_limit: float | None = None, max_segments: int | None = None,
              disturbances: Disturbances = NO_DISTURBANCE,
              schedule: str | None = None) -> RunRequest:
        """A request from what a user types: ``scene`` may be a scene file or a built-in
        scene name (``maze-07``); ``params`` a ``PlannerConfig`` or overrides of the
        planner's declared parameters by name (text or numbers); ``planning_limit`` and
        ``max_segments`` set ``planning_time_limit`` and ``max_segments`` (shortcuts every
        planner accepts; MAPush ignores them). With sensing noise, the closed loop's
        ``sensing_sigma`` is the noise's level unless ``params`` sets it. ``schedule``
        (``sequential`` or ``concurrent``) overrides the scene's."""
        if isinstance(scene, (str, Path)):
            from lamp.suites.registry import resolve_scene

            scene = resolve_scene(scene)
        if schedule is not None:
            from lamp.scene.model import SCHEDULES

            if schedule not in SCHEDULES:
                raise InputError(f"schedule: one of {', '.join(SCHEDULES)}, got {schedule!r}")
            scene = dataclasses.replace(scene, schedule=schedule)
        spec = registry.get(planner)
        if isinstance(params, PlannerConfig):
            config, fleet = params, FleetConfig()
        else:
            config, fleet = configure(spec, params or {})
        shortcuts: dict[str, Any] = {}
        if planning_limit is not None:
            shortcuts["planning_time_limit"] = planning_limit
        if max_segments is not None:
            shortcuts["max_segments"] = max_segments
        if (disturbances.sensing_noise and "sensing_sigma" in spec.params
                and not isinstance(params, PlannerConfig)
                and "sensing_sigma" not in dict(params or {})):
            shortcuts["sensing_sigma"] = disturbances.sensing_noise
        if shortcuts:
            config = config.but(**shortcuts)  # validated: InputError
        return cls(scene, planner, seed, model, config, disturbances, fleet)

    def param_values(self) -> dict[str, Any]:
        """The planner's declared parameters and their values (result.json's ``params``),
        the fleet's settings after them for a closed-loop planner."""
        own = {n: value_of(self.params, n) for n in self.spec.params}
        return {**own, **self.fleet.values()} if self.spec.closed_loop else own

    def describe(self) -> str:
        """One line: planner, seed, model and the parameters that differ from the defaults."""
        default = {**{n: value_of(self.spec.default_config(), n) for n in self.spec.params},
                   **FleetConfig().values()}
        changed = [f"{n}={format_value(v)}" for n, v in self.param_values().items()
                   if v != default[n]]
        model = self.model if isinstance(self.model, str) else type(self.model).__name__
        return (f"{self.scene.name}: planner {self.planner}, seed {self.seed}, model {model}"
                + (f", {' '.join(changed)}" if changed else ""))


def configure(spec: registry.PlannerSpec, overrides: Mapping[str, Any]
              ) -> tuple[PlannerConfig, FleetConfig]:
    """``spec``'s defaults with ``overrides`` (name -> value or text) applied: its own
    parameters, and for a closed-loop planner the fleet's (``fleet_`` + a
    ``FleetConfig`` field). ``InputError`` naming the planner and the parameter for a name
    it does not read or a bad value."""
    own, fleet = dict(overrides), FleetConfig()
    if spec.closed_loop:
        own, fleet = split_overrides(own, spec.name)
    return apply_overrides(spec.default_config(), param_names(spec), own, spec.name), fleet


def param_rows(spec: registry.PlannerSpec) -> list[tuple[str, str, str, str]]:
    """(name, default, rule, doc) of every parameter ``--param`` may set for ``spec``
    (``--help-params``): its own, then the fleet's for a closed-loop planner."""
    rows = param_table(spec.default_config(), spec.params)
    if spec.closed_loop:
        rows += [(PREFIX + n, *rest) for n, *rest in param_table(
            FleetConfig(), [f.name for f in dataclasses.fields(FleetConfig)])]
    return rows


def param_names(spec: registry.PlannerSpec) -> tuple[str, ...]:
    """Every parameter ``--param`` may set for ``spec``: its own, then the fleet's for a
    closed-loop planner."""
    return spec.params + (FLEET_PARAMS if spec.closed_loop else ())
