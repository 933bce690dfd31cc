"""Anonymous multi-robot motion planning (Gspi: Goal Swapping with Priority Inheritance).

``plan_paths(scene, starts, goals, ...) -> MRMPPlan`` routes N disk robots to M <= N goal
points (any robot may take any goal) with synchronised, collision-free paths. See
:mod:`lamp.mrmp.gspi` for the algorithm and its guarantees.
"""

from lamp.mrmp.gspi import MRMPPlan, plan_paths

__all__ = ["MRMPPlan", "plan_paths"]
