"""Disturbances of a run: noisy sensing, imprecise robots, robots that stop, pushes that are
knocked. Part of the run request (``RunRequest.disturbances``), recorded in result.json,
deterministic for the run's seed.

- ``sensing_noise`` (m): every observed object pose is perturbed by Gaussian noise of this
  standard deviation in x and y and ``sensing_noise / 0.2`` rad in heading;
- ``actuation_noise`` (fraction): each robot's commanded motion from row to row is scaled by
  ``1 + e`` and turned by ``e'`` rad, ``e, e'`` ~ N(0, fraction), per robot and row;
- ``robot_failures``: (robot, simulated time) pairs: the robot stops for good at that time
  and stays where it stopped, an obstacle to the others;
- ``push_disturbance`` (N s): during every segment, at a random instant, the object being
  pushed receives an impulse of this size in a random direction.

Zero everywhere (:data:`NO_DISTURBANCE`) leaves a run exactly as it is without one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from lamp.errors import InputError

__all__ = ["NO_DISTURBANCE", "PRESETS", "Disturbances", "parse_failure"]

#: Heading noise per metre of position noise (rad/m): 1 cm of noise comes with 0.05 rad.
HEADING_PER_METRE = 1.0 / 0.2
#: Largest levels accepted (beyond them nothing could be planned or measured).
MAX_SENSING_NOISE = 0.2
MAX_ACTUATION_NOISE = 1.0
MAX_PUSH_IMPULSE = 20.0


def _level(name: str, value: Any, high: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or not 0.0 <= value <= high:
        raise InputError(f"{name}: a number in [0, {high:g}], got {value!r}")
    return float(value)


@dataclass(frozen=True)
class Disturbances:
    """The disturbances of one run (see the module docstring); validated on construction."""

    sensing_noise: float = 0.0
    actuation_noise: float = 0.0
    robot_failures: tuple[tuple[int, float], ...] = ()
    push_disturbance: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "sensing_noise",
                           _level("sensing_noise", self.sensing_noise, MAX_SENSING_NOISE))
        object.__setattr__(self, "actuation_noise",
                           _level("actuation_noise", self.actuation_noise, MAX_ACTUATION_NOISE))
        object.__setattr__(self, "push_disturbance",
                           _level("push_disturbance", self.push_disturbance, MAX_PUSH_IMPULSE))
        failures = []
        for item in self.robot_failures:
            try:
                robot, when = item
            except (TypeError, ValueError):
                raise InputError(f"robot_failures: (robot, time) pairs, got {item!r}") from None
            if isinstance(robot, bool) or not isinstance(robot, int) or robot < 0:
                raise InputError(f"robot_failures: robot index >= 0, got {robot!r}")
            if isinstance(when, bool) or not isinstance(when, (int, float)) \
                    or not math.isfinite(when) or when < 0:
                raise InputError(f"robot_failures: robot {robot}: a time >= 0 s, got {when!r}")
            failures.append((robot, float(when)))
        robots = [r for r, _ in failures]
        if len(set(robots)) != len(robots):
            raise InputError(f"robot_failures: robot {robots} named twice")
        object.__setattr__(self, "robot_failures", tuple(sorted(failures, key=lambda f: f[1])))

    @property
    def active(self) -> bool:
        """Whether anything is disturbed at all."""
        return self != NO_DISTURBANCE

    def check_robots(self, n_robots: int) -> None:
        """``InputError`` for a failing robot the scene does not have, or for all of them."""
        for robot, _ in self.robot_failures:
            if robot >= n_robots:
                raise InputError(f"robot_failures: robot {robot}: the scene has robots "
                                 f"0..{n_robots - 1}")
        if self.robot_failures and len(self.robot_failures) >= n_robots:
            raise InputError("robot_failures: every robot would fail; at least one must remain")

    def to_dict(self) -> dict[str, Any]:
        return {"sensing_noise": self.sensing_noise, "actuation_noise": self.actuation_noise,
                "robot_failures": [list(f) for f in self.robot_failures],
                "push_disturbance": self.push_disturbance}


NO_DISTURBANCE = Disturbances()


def parse_failure(text: str) -> tuple[int, float]:
    """``"K@T"`` (robot K stops at simulated time T seconds) as ``(K, T)``."""
    robot, at, when = str(text).partition("@")
    try:
        if not at:
            raise ValueError
        out = (int(robot), float(when))
    except ValueError:
        raise InputError(f"--robot-failure: ROBOT@SECONDS (for example 1@30), got {text!r}") \
            from None
    if out[0] < 0 or not (math.isfinite(out[1]) and out[1] >= 0):
        raise InputError(f"--robot-failure: a robot index >= 0 and a time >= 0 s, got {text!r}")
    return out


#: Named levels for ``lamp bench --disturb``: the robustness sweep's rows. The preset with a
#: failing robot is drawn per scene and seed by the bench (``lamp.bench.disturb``).
PRESETS: dict[str, Disturbances] = {
    "none": NO_DISTURBANCE,
    "noise-low": Disturbances(sensing_noise=0.005, actuation_noise=0.05),
    "noise-high": Disturbances(sensing_noise=0.01, actuation_noise=0.10),
    "push-knocks": Disturbances(push_disturbance=0.5),
}
