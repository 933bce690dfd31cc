"""Simulation: MuJoCo execution of synchronised robot paths that push objects.

``Simulator(scene).execute(robot_paths)`` -> ``ExecutionResult``; see
``lamp.sim.simulator`` for timing, control and the workspace check, and ``lamp.sim.mjcf``
for the physical model. MuJoCo is imported only when this package is.
"""

from lamp.sim.simulator import (
    MAX_START_GAP,
    MAX_STEP,
    ROBOT_SPEED,
    SETTLE_TIME,
    WORKSPACE_TOLERANCE,
    ExecutionResult,
    SimState,
    Simulator,
    Trace,
    footprint_outside,
)
from lamp.sim.stability import SimulationError

__all__ = [
    "MAX_START_GAP",
    "MAX_STEP",
    "ROBOT_SPEED",
    "SETTLE_TIME",
    "WORKSPACE_TOLERANCE",
    "ExecutionResult",
    "SimState",
    "SimulationError",
    "Simulator",
    "Trace",
    "footprint_outside",
]
