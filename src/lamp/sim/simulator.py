"""MuJoCo execution of synchronised multi-robot paths: robots push objects in a planar world.

``Simulator(scene)`` builds the scene (see ``lamp.sim.mjcf`` for the physical model) with
robots and objects at their start poses; ``execute(robot_paths)`` drives the robots along
(N, T, 2) synchronised world-frame waypoints and reports where the objects ended up.
State (poses, velocities, the robots' held targets) carries over between calls.

Timing. The robots move at the scene's speed (``robots.speed``, default ``ROBOT_SPEED`` =
0.25 m/s): the target of every robot moves
linearly between consecutive rows of the path, and each row-to-row interval lasts
``max_i |p_i[t+1] - p_i[t]| / ROBOT_SPEED``, so the robot with the longest step in that row
moves at exactly ``ROBOT_SPEED`` and the others move proportionally slower, all arriving at
row t + 1 together (synchronisation is kept, so a plan that is collision-free row by row
stays so in between). Rows where no robot moves take no time. Before row 0 the robots move
from where they are to ``robot_paths[:, 0]`` (at most ``MAX_START_GAP`` away) in the same
way; after the last row they hold it for ``SETTLE_TIME`` so that pushed objects come to
rest. A path densified to ``MAX_STEP`` = 0.02 m per row therefore takes 0.08 s per row.

Control. Each robot joint follows its moving target with a force-limited PD law with
velocity feed-forward, ``f = kp (p* - q) + kv (v* - qdot)``, clipped to
``lamp.sim.mjcf.ROBOT_FORCE_LIMIT`` per axis (physics step ``lamp.sim.mjcf.TIMESTEP`` =
2 ms). The feed-forward makes the robot track a moving target closely (0.5 mm, one
step of motion, in free motion; 1.5 mm while pushing one object); the force limit makes a robot
commanded into a wall, an obstacle or a blocked object stop at it instead of passing
through (soft contacts then penetrate by under a millimetre). A robot that was blocked
while its target ran on catches up quickly (up to about 2 m/s) once it is free again; a
plan that blocks robots has failed anyway, and ``ExecutionResult.robot_errors`` shows it.

Start states should not overlap: an overlap of d between bodies is pushed apart within a
few steps and the lighter body travels about 2.5 d.

Workspace. An object "left the workspace" when any part of its footprint lies outside
[0, W] x [0, H] by more than ``WORKSPACE_TOLERANCE`` (2 mm: soft contacts let an object
pressed into a border wall by three robots at their force limit sink in by about 0.3 mm,
which must not count); this is checked after every physics step. The border walls stop
objects, so in practice only objects placed across the border (``set_state``) are reported.

Determinism: the same scene, start state and paths give bit-identical results, whether
on a new simulator or on one reset with ``set_state`` (MuJoCo runs single-threaded here).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout
from numpy.typing import ArrayLike

from lamp.geometry.se2 import wrap_angle
from lamp.geometry.shapes import local_outline
from lamp.geometry.team import DEFAULT_TEAM
from lamp.scene.model import Circle, Scene, Shape
from lamp.sim.mjcf import ROBOT_KP, ROBOT_KV, BuiltModel, ObjectBody, build_model
from lamp.sim.stability import StabilityWatch, install_warning_handler

#: Speed of the robots along their paths [m/s] (the fastest robot of each row).
ROBOT_SPEED = DEFAULT_TEAM.speed
#: Largest allowed distance between consecutive rows of one robot's path [m].
MAX_STEP = DEFAULT_TEAM.row_step
#: Largest allowed distance between a robot and the first row of its path [m].
MAX_START_GAP = 0.05
#: Time the last waypoint is held at the end of every ``execute`` call [s].
SETTLE_TIME = 0.2
#: Slack on the workspace border before an object counts as outside [m].
WORKSPACE_TOLERANCE = 0.002

install_warning_handler()  # MuJoCo's warnings to the log, not to MUJOCO_LOG.TXT
_STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION
_ROLLOUT_SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS
_STEP_SLACK = 1e-9  # tolerance on MAX_STEP / MAX_START_GAP comparisons
_CHUNK = 4096  # physics steps per rollout call (bounds the memory of recorded states)
_NONE_FAILED: Mapping[int, np.ndarray] = MappingProxyType({})
#: Physics steps between two ``stop`` checks of a watched ``execute`` (50 ms).
STOP_CHECK_STEPS = 25


@dataclass(frozen=True)
class Trace:
    """States recorded during one ``execute`` call (every ``record_every`` steps).

    Row 0 is the state at the start of the call; the last row is the final state.
    """

    times: np.ndarray  # (S,) simulation time since the start of the call [s]
    robot_positions: np.ndarray  # (S, N, 2)
    object_poses: np.ndarray  # (S, K, 3), theta wrapped to [-pi, pi)


@dataclass(frozen=True)
class ExecutionResult:
    """Outcome of one ``Simulator.execute`` call."""

    object_poses: np.ndarray  # (K, 3) final (x, y, theta), theta wrapped to [-pi, pi)
    robot_positions: np.ndarray  # (N, 2) final robot centres
    left_workspace: bool  # some object's footprint left [0, W] x [0, H] during the call
    objects_left: np.ndarray  # (K,) bool, which objects left the workspace
    sim_time: float  # simulated seconds in this call (motion + settle)
    steps: int  # physics steps in this call
    robot_errors: np.ndarray  # (N,) final distance of each robot from its last waypoint
    trace: Trace | None = None
    #: physics step at which ``stop`` ended the paths early (then the robots held where
    #: they were for the settle time); None when the paths ran to their end
    stopped_at: int | None = None
    #: Always False: a simulator runs every segment it is given (``Execution.declined``).
    declined: bool = False


@dataclass(frozen=True)
class SimState:
    """A snapshot of the simulation; ``Simulator.set_state`` restores it bit-exactly."""

    object_poses: np.ndarray  # (K, 3)
    robot_positions: np.ndarray  # (N, 2)
    time: float
    physics: np.ndarray  # MuJoCo's integration state (mjSTATE_INTEGRATION)


def footprint_outside(
    shape: Shape | ObjectBody,
    poses: ArrayLike,
    workspace: tuple[float, float],
    tolerance: float = 0.0,
) -> np.ndarray:
    """Whether the footprint of ``shape`` at each of ``poses`` (..., 3) reaches outside
    [-tol, W + tol] x [-tol, H + tol]; returns a bool array of shape (...).

    Polygons and rectangles are checked exactly at their vertices (a convex region
    contains a polygon iff it contains its vertices); circles by centre and radius.
    """
    body = shape if isinstance(shape, ObjectBody) else _object_body(shape)
    poses = np.asarray(poses, dtype=float)
    w, h = float(workspace[0]), float(workspace[1])
    x, y = poses[..., 0], poses[..., 1]
    if len(body.outline) == 0:
        r = body.radius
        return (
            (x - r < -tolerance)
            | (y - r < -tolerance)
            | (x + r > w + tolerance)
            | (y + r > h + tolerance)
        )
    c, s = np.cos(poses[..., 2])[..., None], np.sin(poses[..., 2])[..., None]
    px, py = body.outline[:, 0], body.outline[:, 1]
    wx = x[..., None] + c * px - s * py
    wy = y[..., None] + s * px + c * py
    return (
        (wx.min(axis=-1) < -tolerance)
        | (wy.min(axis=-1) < -tolerance)
        | (wx.max(axis=-1) > w + tolerance)
        | (wy.max(axis=-1) > h + tolerance)
    )


def _object_body(shape: Shape) -> ObjectBody:
    if isinstance(shape, Circle):
        return ObjectBody((0.0, 0.0), np.zeros((0, 2)), float(shape.radius))
    return ObjectBody((0.0, 0.0), local_outline(shape), 0.0)


class Simulator:
    """MuJoCo simulation of one scene; see the module docstring for timing and physics.

    Args:
        scene: the scene (workspace, obstacles, objects, robots).
        object_poses: (K, 3) initial object poses (default: the objects' start poses).
        robot_positions: (N, 2) initial robot centres (default: the robots' start positions).

    Construction compiles the model only once per scene structure (workspace, obstacles,
    object shapes, robot count and radius, physics); later simulators of that structure
    reuse it.
    """

    def __init__(self, scene: Scene, object_poses: ArrayLike | None = None,
                 robot_positions: ArrayLike | None = None) -> None:
        self.scene = scene
        #: The robots' driving speed (m/s): the scene's ``robots.speed``, default
        #: ``ROBOT_SPEED``.
        self.speed = float(scene.physics.robot_speed)
        self._built: BuiltModel = build_model(scene)
        self.model: mujoco.MjModel = self._built.model
        self.data = mujoco.MjData(self.model)
        self._centroids = np.array([b.centroid for b in self._built.objects],
                                   dtype=float).reshape(-1, 2)
        self._nstate = mujoco.mj_stateSize(self.model, _STATE_SPEC)
        self._nroll = mujoco.mj_stateSize(self.model, _ROLLOUT_SPEC)
        # qpos addresses inside a rollout state row (row = [time, qpos, qvel, act, ...])
        self._roll_robot = 1 + self._built.robot_qpos
        self._roll_object = 1 + self._built.object_qpos
        self.set_state(
            object_poses=scene.object_starts() if object_poses is None else object_poses,
            robot_positions=scene.robot_starts_array if robot_positions is None
            else robot_positions)

    # ------------------------------------------------------------------ state
    @property
    def n_robots(self) -> int:
        return self._built.n_robots

    @property
    def n_objects(self) -> int:
        return self._built.n_objects

    @property
    def time(self) -> float:
        """Simulated time since construction or the last ``set_state`` with poses [s]."""
        return float(self.data.time)

    @property
    def object_poses(self) -> np.ndarray:
        """(K, 3) current object poses, theta wrapped to [-pi, pi)."""
        return self._qpos_to_poses(self.data.qpos[self._built.object_qpos])

    @property
    def robot_positions(self) -> np.ndarray:
        """(N, 2) current robot centres."""
        return self.data.qpos[self._built.robot_qpos].copy()

    disturbed = False  # nothing disturbs a plain simulation (``WorldExecutor``)
    pushes_tracked = True

    @property
    def true_object_poses(self) -> np.ndarray:
        """(K, 3) the objects' poses: ``object_poses`` (no sensor in between)."""
        return self.object_poses

    @property
    def failed(self) -> Mapping[int, np.ndarray]:
        """Robots that stopped for good: none in a plain simulation."""
        return _NONE_FAILED

    def state(self) -> SimState:
        """A snapshot that ``set_state`` restores exactly (velocities and solver warm start
        included)."""
        physics = np.empty(self._nstate)
        mujoco.mj_getState(self.model, self.data, physics, _STATE_SPEC)
        return SimState(self.object_poses, self.robot_positions, self.time, physics)

    def set_state(self, state: SimState | None = None, *, object_poses: ArrayLike | None = None,
                  robot_positions: ArrayLike | None = None) -> None:
        """Restore a snapshot, or place objects and robots at rest at the given poses.

        With ``state``: exact restore. Otherwise the simulation is reset (time 0, all
        velocities zero) and the given poses are applied; omitted ones keep their current
        values. Robots hold their new positions.
        """
        if state is not None:
            if object_poses is not None or robot_positions is not None:
                raise ValueError("set_state: pass either state or poses, not both")
            if state.physics.shape != (self._nstate,):
                raise ValueError(
                    f"set_state: state.physics has shape {state.physics.shape}, "
                    f"expected ({self._nstate},) for this scene"
                )
            mujoco.mj_setState(self.model, self.data, state.physics, _STATE_SPEC)
            mujoco.mj_forward(self.model, self.data)
            return
        obj = self.object_poses if object_poses is None else object_poses
        rob = self.robot_positions if robot_positions is None else robot_positions
        obj = _as_array("object_poses", obj, (self.n_objects, 3))
        rob = _as_array("robot_positions", rob, (self.n_robots, 2))
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self._built.object_qpos] = self._poses_to_qpos(obj)
        self.data.qpos[self._built.robot_qpos] = rob
        self.data.ctrl[:] = rob.ravel()
        mujoco.mj_forward(self.model, self.data)

    def _qpos_to_poses(self, q: np.ndarray) -> np.ndarray:
        """Body coordinates (centroid x, y, theta) -> object poses (origin x, y, theta)."""
        q = np.asarray(q, dtype=float)
        th = q[..., 2]
        c, s = np.cos(th), np.sin(th)
        cx, cy = self._centroids[:, 0], self._centroids[:, 1]
        out = np.empty(q.shape)
        out[..., 0] = q[..., 0] - (c * cx - s * cy)
        out[..., 1] = q[..., 1] - (s * cx + c * cy)
        out[..., 2] = wrap_angle(th)
        return out

    def _poses_to_qpos(self, poses: np.ndarray) -> np.ndarray:
        th = poses[:, 2]
        c, s = np.cos(th), np.sin(th)
        cx, cy = self._centroids[:, 0], self._centroids[:, 1]
        return np.stack([poses[:, 0] + c * cx - s * cy, poses[:, 1] + s * cx + c * cy, th], axis=1)

    # -------------------------------------------------------------- execution
    def targets(self, robot_paths: ArrayLike, settle_time: float = SETTLE_TIME) -> np.ndarray:
        """(S, N, 2) target position of every robot at the end of each physics step of an
        ``execute(robot_paths)`` call from the current state (validated like ``execute``)."""
        pos, _ = self._schedule(self._validate(robot_paths), settle_time)
        return pos

    def execute(self, robot_paths: ArrayLike, record_every: int | None = None,
                settle_time: float = SETTLE_TIME,
                stop: Callable[[np.ndarray], bool] | None = None) -> ExecutionResult:
        """Drive the robots along ``robot_paths`` (N, T, 2) and simulate.

        Args:
            robot_paths: synchronised world-frame waypoints; consecutive rows of a robot at
                most ``MAX_STEP`` apart, row 0 within ``MAX_START_GAP`` of the robot.
            record_every: if given, record a ``Trace`` every that many physics steps.
            settle_time: how long the last row is held at the end [s].
            stop: if given, called with the (K, 3) object poses every ``STOP_CHECK_STEPS``
                physics steps; when it returns True the paths end there: every robot holds
                the place it has reached for ``settle_time`` and ``stopped_at`` gives the
                step. Until it fires the result is bit-identical to an unwatched call.

        Raises:
            SimulationError: the state turned non-finite or huge (``lamp.sim.stability``).
            ValueError: malformed paths (shape, non-finite values, a step too long, a start
                too far from the robot) or a bad ``record_every`` / ``settle_time``.
        """
        _check_execute_args(record_every, settle_time)
        paths = self._validate(robot_paths)
        pos, vel = self._schedule(paths, settle_time)
        n_steps = len(pos)
        ctrl = (pos + (ROBOT_KV / ROBOT_KP) * vel).reshape(n_steps, 1, 2 * self.n_robots)
        chunk_size = _CHUNK if stop is None else STOP_CHECK_STEPS
        n_settle = self._settle_steps(settle_time)
        stopped_at: int | None = None

        start_time = self.data.time
        watch = StabilityWatch(self.data)
        first = np.empty(self._nroll)
        mujoco.mj_getState(self.model, self.data, first, _ROLLOUT_SPEC)
        objects_left = self._outside(first[None]).any(axis=0)
        rows = [first[None]] if record_every is not None else []
        # roll out in chunks so that memory stays bounded on long paths; each chunk starts
        # from the full physics state and warm start the previous one ended in, so chunking
        # does not change the result
        lo = 0
        while lo < n_steps:
            states = self._roll_out(ctrl[lo : lo + chunk_size].reshape(1, -1, ctrl.shape[-1]))
            objects_left |= self._outside(states).any(axis=0)
            if record_every is not None:
                steps = lo + 1 + np.arange(len(states))  # step index of each row
                keep = (steps % record_every == 0) | (steps == n_steps)
                rows.append(states[keep])
            lo += len(states)
            watch.check(lo, start_time, float(self.model.opt.timestep))
            if (stop is not None and stopped_at is None and lo < n_steps - n_settle
                    and stop(self.object_poses)):
                # the paths end here: hold where the robots are, then settle
                stopped_at = lo
                hold = self.robot_positions.reshape(1, 2 * self.n_robots)
                ctrl = np.concatenate([ctrl[:lo], np.repeat(hold, n_settle, axis=0)
                                       .reshape(n_settle, 1, 2 * self.n_robots)])
                n_steps = len(ctrl)
        if n_steps > 0:
            mujoco.mj_forward(self.model, self.data)

        trace = None if record_every is None else self._trace(np.concatenate(rows), start_time)
        robot_final = self.robot_positions
        return ExecutionResult(
            object_poses=self.object_poses,
            robot_positions=robot_final,
            left_workspace=bool(objects_left.any()),
            objects_left=objects_left,
            sim_time=n_steps * float(self.model.opt.timestep),
            steps=n_steps,
            robot_errors=np.hypot(*(robot_final - paths[:, -1]).T),
            trace=trace,
            stopped_at=stopped_at,
        )

    def _roll_out(self, chunk: np.ndarray) -> np.ndarray:
        """Simulate the (1, S, nu) controls ``chunk`` from the current full physics state and
        warm start; returns the (S, nroll) states and leaves ``self.data`` in the last one."""
        init = np.empty(self._nroll)
        mujoco.mj_getState(self.model, self.data, init, _ROLLOUT_SPEC)
        states, _ = mj_rollout.rollout(
            self.model,
            self.data,
            init[None],
            chunk,
            initial_warmstart=self.data.qacc_warmstart[None].copy(),
        )
        states = states[0]
        # the rollout ran on self.data, which now holds the final state and warm start;
        # set the final state explicitly all the same so that nothing relies on that
        warm = self.data.qacc_warmstart.copy()
        mujoco.mj_setState(self.model, self.data, states[-1], _ROLLOUT_SPEC)
        self.data.qacc_warmstart[:] = warm
        self.data.ctrl[:] = chunk[0, -1]
        return states

    def _trace(self, recorded: np.ndarray, start_time: float) -> Trace:
        """The ``Trace`` of recorded rollout states (times from ``start_time``)."""
        return Trace(
            times=recorded[:, 0] - start_time,
            robot_positions=recorded[:, self._roll_robot],
            object_poses=self._qpos_to_poses(recorded[:, self._roll_object]),
        )

    def _outside(self, states: np.ndarray) -> np.ndarray:
        """(S, K) whether each object's footprint is outside the workspace in each rollout
        state row (beyond ``WORKSPACE_TOLERANCE``)."""
        poses = self._qpos_to_poses(states[:, self._roll_object])
        out = np.zeros((len(states), self.n_objects), dtype=bool)
        for k, body in enumerate(self._built.objects):
            out[:, k] = footprint_outside(
                body, poses[:, k], self.scene.workspace, WORKSPACE_TOLERANCE
            )
        return out

    def _validate(self, robot_paths: ArrayLike) -> np.ndarray:
        try:
            paths = np.asarray(robot_paths, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"robot_paths must be a numeric (N, T, 2) array: {exc}") from None
        n = self.n_robots
        if paths.ndim != 3 or paths.shape[0] != n or paths.shape[2] != 2 or paths.shape[1] < 1:
            raise ValueError(
                f"robot_paths has shape {paths.shape}, expected ({n}, T, 2) with T >= 1 "
                f"(one path per robot, {n} robots)"
            )
        bad = ~np.isfinite(paths)
        if bad.any():
            i, t, _ = np.argwhere(bad)[0]
            raise ValueError(f"robot_paths[{i}, {t}] = {paths[i, t]} is not finite")
        if paths.shape[1] > 1:
            step = np.hypot(*np.moveaxis(np.diff(paths, axis=1), 2, 0))
            if step.max() > MAX_STEP + _STEP_SLACK:
                i, t = np.unravel_index(np.argmax(step), step.shape)
                raise ValueError(
                    f"robot_paths[{i}] moves {step[i, t]:.4f} m between rows {t} and {t + 1}; "
                    f"consecutive rows must be at most {MAX_STEP} m apart (densify the path)"
                )
        gap = np.hypot(*(paths[:, 0] - self.robot_positions).T)
        if gap.max() > MAX_START_GAP + _STEP_SLACK:
            i = int(np.argmax(gap))
            raise ValueError(
                f"robot_paths[{i}, 0] = {paths[i, 0]} is {gap[i]:.4f} m from robot {i} at "
                f"{self.robot_positions[i]}; paths must start within {MAX_START_GAP} m of the "
                "robots (use set_state to move robots)"
            )
        return paths

    def _settle_steps(self, settle_time: float) -> int:
        """Physics steps the last row is held for ``settle_time`` seconds."""
        return math.ceil(settle_time / float(self.model.opt.timestep) - 1e-9)

    def row_durations(self, paths: np.ndarray) -> np.ndarray:
        """(T,) seconds the targets take to each row of ``paths`` from the one before (row 0:
        from where the robots are): the row's longest robot step over the driving speed."""
        way = np.concatenate([self.robot_positions[:, None], paths], axis=1)
        return np.hypot(*np.moveaxis(np.diff(way, axis=1), 2, 0)).max(axis=0) / self.speed

    def _schedule(self, paths: np.ndarray, settle_time: float) -> tuple[np.ndarray, np.ndarray]:
        """Per-step targets and target velocities, (S, N, 2) each (see module docstring)."""
        dt = float(self.model.opt.timestep)
        way = np.concatenate([self.robot_positions[:, None], paths], axis=1)  # (N, T+1, 2)
        dur = self.row_durations(paths)
        keep = np.concatenate([[True], dur > 1e-12])
        way = way[:, keep]
        tau = np.concatenate([[0.0], np.cumsum(dur[dur > 1e-12])])
        n_move = math.ceil(tau[-1] / dt - 1e-9) if len(tau) > 1 else 0
        n_settle = self._settle_steps(settle_time)
        n = self.n_robots
        pos = np.empty((n_move + n_settle, n, 2))
        vel = np.zeros((n_move + n_settle, n, 2))
        if n_move:
            t = np.minimum(dt * np.arange(1, n_move + 1), tau[-1])
            j = np.clip(np.searchsorted(tau, t, side="left"), 1, len(tau) - 1)
            span = tau[j] - tau[j - 1]
            frac = (t - tau[j - 1]) / span
            a, b = way[:, j - 1], way[:, j]  # (N, S, 2)
            pos[:n_move] = np.swapaxes(a + frac[None, :, None] * (b - a), 0, 1)
            vel[:n_move] = np.swapaxes((b - a) / span[None, :, None], 0, 1)
        pos[n_move:] = way[:, -1]
        return pos, vel


def _check_execute_args(record_every: int | None, settle_time: float) -> None:
    """ValueError unless ``record_every`` is None or a positive integer and ``settle_time``
    finite and >= 0 (see :meth:`Simulator.execute`)."""
    if record_every is not None and (isinstance(record_every, bool) or not isinstance(
            record_every, (int, np.integer)) or record_every < 1):
        raise ValueError(f"record_every must be a positive integer, got {record_every!r}")
    if not (math.isfinite(settle_time) and settle_time >= 0.0):
        raise ValueError(f"settle_time must be finite and >= 0, got {settle_time!r}")


def _as_array(name: str, value: ArrayLike, shape: tuple[int, int]) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array of shape {shape}: {exc}") from None
    if arr.shape != shape:
        raise ValueError(f"{name} has shape {arr.shape}, expected {shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} contains non-finite values: {arr.tolist()}")
    return arr
