"""What the manipulation model promises the layers that call it.

The model (``lamp.manip``) proposes contacts and pushes for a requested object motion; the
object lattice (``lamp.search``) only asks for motions inside its range, and its training
data is drawn from that range. Both read it here, so the search layer does not load the
model's package to learn one tuple.
"""

from __future__ import annotations

__all__ = ["MAX_ROBOTS", "MOTION_RANGE"]

MOTION_RANGE = (0.2, 0.2, 0.5)
"""The requested motions the model is trained for (object frame): |dx|, |dy| (m) and
|dtheta| (rad) at most this. The training data draws from it, the network scales by it and
the object lattice keeps its primitives inside it."""
MAX_ROBOTS = 3
"""Largest robot budget the proposers support."""
