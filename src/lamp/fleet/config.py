"""The fleet schedule's settings: :class:`FleetConfig` and the constants it defaults to.

Every setting of the concurrent schedule is owned here. They are set like a planner's
parameters, with the ``fleet_`` prefix (``lamp run --param lazy.fleet_pass_margin=2``):
:func:`split_overrides` takes them out of a planner's overrides, and ``PARAMS`` lists
their public names (each ``fleet_`` + a field of :class:`FleetConfig`). Validated on
construction like every parameter set (``lamp.contract.params``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from lamp.contract.params import apply_overrides, check_fields, param
from lamp.errors import InputError

__all__ = ["CLAIM_NEAR", "MIN_SPACE_CACHE_MB", "PARAMS",
           "PASS_MARGIN", "PLAN_NEAR", "PREFIX", "REJOIN_SLACK", "REPLAN_NEAR", "SPACE_CACHE_MB",
           "FleetConfig", "split_overrides"]

#: The near part of a claim (``regions.claims``): the footprints along this much (m) of an
#: object's planned travel, which even a plan that only crosses its claim keeps out of
#: (``cross_waiting``'s default; measured in ``docs/fleet.md``, Coordination).
CLAIM_NEAR = 2.0
#: How far ahead (m of travel) a plan must pass each point of a higher-ranked object's
#: claim to go through it (``admission.passes_ahead``; ``pass_margin``'s default).
PASS_MARGIN = 1.0
#: An object's loop plans around the other teams' robots standing this near (m) to its
#: own (``plan_near``'s default, inf: all of them). 5 m shortens some runs and lengthens
#: others, and loses one of the 15 held-out scenes (``docs/fleet.md``, What each object
#: gets).
PLAN_NEAR = math.inf
#: After its planner found no plan, an object's loops plan around only the other teams'
#: robots standing this near (m) to its own (``replan_near``'s default): a long haul whose
#: every plan around all of them used up its search budget then plans in a few seconds
#: (``docs/fleet.md``, What each object gets).
REPLAN_NEAR = 5.0
#: The rows a segment's rejoins may insert, as a share of its planned rows; past it the
#: segment ends (``segments.Segment.rejoin``; ``rejoin_slack``'s default). A push jammed
#: on a shelf corner otherwise runs event after event without ending.
REJOIN_SLACK = 1.0
#: Robot-space cache (MB) the objects moving at once share (each object's
#: ``space_cache_mb`` is at most its part, at least ``MIN_SPACE_CACHE_MB``): memory stays
#: near one sequential run's up to 48 objects moving at once.
SPACE_CACHE_MB = 192.0
MIN_SPACE_CACHE_MB = 4.0
#: The prefix of the fleet's settings among a planner's parameters.
PREFIX = "fleet_"


@dataclass(frozen=True)
class FleetConfig:
    """The concurrent schedule's settings (module docstring); the defaults are the
    schedule's measured defaults."""

    park_clear: float = param(0.0, "Concurrent schedule: a team whose object is placed "
                              "first moves this far (m) from what the other objects still "
                              "need; 0: it stays.", low=0.0)
    reinforce_reach: float = param(0.0, "Concurrent schedule: when no object waits to "
                                   "start, free robots within this distance (m) of a moving "
                                   "object whose team has room join it; 0: they stay free.",
                                   low=0.0)
    cross_near: float = param(0.0, "Concurrent schedule: a plan that only crosses a "
                              "higher-ranked object's way heeds just the part of its claim "
                              "within this much (m) of its planned travel; 0: the whole "
                              "claim.", low=0.0)
    cross_waiting: float = param(CLAIM_NEAR, "Concurrent schedule: a plan that only crosses "
                                 "the way of a higher-ranked object standing waiting heeds "
                                 "just the part of its claim within this much (m) of its "
                                 "planned travel; 0: the whole claim.", low=0.0)
    pass_margin: float = param(PASS_MARGIN, "Concurrent schedule: a plan may go through a "
                               "higher-ranked object's claim when it passes each point of "
                               "it this much (m) of travel before that object comes near, "
                               "or leave a claim it stands in; inf: it waits for that "
                               "object to pass.", low=0.0, unbounded=True)
    plan_near: float = param(PLAN_NEAR, "Concurrent schedule: an object's loop plans "
                             "around the other teams' robots standing within this distance "
                             "(m) of its own robots and leaves the farther ones out (they "
                             "move before it comes; admission holds back a segment that "
                             "meets one still standing, and the loop plans anew there); "
                             "inf: around all of them.", low=0.0, unbounded=True)
    replan_near: float = param(REPLAN_NEAR, "Concurrent schedule: once an object's planner "
                               "found no plan, its later loops plan around only the other "
                               "teams' robots within this distance (m) of its own (at most "
                               "plan_near); inf: as plan_near.", low=0.0, unbounded=True)
    balance_teams: int = param(0, "Concurrent schedule: 1: the robots are matched to the "
                               "objects starting together so that the latest arrival plus "
                               "haul is least (teams.balanced_teams); 0: each object in "
                               "priority order takes its nearest free robots.", low=0)
    reach_cut: int = param(0, "Concurrent schedule: 1: admission cuts a pushed object's "
                           "space to where it can get from where it is seen (its robots' "
                           "way x 1.5 + 0.1 m; only where pushes are tracked exactly: no "
                           "sensing or actuation noise, no knocks); 0: anywhere along its "
                           "planned motion.", low=0)
    order_in_way: int = param(0, "Concurrent schedule: 1: an object also starts after the "
                              "ready objects standing in its way round the obstacles "
                              "(teams.stands_in_way; a line of loads leaves an aisle front "
                              "first); 0: only after those whose way its goal lies in.",
                              low=0)
    follow: int = param(0, "Concurrent schedule: 1: an object's loop plans as if the "
                        "higher-ranked moving objects standing in its way ahead of it "
                        "(not head-on) were at their goals, and its segments wait for "
                        "them to move on (a line of loads leaves an aisle together); 0: "
                        "it plans round them where they stand.", low=0)
    rejoin_limit: int = param(0, "Concurrent schedule: a segment whose robots had to move "
                              "back to their rows this many times (held back by what they "
                              "push) ends, stopped; 0: never.", low=0)
    rejoin_slack: float = param(REJOIN_SLACK, "Concurrent schedule: a segment whose robots' "
                                "moves back to their rows (held back by what they push) "
                                "would add more than this share of its planned rows ends, "
                                "stopped; inf: never.", low=0.0, unbounded=True)

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("balance_teams", "reach_cut", "follow", "order_in_way"):
            if getattr(self, name) > 1:
                raise InputError(f"fleet_{name}: 0 or 1, got {getattr(self, name)}")

    def values(self) -> dict[str, Any]:
        """Every setting by its public name (``fleet_`` + field)."""
        return {PREFIX + f.name: getattr(self, f.name) for f in fields(self)}


#: The settings' public names, in declaration order.
PARAMS: tuple[str, ...] = tuple(PREFIX + f.name for f in fields(FleetConfig))


def split_overrides(overrides: Mapping[str, Any], owner: str, base: FleetConfig | None = None
                    ) -> tuple[dict[str, Any], FleetConfig]:
    """``overrides`` (name -> value or text) split into the planner's own and a
    :class:`FleetConfig` (``base`` or the defaults) with the ``fleet_`` ones applied
    (``InputError`` naming ``owner``, the name and the rule for a bad one)."""
    own = {n: v for n, v in overrides.items() if not n.startswith(PREFIX)}
    mine = {n[len(PREFIX):]: v for n, v in overrides.items() if n.startswith(PREFIX)}
    names = [f.name for f in fields(FleetConfig)]
    unknown = [n for n in mine if n not in names]
    if unknown:  # refused by the planner's own check, which lists every name
        own.update({PREFIX + n: mine.pop(n) for n in unknown})
    config = base or FleetConfig()
    for n, v in mine.items():
        try:
            config = apply_overrides(config, names, {n: v}, owner)
        except InputError as exc:  # named as the user wrote it
            raise InputError(str(exc).replace(f"{owner}.{n}", f"{owner}.{PREFIX}{n}")) from None
    return own, config
