"""The pushing task shared by the Gymnasium and PettingZoo environments.

``PushCore`` runs one scene on the project's MuJoCo simulator (``lamp.sim``) under velocity
commands and computes observations, rewards and termination; ``lamp.env.gym_env`` and
``lamp.env.parallel`` only wrap it in the two APIs. See ``docs/env.md`` for the user-facing
description; the guarantees stated here are the ones the tests check.

Frame. Observations are expressed in a common frame with its origin at the active object:
world axes (``frame="world"``, the default) or axes turned so that x points from the object
to its goal (``frame="goal"``: the task then looks the same in every direction); actions
are velocities in that frame's axes.

Control. One environment step lasts ``PushConfig.frame_skip`` physics steps of
``lamp.sim.mjcf.TIMESTEP`` (default 10 x 2 ms = 20 ms). The command of robot i is a
velocity ``a_i * max_speed`` with ``a_i`` clipped to [-1, 1] per component and then to the
unit disk (so no robot is asked to move faster than ``max_speed``). The robot's position
actuator is held at the target ``q_i + v_i * period / 2 + (kv / kp) v_i`` for the whole
step, re-anchored on the robot's actual position every step: the target leads the robot by
what it should cover in half a step, so on average over the step the force is
``kv (v_i - qdot_i)`` (clipped to the force limit), a velocity servo that reaches the
commanded velocity within a few physics steps (time constant ``ROBOT_MASS / ROBOT_KV`` =
12 ms), moves a free robot at the commanded speed to within 3 % (tested) and builds up no
lag when the robot is blocked.

Task. Objects are pushed one after another in scene order (as the scene format defines).
The *active* object k succeeds once, at the end of a step, its position lies within
``position_tolerance`` of its goal and (unless ``orientation_tolerance`` is None) its
orientation within ``orientation_tolerance``; then object k + 1 becomes active. An object
that has succeeded is not checked again. The episode

- terminates with success when the last object succeeds;
- terminates with failure when any object's footprint is outside the workspace by more
  than ``lamp.sim.WORKSPACE_TOLERANCE`` at the start or the end of a step (the border walls
  stop objects, so in practice only an object placed across the border is reported, as in
  ``Simulator.execute``, which also checks between physics steps);
- is truncated when ``time_limit`` simulated seconds have passed.

Reward of one step (weights in ``RewardWeights``, all non-negative):
``progress * (d_prev - d) + rotation * (e_prev - e) + approach * (c_prev - c)
+ behind * (b - b_prev) - time + success * [object succeeded] - leave * [object left the
workspace]``, where d is the active object's distance to its goal position, e its wrapped
orientation error (0 when orientation is ignored), c the mean gap between the robots and
the active object's bounding circle and b the mean over robots of the cosine between
(robot - object) and (object - goal): 1 for a robot straight behind the object, where it
pushes towards the goal (MAPush's "optimal contact behaviour" term, as a potential). When the active object changes, the differences restart from the new
object's values, so the sum of the shaping terms over an episode telescopes.

Determinism: the same scene, configuration, reset options and actions give bit-identical
observations, rewards and infos (MuJoCo runs single-threaded; nothing here is random).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from lamp.contract.goals import SUCCESS_ORIENTATION_TOL, SUCCESS_POSITION_TOL
from lamp.geometry.robot_space import RobotSpace
from lamp.geometry.shapes import half_extents
from lamp.scene.model import Scene
from lamp.sim.mjcf import ROBOT_KP, ROBOT_KV, build_model
from lamp.sim.simulator import WORKSPACE_TOLERANCE, Simulator, footprint_outside
from lamp.suites.registry import resolve_scene

#: Axes of the common frame (``PushConfig.frame``).
FRAMES = ("world", "goal")


def _check(ok: bool, name: str, value: Any, rule: str) -> None:
    if not ok:
        raise ValueError(f"{name} = {value!r}: must be {rule}")


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms (see the module docstring); all finite and >= 0."""

    progress: float = 10.0  # per metre the active object gets closer to its goal
    rotation: float = 1.0  # per radian of orientation error removed
    approach: float = 2.0  # per metre the robots get closer to the active object
    time: float = 0.01  # cost of every step
    success: float = 10.0  # once per object that reaches its goal
    leave: float = 10.0  # once when an object leaves the workspace
    behind: float = 0.0  # per unit rise of the mean "behind the object" cosine

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            _check(
                isinstance(v, (int, float)) and math.isfinite(v) and v >= 0,
                f"reward.{f.name}", v, "a finite number >= 0",
            )


@dataclass(frozen=True)
class PushConfig:
    """Environment settings; every field is validated (ValueError naming the field)."""

    frame_skip: int = 10  # physics steps per environment step (2 ms each)
    max_speed: float = 0.5  # robot speed commanded by an action of norm 1 [m/s]
    time_limit: float = 120.0  # episode length [simulated s]
    position_tolerance: float = SUCCESS_POSITION_TOL  # success radius around the goal [m]
    orientation_tolerance: float | None = SUCCESS_ORIENTATION_TOL  # [rad]; None: ignored
    patch_size: int = 9  # P: the occupancy patch is P x P samples centred on the robot
    patch_spacing: float = 0.05  # distance between patch samples [m]
    patch_range: float = 0.2  # free clearance mapped to 1.0 in the patch [m]
    reward: RewardWeights = field(default_factory=RewardWeights)
    #: axes of the common frame: "world", or "goal" (x towards the active goal; actions,
    #: positions, headings and patch samples are all expressed in it)
    frame: str = "world"

    def __post_init__(self) -> None:
        _check(
            isinstance(self.frame_skip, int) and not isinstance(self.frame_skip, bool)
            and self.frame_skip >= 1,
            "frame_skip", self.frame_skip, "an integer >= 1",
        )
        _check(
            isinstance(self.patch_size, int) and not isinstance(self.patch_size, bool)
            and self.patch_size >= 1 and self.patch_size % 2 == 1,
            "patch_size", self.patch_size, "an odd integer >= 1",
        )
        for name in ("max_speed", "time_limit", "position_tolerance", "patch_spacing",
                     "patch_range"):
            v = getattr(self, name)
            _check(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                and v > 0,
                name, v, "a finite number > 0",
            )
        tol = self.orientation_tolerance
        _check(
            tol is None or (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0),
            "orientation_tolerance", tol, "None or a finite number > 0",
        )
        _check(isinstance(self.reward, RewardWeights), "reward", self.reward,
               "a RewardWeights")
        _check(self.frame in FRAMES, "frame", self.frame, f"one of {FRAMES}")


@dataclass(frozen=True)
class StepOutcome:
    """What one ``PushCore.step`` produced (the observation is read separately)."""

    reward: float
    terminated: bool
    truncated: bool
    info: dict[str, Any]


def _pose3(name: str, value: ArrayLike) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r}: must be a pose (x, y, theta)") from None
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ValueError(f"{name} = {value!r}: must be a finite pose (x, y, theta)")
    return arr


class PushCore:
    """One scene under velocity control; see the module docstring for the task."""

    def __init__(self, scene: Scene | str | Path, config: PushConfig | None = None,
                 sim: Simulator | None = None) -> None:
        self.scene = resolve_scene(scene)
        self.config = config if config is not None else PushConfig()
        if not isinstance(self.config, PushConfig):
            raise ValueError(f"config = {self.config!r}: must be a PushConfig")
        if sim is not None and sim.scene is not self.scene and sim.scene != self.scene:
            raise ValueError("sim: a simulator of another scene")
        self.sim = Simulator(self.scene) if sim is None else sim
        built = build_model(self.scene)
        self._model, self._data = self.sim.model, self.sim.data
        self._robot_qpos = built.robot_qpos.ravel()
        self._object_qpos = built.object_qpos
        self._bodies = built.objects
        self._centroids = np.array([b.centroid for b in built.objects], float).reshape(-1, 2)
        self._bounds = np.array([o.shape.bounding_radius for o in self.scene.objects])
        self.extents = np.array([half_extents(o.shape) for o in self.scene.objects], float)
        self.n_robots = self.scene.n_robots
        self.n_objects = len(self.scene.objects)
        self.period = self.config.frame_skip * float(self._model.opt.timestep)
        self._gain = 0.5 * self.period + ROBOT_KV / ROBOT_KP  # target offset per unit velocity
        c = self.config
        half = (c.patch_size - 1) // 2
        g = np.arange(-half, half + 1) * c.patch_spacing
        gx, gy = np.meshgrid(g, g, indexing="xy")  # patch[r, s] at (x = g[s], y = g[r])
        self._patch_offsets = np.stack([gx, gy], axis=-1)  # (P, P, 2)
        self._h = 0.01
        self._pad = half * c.patch_spacing / self._h + 2
        self.goals = self.scene.object_goals()
        self.active = 0
        self.steps = 0
        self.left = np.zeros(self.n_objects, bool)
        if sim is None:
            self.reset()
        else:
            self.resume()

    # ----------------------------------------------------------------- state
    @property
    def time(self) -> float:
        """Simulated seconds since the last reset."""
        return self.steps * self.period

    @property
    def done(self) -> bool:
        return self.active >= self.n_objects or bool(self.left.any())

    def robot_positions(self) -> np.ndarray:
        return self._data.qpos[self._robot_qpos].reshape(-1, 2)

    def object_poses(self) -> np.ndarray:
        """(K, 3) object poses (origin x, y, theta), theta wrapped to [-pi, pi)."""
        q = self._data.qpos[self._object_qpos]
        th = q[:, 2]
        c, s = np.cos(th), np.sin(th)
        cx, cy = self._centroids[:, 0], self._centroids[:, 1]
        return np.stack(
            [q[:, 0] - (c * cx - s * cy), q[:, 1] - (s * cx + c * cy),
             (th + np.pi) % (2 * np.pi) - np.pi],
            axis=1,
        )

    def reset(
        self,
        object_poses: ArrayLike | None = None,
        robot_positions: ArrayLike | None = None,
        goal: ArrayLike | None = None,
        active: int = 0,
    ) -> None:
        """Start an episode: objects and robots at rest at the given poses (default: the
        scene's starts), ``active`` the first object to push, ``goal`` (optional) replacing
        that object's goal pose. Bad values raise ValueError naming the argument."""
        if isinstance(active, bool) or not isinstance(active, (int, np.integer)) or not (
            0 <= active < self.n_objects
        ):
            raise ValueError(f"object = {active!r}: must be an object index in [0, {self.n_objects})")
        if goal is not None:
            _pose3("goal", goal)  # validated before anything changes
        self.sim.set_state(
            object_poses=self.scene.object_starts() if object_poses is None else object_poses,
            robot_positions=self.scene.robot_starts_array
            if robot_positions is None
            else robot_positions,
        )
        self.resume(active, goal)

    def resume(self, active: int = 0, goal: ArrayLike | None = None) -> None:
        """Start an episode from the simulator's current state (poses and velocities kept,
        e.g. a shared simulator that earlier objects were pushed in); as ``reset`` otherwise."""
        if isinstance(active, bool) or not isinstance(active, (int, np.integer)) or not (
            0 <= active < self.n_objects
        ):
            raise ValueError(f"object = {active!r}: must be an object index in [0, {self.n_objects})")
        self.goals = self.scene.object_goals()
        if goal is not None:
            self.goals[active] = _pose3("goal", goal)
        self.active = int(active)
        self.steps = 0
        self.left = np.zeros(self.n_objects, bool)
        self._poses = self.object_poses()
        self._outside_now = self._outside(self._poses)
        self._start_object()

    def set_goal(self, goal: ArrayLike) -> None:
        """Replace the active object's goal pose (e.g. by a subgoal); episode continues."""
        if self.done:
            raise ValueError("set_goal: the episode is over; call reset first")
        self.goals[self.active] = _pose3("goal", goal)
        self._prev = self._measures(self.object_poses())

    def _start_object(self) -> None:
        """Rebuild the occupancy field for the active object and restart the shaping terms."""
        poses = self.object_poses()
        space = RobotSpace.from_scene(
            self.scene, object_poses=poses, exclude_objects=[self.active],
            robot_radius=self.scene.robot_radius, resolution=self._h,
        )
        c = self.config
        free = np.clip((space.field - self.scene.robot_radius) / c.patch_range, 0.0, 1.0)
        pad = int(math.ceil(self._pad))
        self._patch_field = np.pad(free.astype(np.float32), pad)  # zero outside: border wall
        self._patch_shift = pad
        self._prev = self._measures(poses)

    def _measures(self, poses: np.ndarray) -> tuple[float, float, float, float]:
        """(distance, orientation error, mean robot gap, mean behind-cosine) of the active
        object (see the module docstring)."""
        k = min(self.active, self.n_objects - 1)
        pose, goal = poses[k], self.goals[k]
        dist = math.hypot(pose[0] - goal[0], pose[1] - goal[1])
        if self.config.orientation_tolerance is None:
            err = 0.0
        else:
            err = abs(float((pose[2] - goal[2] + math.pi) % (2 * math.pi) - math.pi))
        rob = self.robot_positions()
        gap = np.hypot(rob[:, 0] - pose[0], rob[:, 1] - pose[1]) - self._bounds[k]
        gap = float(np.maximum(gap - self.scene.robot_radius, 0.0).mean())
        back = np.array([pose[0] - goal[0], pose[1] - goal[1]]) / max(dist, 1e-9)
        rel = rob - pose[:2]
        cos = (rel @ back) / np.maximum(np.hypot(rel[:, 0], rel[:, 1]), 1e-9)
        behind = float(cos.mean()) if dist > 1e-9 else 0.0
        return dist, err, gap, behind

    # ------------------------------------------------------------------ step
    def check_action(self, action: ArrayLike, name: str = "action") -> np.ndarray:
        """``action`` as an (N, 2) float array; ValueError naming ``name`` and the bad entry
        when it has another shape or holds a non-finite value."""
        try:
            a = np.asarray(action, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{name} must be a numeric array of shape ({self.n_robots}, 2), "
                             f"got {action!r}") from None
        if a.size != 2 * self.n_robots:
            raise ValueError(
                f"{name} has shape {a.shape}, expected ({self.n_robots}, 2): one (vx, vy) "
                f"command per robot"
            )
        a = a.reshape(self.n_robots, 2)
        if not np.isfinite(a).all():
            i = int(np.argwhere(~np.isfinite(a))[0, 0])
            raise ValueError(f"{name}[{i}] = {a[i].tolist()} is not finite")
        return a

    def step(self, action: ArrayLike) -> StepOutcome:
        """Apply velocity commands (N, 2) in [-1, 1] for one period; see the module docstring."""
        if self.done:
            raise ValueError("step: the episode is over; call reset first")
        a = np.clip(self.check_action(action), -1.0, 1.0)
        norm = np.sqrt((a * a).sum(axis=1, keepdims=True))
        v = a * (self.config.max_speed / np.maximum(norm, 1.0))
        if self.config.frame == "goal":
            c, s = self._axes()
            v = np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]], axis=1)
        q = self._data.qpos[self._robot_qpos]
        self._data.ctrl[:] = q + v.ravel() * self._gain
        mujoco.mj_step(self._model, self._data, nstep=self.config.frame_skip)
        self.steps += 1

        poses = self.object_poses()
        w = self.config.reward
        dist, err, gap, behind = self._measures(poses)
        d0, e0, g0, b0 = self._prev
        reward = w.progress * (d0 - dist) + w.rotation * (e0 - err) + w.approach * (g0 - gap)
        reward += w.behind * (behind - b0) - w.time
        self._prev = (dist, err, gap, behind)
        # outside at the start or the end of the step (see the module docstring)
        now = self._outside(poses)
        self.left = self._outside_now | now
        self._outside_now = now
        self._poses = poses
        placed = -1
        if self.left.any():
            reward -= w.leave
        elif dist <= self.config.position_tolerance and (
            self.config.orientation_tolerance is None or err <= self.config.orientation_tolerance
        ):
            reward += w.success
            placed = self.active
            self.active += 1
            if self.active < self.n_objects:
                self._start_object()
        terminated = self.done
        truncated = not terminated and self.time >= self.config.time_limit - 1e-9
        info = {
            "object": min(self.active, self.n_objects - 1),
            "position_error": dist,
            "orientation_error": err,
            "robot_gap": gap,
            "robots_behind": behind,
            "placed": placed,
            "left_workspace": bool(self.left.any()),
            "is_success": self.active >= self.n_objects,
            "sim_time": self.time,
        }
        return StepOutcome(float(reward), terminated, truncated, info)

    def _near_border(self, poses: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """(K,) whether each object's bounding circle comes within ``margin`` of the border."""
        W, H = self.scene.workspace
        x, y, r = poses[:, 0], poses[:, 1], self._bounds + margin
        return (x - r < 0) | (y - r < 0) | (x + r > W) | (y + r > H)

    def _outside(self, poses: np.ndarray) -> np.ndarray:
        """(K,) whether each object's footprint is outside the workspace (beyond tolerance);
        exact check only for objects whose bounding circle reaches the border."""
        out = np.zeros(self.n_objects, bool)
        for k in np.flatnonzero(self._near_border(poses, WORKSPACE_TOLERANCE)):
            out[k] = bool(
                footprint_outside(self._bodies[k], poses[k], self.scene.workspace,
                                  WORKSPACE_TOLERANCE)
            )
        return out

    # ----------------------------------------------------------- observation
    def _axes(self) -> tuple[float, float]:
        """(cos, sin) of the common frame's x axis in the world."""
        if self.config.frame == "world":
            return 1.0, 0.0
        k = min(self.active, self.n_objects - 1)
        dx, dy = self.goals[k, :2] - self._poses[k, :2]
        n = math.hypot(dx, dy)
        return (1.0, 0.0) if n < 1e-9 else (dx / n, dy / n)

    def info(self) -> dict[str, Any]:
        """Info of the current state (what ``reset`` returns)."""
        dist, err, gap, behind = self._prev
        return {
            "object": min(self.active, self.n_objects - 1),
            "position_error": dist,
            "orientation_error": err,
            "robot_gap": gap,
            "robots_behind": behind,
            "placed": -1,
            "left_workspace": bool(self.left.any()),
            "is_success": self.active >= self.n_objects,
            "sim_time": self.time,
        }

    def observe(self) -> dict[str, np.ndarray]:
        """Centralised observation (float32), in the common frame: origin at the active
        object's position (after the last object succeeded: the last object's), world axes
        or (``frame="goal"``) x pointing from the object to its goal.

        ``robots`` (N, 2) robot centres; ``object`` (2,) cos, sin of the object's heading;
        ``goal`` (4,) goal position, cos, sin of the goal heading; ``extent`` (2,) half
        extents of the object's bounding box in its own frame; ``patch`` (N, P, P) free
        clearance of a robot centre at the samples around each robot (0: a robot centred
        there would touch an obstacle, another object or the border; 1: at least
        ``patch_range`` free), ``patch[i, r, s]`` at offset (g[s], g[r]) (common-frame axes)
        with g = (-(P-1)/2 .. (P-1)/2) * ``patch_spacing``.
        """
        k = min(self.active, self.n_objects - 1)
        pose = self._poses[k]
        goal = self.goals[k]
        rob = self.robot_positions()
        c, s = self._axes()
        offsets = self._patch_offsets
        if self.config.frame == "goal":
            ox, oy = offsets[..., 0], offsets[..., 1]
            offsets = np.stack([c * ox - s * oy, s * ox + c * oy], axis=-1)
        pts = rob[:, None, None, :] + offsets[None]  # (N, P, P, 2)
        idx = np.rint(pts / self._h).astype(np.intp) + self._patch_shift
        ny, nx = self._patch_field.shape
        i = np.clip(idx[..., 0], 0, nx - 1)
        j = np.clip(idx[..., 1], 0, ny - 1)
        rel = rob - pose[:2]
        gx, gy = goal[0] - pose[0], goal[1] - pose[1]
        phi = math.atan2(s, c)
        return {
            "robots": np.stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]],
                               axis=1).astype(np.float32),
            "object": np.array([math.cos(pose[2] - phi), math.sin(pose[2] - phi)], np.float32),
            "goal": np.array(
                [c * gx + s * gy, -s * gx + c * gy, math.cos(goal[2] - phi),
                 math.sin(goal[2] - phi)],
                np.float32,
            ),
            "extent": self.extents[k].astype(np.float32),
            "patch": self._patch_field[j, i],
        }
