"""A simulator with a real world's troubles: noisy sensing, imprecise robots, robots that stop,
knocked pushes (``lamp.contract.disturb``).

:class:`DisturbedExecutor` wraps a :class:`~lamp.sim.Simulator` the way a Gymnasium wrapper
wraps an environment: the closed loop drives it through the same ``Executor`` protocol and
cannot tell. Everything the loop observes carries the sensing noise: ``object_poses``, the
result's ``object_poses``, and the poses a push watch (``execute``'s ``stop``) is called
with, a fresh reading at each check. The simulator's true state is ``true_object_poses``
and the recorded trace, so the recording and the final success verdict are the truth. With
no disturbance every call passes straight through (bit-identical). Deterministic for its
seed.

Timing of a failure: the rows of a path are reached at the documented times (row t -> t+1
lasts the longest robot step over the scene's robot speed, ``lamp.sim.simulator``), so a
robot failing at time T holds, from the first row reached at or after T, the place of that
row (``failed`` maps it to that place, ``fired`` to that row's time); in every later call
it holds where it is at the call's start: a braked robot that a pushed object may shove,
not a spring back to its place.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from lamp.contract.disturb import HEADING_PER_METRE, Disturbances
from lamp.contract.trajectory import densify
from lamp.sim.simulator import SETTLE_TIME, ExecutionResult, Simulator, Trace

__all__ = ["DisturbedExecutor"]


class DisturbedExecutor:
    """``sim`` under ``disturbances`` (see the module docstring)."""

    #: Its readings may be noisy and its robots may fail
    #: (``lamp.contract.runner.WorldExecutor``).
    disturbed = True

    def __init__(self, sim: Simulator, disturbances: Disturbances, seed: int) -> None:
        self.sim = sim
        self.disturbances = disturbances
        self.rng = np.random.default_rng([int(seed), 0x5EED])
        #: robot -> where it stopped (those whose failure time has come)
        self.failed: dict[int, np.ndarray] = {}
        #: robot -> the simulated time it stopped at (the time its stopping row is reached)
        self.fired: dict[int, float] = {}
        self._pending = list(disturbances.robot_failures)

    @property
    def pushes_tracked(self) -> bool:
        """Exact readings and pushes (``WorldExecutor``): robots may only fail."""
        d = self.disturbances
        return d.sensing_noise == 0.0 and d.actuation_noise == 0.0 and d.push_disturbance == 0.0

    # ------------------------------------------------------------------ observation
    @property
    def object_poses(self) -> np.ndarray:
        """(K, 3) a fresh reading of the objects' poses (true poses plus new sensing noise)."""
        return self._observe()

    @property
    def true_object_poses(self) -> np.ndarray:
        return self.sim.object_poses

    @property
    def robot_positions(self) -> np.ndarray:
        return self.sim.robot_positions

    @property
    def time(self) -> float:
        return self.sim.time

    def _observe(self) -> np.ndarray:
        poses = self.sim.object_poses
        sigma = self.disturbances.sensing_noise
        if sigma > 0:
            noise = self.rng.normal(0.0, 1.0, poses.shape) * np.array(
                [sigma, sigma, sigma * HEADING_PER_METRE])
            poses = poses + noise
            poses[:, 2] = (poses[:, 2] + np.pi) % (2 * np.pi) - np.pi
        return poses

    # --------------------------------------------------------------------- execution
    def execute(self, robot_paths: np.ndarray, record_every: int | None = None,
                stop: Callable[[np.ndarray], bool] | None = None,
                settle_time: float = SETTLE_TIME) -> ExecutionResult:
        """Run ``robot_paths`` with the robots' imprecision and failures, and knock the
        pushed object once; the result's ``object_poses`` are observed ones, its trace true.
        ``settle_time`` as in ``Simulator.execute`` (the fleet schedule holds no settle
        while other sub-teams move on)."""
        paths = np.asarray(robot_paths, float)
        if not self.disturbances.active:
            return self.sim.execute(paths, record_every=record_every, stop=stop,
                                    settle_time=settle_time)
        if stop is not None and self.disturbances.sensing_noise > 0:
            watch = stop  # the push watch reads the sensor, never the true poses
            stop = lambda _true_poses: watch(self._observe())  # noqa: E731
        paths = self._imprecise(paths)
        paths = self._fail(paths)
        if self.disturbances.push_disturbance > 0 and paths.shape[1] > 2:
            out = self._knocked(paths, record_every, stop, settle_time)
        else:
            out = self.sim.execute(paths, record_every=record_every, stop=stop,
                                   settle_time=settle_time)
        return replace(out, object_poses=self._observe())

    def _imprecise(self, paths: np.ndarray) -> np.ndarray:
        """Each robot's row-to-row motion scaled by 1 + e and turned by e' (e, e' ~ N(0,
        actuation_noise)); re-densified to the simulator's row spacing."""
        f = self.disturbances.actuation_noise
        if f <= 0 or paths.shape[1] < 2:
            return paths
        steps = np.diff(paths, axis=1)  # (N, T-1, 2)
        scale = 1.0 + self.rng.normal(0.0, f, steps.shape[:2])
        turn = self.rng.normal(0.0, f, steps.shape[:2])
        c, s = np.cos(turn), np.sin(turn)
        moved = np.stack([c * steps[..., 0] - s * steps[..., 1],
                          s * steps[..., 0] + c * steps[..., 1]], axis=-1) * scale[..., None]
        out = np.concatenate([paths[:, :1], paths[:, :1] + np.cumsum(moved, axis=1)], axis=1)
        return densify(out)

    def row_durations(self, paths: np.ndarray) -> np.ndarray:
        """The simulator's schedule of ``paths`` as given (``Simulator.row_durations``)."""
        return self.sim.row_durations(paths)

    def _row_times(self, paths: np.ndarray) -> np.ndarray:
        """The simulated time each row is reached (the simulator's documented schedule)."""
        return self.sim.time + np.cumsum(self.sim.row_durations(paths))

    def _fail(self, paths: np.ndarray) -> np.ndarray:
        """Failed robots hold where they stopped; a failure due in this call stops its robot
        at the first row reached at or after its time."""
        paths = paths.copy()
        times = self._row_times(paths)
        fresh = set()
        for robot, when in list(self._pending):
            if times[-1] < when:
                continue
            row = int(np.searchsorted(times, when))
            self.failed[robot] = paths[robot, row].copy()
            self.fired[robot] = float(times[row])
            paths[robot, row:] = self.failed[robot]
            self._pending.remove((robot, when))
            fresh.add(robot)
        now = self.sim.robot_positions
        for robot in self.failed:
            if robot not in fresh:  # braked where it is (others may have shoved it)
                paths[robot, :] = now[robot]
        return paths

    def _knocked(self, paths: np.ndarray, record_every: int | None,
                 stop: Callable[[np.ndarray], bool] | None, settle_time: float
                 ) -> ExecutionResult:
        """The paths in two parts with an impulse on the pushed object in between (the one
        that moved most in the first part; none when nothing moved)."""
        cut = int(self.rng.integers(1, paths.shape[1] - 1))
        before = self.sim.object_poses
        first = self.sim.execute(paths[:, : cut + 1], record_every=record_every,
                                 settle_time=0.0, stop=stop)
        moved = np.hypot(*(self.sim.object_poses[:, :2] - before[:, :2]).T)
        if moved.size and moved.max() > 1e-3:
            angle = self.rng.uniform(-np.pi, np.pi)
            self._kick(int(np.argmax(moved)), self.disturbances.push_disturbance
                       * np.array([np.cos(angle), np.sin(angle)]))
        if first.stopped_at is not None:
            return first
        # on from where the robots are (a robot pressing on the knocked object may lag its
        # target by more than the simulator's start gap)
        rest = densify(np.concatenate([self.sim.robot_positions[:, None], paths[:, cut + 1:]],
                                      axis=1))
        second = self.sim.execute(rest, record_every=record_every, stop=stop,
                                  settle_time=settle_time)
        return _joined(first, second)

    def _kick(self, k: int, impulse: np.ndarray) -> None:
        """An impulse (N s) on object ``k``'s centre of mass."""
        m, d = self.sim.model, self.sim.data
        mass = float(m.body(f"o{k}").mass[0])
        for axis, value in zip("xy", impulse, strict=True):
            d.qvel[m.joint(f"o{k}{axis}").dofadr[0]] += float(value) / mass


def _joined(a: ExecutionResult, b: ExecutionResult) -> ExecutionResult:
    """One result for two consecutive calls (``b``'s trace shifted by ``a``'s time)."""
    trace = None
    if a.trace is not None and b.trace is not None:
        trace = Trace(np.concatenate([a.trace.times, b.trace.times[1:] + a.sim_time]),
                      np.concatenate([a.trace.robot_positions, b.trace.robot_positions[1:]]),
                      np.concatenate([a.trace.object_poses, b.trace.object_poses[1:]]))
    return replace(b, left_workspace=a.left_workspace or b.left_workspace,
                   objects_left=a.objects_left | b.objects_left,
                   sim_time=a.sim_time + b.sim_time, steps=a.steps + b.steps, trace=trace)
