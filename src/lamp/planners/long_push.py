"""Long pushes: consecutive verified transitions that keep their contact formation run as
one continuous push.

A plan is a chain of verified transitions T_R = T_move (+) T_manip, one per lattice edge
(0.1-0.3 m of object motion each). Where transition k+1 starts exactly where k ends and
its approach T_move moves no robot more than ``LoopConfig.continuous_push_gap`` (the
same robots stay at the same contacts, up to centimetres), executing them one by one only
adds a stop, a settle and a new "segment" between two pushes that are really one. The
closed loop therefore executes such a run of transitions as a single segment: one
approach, then the pushes back to back, up to ``LoopConfig.long_push_length`` metres of
planned object motion and ``LoopConfig.long_push_turn`` radians of planned turn (bounds
on how long the loop goes without observing drift: a pure rotation moves the object's
origin by nothing, so without the second bound a turn in place of any size ran unobserved;
corridor-01, seed 2: three 0.39 rad turns in a bay ran as one push, the box slid instead
of turning, and the object was lost).

:func:`merge` builds the one transition that stands for the run: its approach is the
first one's, its push the concatenation of the rest (trivial approaches included, so the
executed rows are exactly those of the parts), its contacts and robot-to-contact pairing
the first push's, and its push paths those robots' merged paths expressed in the object
frame at the first pose (what a recording draws).
"""

from __future__ import annotations

import numpy as np

from lamp.contract.robots import robots_match
from lamp.contract.trajectory import concat
from lamp.contract.transition import Transition
from lamp.geometry import se2

__all__ = ["approach_travel", "continues", "merge", "take_long_push"]


def approach_travel(trans: Transition) -> float:
    """The longest distance a robot travels in ``trans``'s approach T_move (m)."""
    move = np.asarray(trans.move, float)
    if move.shape[1] < 2:
        return 0.0
    return float(np.max(np.sum(np.linalg.norm(np.diff(move, axis=1), axis=2), axis=1)))


def continues(prev: Transition, nxt: Transition, max_gap: float) -> bool:
    """Whether ``nxt`` continues ``prev``'s push: it starts where ``prev`` ends, with the
    same number of pushers, and its approach moves no robot more than ``max_gap``."""
    return (nxt.budget == prev.budget
            and robots_match(prev.robot_end, nxt.robot_start, 1e-9)
            and approach_travel(nxt) <= max_gap)


def merge(chain: list[Transition]) -> Transition:
    """One transition executing ``chain`` (consecutive, each continuing the one before)."""
    first = chain[0]
    if len(chain) == 1:
        return first
    manip = concat(first.manip, *[concat(t.move, t.manip) for t in chain[1:]])
    # the robot standing on contact j when the first push starts pushes contact j throughout
    start = np.asarray(first.manip[:, 0], float)
    contacts = np.asarray(first.contacts, float)
    gap = np.linalg.norm(start[:, None, :] - contacts[None, :, :], axis=2)  # (N, B)
    pusher = np.argmin(gap, axis=0)
    pushes_local = se2.inverse_transform_points(first.q_from, manip[pusher])
    return Transition(first.q_from, chain[-1].q_to, first.contacts, pushes_local, first.move,
                      manip, first.edge)


def _motion(trans: Transition) -> tuple[float, float]:
    """(distance the object's origin travels, |turn|) of ``trans``'s planned motion."""
    a, b = np.asarray(trans.q_from, float), np.asarray(trans.q_to, float)
    return float(np.hypot(*(b[:2] - a[:2]))), abs(float(se2.wrap_angle(b[2] - a[2])))


def take_long_push(first: Transition, pending: list[Transition], max_gap: float,
                   max_length: float, max_turn: float = float("inf")) -> list[Transition]:
    """``first`` and the transitions at the head of ``pending`` that continue it, while the
    planned object motion stays within ``max_length`` (m, summed) and its turn within
    ``max_turn`` (rad, summed |turn| of the parts); they are removed from ``pending``.
    ``first`` is always taken, whatever its own length and turn."""
    chain = [first]
    length, turn = _motion(first)
    while pending and continues(chain[-1], pending[0], max_gap):
        step, dturn = _motion(pending[0])
        if length + step > max_length + 1e-9 or turn + dturn > max_turn + 1e-9:
            break
        length += step
        turn += dturn
        chain.append(pending.pop(0))
    return chain
