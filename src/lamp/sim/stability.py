"""A simulation that goes unstable is an error naming the step, never a result.

MuJoCo, when a state turns non-finite or huge (``mj_checkPos``, ``mj_checkVel``,
``mj_checkAcc``: beyond ``mjMAXVAL`` = 1e10), warns, *resets the data to the model's
initial state* and carries on; the objects would then be reported where the reset put
them. Its default warning handler also writes ``MUJOCO_LOG.TXT`` into the working folder.

Here:

- :func:`install_warning_handler` routes MuJoCo's warnings to the ``lamp.sim`` logger
  (no file lands in the user's folder); a handler the caller installed first is kept;
- :class:`StabilityWatch` reads MuJoCo's warning counters (they survive the reset) after
  each stretch of steps and raises :class:`SimulationError` naming the step, the simulated
  time and MuJoCo's message. Inputs are refused before they get here where a bound is
  known (``lamp.scene.physics``, the loader's angle bound); this is the last line.
"""

from __future__ import annotations

import logging

import mujoco

from lamp.errors import InputError

__all__ = ["SimulationError", "StabilityWatch", "install_warning_handler"]

_LOG = logging.getLogger("lamp.sim")
#: MuJoCo's warnings that mean the state was non-finite or huge and has been reset.
UNSTABLE = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
            mujoco.mjtWarning.mjWARN_BADQACC)


class SimulationError(InputError):
    """The scene cannot be simulated: the physics state turned non-finite or huge (the
    message names the step). An input error (exit status 2): its cause is a scene whose
    values the simulator cannot serve."""


def _handler(message: str) -> None:
    _LOG.warning("MuJoCo: %s", message.strip())


def install_warning_handler() -> None:
    """Route MuJoCo's warnings to the ``lamp.sim`` logger unless a handler is set."""
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(_handler)


class StabilityWatch:
    """Raises :class:`SimulationError` once MuJoCo has reported an unstable state on
    ``data`` since this watch was made (or since its last check)."""

    def __init__(self, data: mujoco.MjData) -> None:
        self.data = data
        self._seen = self._count()

    def _count(self) -> int:
        return sum(int(self.data.warning[int(w)].number) for w in UNSTABLE)

    def check(self, step: int, start_time: float, timestep: float) -> None:
        """``step``: the physics steps of the call done so far (the error names them)."""
        if self._count() == self._seen:
            return
        what = "; ".join(
            f"a non-finite or huge value in {w.name.removeprefix('mjWARN_BAD').upper()} at "
            f"DOF {int(self.data.warning[int(w)].lastinfo)}"
            for w in UNSTABLE if self.data.warning[int(w)].number)
        raise SimulationError(
            f"the simulation went unstable within the first {step} physics steps of a motion "
            f"starting at t = {start_time:.3f} s (by t = {start_time + step * timestep:.3f} "
            f"s): {what}; the scene's values (masses, speeds, poses) cannot be simulated")
