"""A sub-team's segment on the fleet's shared clock: its rows re-timed to the common row
grid, how far it has run, and the space it still needs.

Every closed loop hands its executor robot paths whose rows are timed by the simulator's
rule (``Simulator.row_durations``: a row lasts its longest robot step over the driving
speed). Segments of several sub-teams run in one simulator, so each is first re-timed on
its own (:func:`on_grid`): its robots' positions at multiples of ``row_step / speed``
seconds after it starts. Rows of several re-timed segments then stack into one set of
paths in which every sub-team moves as it would alone, and no row steps further than
``row_step``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely

from lamp.contract.events import TRACE_EVERY
from lamp.contract.trajectory import straight_moves
from lamp.fleet.config import REJOIN_SLACK
from lamp.fleet.regions import OBJECT_MARGIN, swept
from lamp.geometry.shapes import to_shapely
from lamp.scene.model import Shape
from lamp.sim.simulator import SETTLE_TIME

__all__ = ["REJOIN_GAP", "Segment", "TOUCH_TOLERANCE", "on_grid", "run_together"]

#: A robot that starts a segment near its object (left in contact by the last push) counts
#: as pushing once it comes this much (m) nearer than it stood.
TOUCH_TOLERANCE = 0.002
#: A robot farther than this (m) from its next row moves back to it first (the simulator
#: takes paths that start within ``MAX_START_GAP`` = 0.05 m of the robots).
REJOIN_GAP = 0.03


def on_grid(start: np.ndarray, paths: np.ndarray, row_step: float) -> np.ndarray:
    """``paths`` (N, T, 2) of robots now at ``start`` (N, 2) re-timed to rows ``row_step /
    speed`` seconds apart: (N, G, 2), G >= 1, the last row the paths' last. Rows in which
    no robot moves take no time (as in the simulator) and are dropped; each robot's
    position between two rows is interpolated linearly, so no step exceeds ``row_step``."""
    paths = np.asarray(paths, float)
    way = np.concatenate([np.asarray(start, float)[:, None], paths], axis=1)
    dur = np.hypot(*np.moveaxis(np.diff(way, axis=1), 2, 0)).max(axis=0)  # (T,) in metres
    keep = np.concatenate([[True], dur > 1e-12])
    way = way[:, keep]
    tau = np.concatenate([[0.0], np.cumsum(dur[dur > 1e-12])])
    n = max(1, int(np.ceil(tau[-1] / row_step - 1e-9)))
    grid = np.minimum(row_step * np.arange(1, n + 1), tau[-1])
    out = np.empty((way.shape[0], n, 2))
    for i in range(way.shape[0]):
        for axis in (0, 1):
            out[i, :, axis] = np.interp(grid, tau, way[i, :, axis])
    out[:, -1] = paths[:, -1]  # also after rows of moves below 1e-12 m, dropped
    return out


@dataclass
class Segment:
    """One object's segment, submitted by its loop and then run on the shared clock."""

    index: int  # the object
    team: list[int]  # the robots, in the order of ``rows``
    rows: np.ndarray  # (n, G, 2) on the grid
    poses: np.ndarray  # (P, 3) the object poses the segment plans to pass
    stop: Callable[[np.ndarray], bool] | None
    shape: Shape
    robot_radius: float
    cursor: int = 0
    sim_time: float = 0.0
    left: bool = False
    stopped_at: int | None = None
    rejoined: int = 0  # times its robots moved back to their rows (:meth:`rejoin`)
    #: its rows when submitted, and how many its rejoins have inserted since
    planned: int = field(init=False)
    added: int = field(default=0, init=False)
    #: the first row at which a robot may touch the object (:meth:`first_touch`); before
    #: it the object stands at its first planned pose
    touch: int = field(init=False)
    #: the spaces it takes, filled on first use: where its object may be (``spacetime``;
    #: the planned poses never change, so neither do these) and its :meth:`core` (renewed
    #: when a rejoin changes the rows)
    spaces: dict[str, shapely.Geometry] = field(default_factory=dict, init=False, repr=False,
                                                compare=False)
    #: boxes (and its :meth:`ends`) derived from its rows, filled on first use and kept
    #: with the rows they came from (``spacetime.reach_box``)
    bounds: dict[str, tuple] = field(default_factory=dict, init=False, repr=False,
                                     compare=False)

    def __post_init__(self) -> None:
        self.touch = self.first_touch()
        self.planned = int(self.rows.shape[1])

    def first_touch(self) -> int:
        """The first row from which the segment's robots may move the object: the start
        of the first row-to-row move (a straight line) on which a robot comes closer to
        the object at its first planned pose than ``OBJECT_MARGIN`` beyond its radius and
        than ``TOUCH_TOLERANCE`` nearer than it stood at row 0 (a robot left in contact
        by the last push, moving away or along, pushes nothing). Before that row the
        object stands where it stood (within the margin a drifted start has). 0 when no
        robot comes near (nothing known: the object may move from the start)."""
        rows = self.rows
        if rows.shape[1] < 2:
            return 0
        body = to_shapely(self.shape, self.poses[0])
        d0 = shapely.distance(body, shapely.points(rows[:, 0]))
        limit = np.minimum(self.robot_radius + OBJECT_MARGIN, d0 - TOUCH_TOLERANCE)
        moves = shapely.linestrings(np.stack([rows[:, :-1], rows[:, 1:]], axis=2).reshape(-1, 2, 2))
        dist = shapely.distance(body, moves).reshape(rows.shape[0], -1)
        hit = np.flatnonzero((dist < limit[:, None]).any(axis=0))
        return int(hit[0]) if hit.size else 0

    @property
    def remaining(self) -> int:
        return self.rows.shape[1] - self.cursor

    @property
    def done(self) -> bool:
        return self.cursor >= self.rows.shape[1] or self.stopped_at is not None

    def rejoin(self, positions: np.ndarray, row_step: float, limit: int = 0,
               slack: float = REJOIN_SLACK) -> None:
        """Robots that stand more than ``REJOIN_GAP`` from the next row (nudged while they
        held, or held back by what they push) first move straight back to it: rows are
        inserted before it. The segment ends instead, stopped where it stands
        (``stopped_at``, as a push watch stops one), when those rows would take the rows
        inserted over its life past ``slack`` times its planned rows (``inf``: never), or
        at the ``limit``-th rejoin (0: no limit); its loop sees what the push achieved, a
        stall or drift, and plans anew.

        Guarantee (tested, Hypothesis): ``added <= slack * planned`` always, so a segment
        whose every event runs at least one of its rows ends within ``(1 + slack) *
        planned`` events, whatever holds its robots back; a sequential run's push ends
        on time, here the slack is what a jammed push is given on top."""
        gap = np.hypot(*(np.asarray(positions, float) - self.rows[:, self.cursor]).T)
        if gap.max() <= REJOIN_GAP:
            return
        self.rejoined += 1
        back = straight_moves(np.asarray(positions, float), self.rows[:, self.cursor], row_step)
        if 0 < limit <= self.rejoined or self.added + back.shape[1] > slack * self.planned:
            self.stopped_at = 0
            return
        self.added += back.shape[1]
        self.rows = np.concatenate([back, self.rows[:, self.cursor:]], axis=1)
        self.spaces.pop("core", None)
        # a push under way goes on moving the object; one not begun begins as late as the
        # inserted rows delay it, or as early as they come near the object
        self.touch = 0 if self.touch <= self.cursor else min(
            back.shape[1] + self.touch - self.cursor, self.first_touch())
        self.cursor = 0

    def ends(self) -> tuple[shapely.Geometry, shapely.Geometry]:
        """Where its bodies stand before and after it (with margins): its object at the
        first and last planned pose, its robots at their first and last rows; kept in
        ``bounds`` with the rows they came from (a waiting segment is asked at every
        event)."""
        cached = self.bounds.get("ends_bodies")
        if cached is not None and cached[0] is self.rows:
            return cached[1]
        ends = (swept(self.shape, self.poses[:1], self.rows[:, :1], self.robot_radius),
                swept(self.shape, self.poses[-1:], self.rows[:, -1:], self.robot_radius))
        self.bounds["ends_bodies"] = (self.rows, ends)
        return ends

    def core(self) -> shapely.Geometry:
        """Its bodies exactly as planned (``regions.swept(..., margins=False)``), prepared;
        computed once for its rows."""
        core = self.spaces.get("core")
        if core is None:
            core = swept(self.shape, self.poses, self.rows, self.robot_radius, margins=False)
            shapely.prepare(core)
            self.spaces["core"] = core
        return core


def run_together(executor: Any, running: Sequence[Segment]
                 ) -> tuple[Any, np.ndarray, int, list[Segment]]:
    """Run the ``running`` segments' next rows stacked into one set of paths on
    ``executor`` (robots in none of them stand where they are) until the first segment
    ends, or a push watch stops one; its settle time only when every segment ends there
    (else their held rows settle). Returns the execution, the paths, how many rows every
    segment ran (those whose time had come when a watch stopped them), and the segments
    whose watch fired. Moves no cursor."""
    now = np.asarray(executor.robot_positions, float)
    n_rows = min(s.remaining for s in running)
    paths = np.repeat(now[:, None], n_rows, axis=1)
    for s in running:
        paths[s.team] = s.rows[:, s.cursor:s.cursor + n_rows]
    fired: list[Segment] = []

    def stop(poses: np.ndarray) -> bool:
        for s in running:
            if s.stop is not None and s.stop(poses):
                fired.append(s)
        return bool(fired)

    watched = any(s.stop is not None for s in running)
    tau = np.cumsum(executor.row_durations(paths))  # when each row is reached
    every = all(s.remaining == n_rows for s in running)
    out = executor.execute(paths, record_every=TRACE_EVERY, stop=stop if watched else None,
                           settle_time=SETTLE_TIME if every else 0.0)
    done = n_rows
    if out.stopped_at is not None:
        stopped_s = out.stopped_at * float(out.sim_time) / max(1, int(out.steps))
        done = int(np.clip(np.searchsorted(tau, stopped_s + 1e-9, side="right"), 0, n_rows))
    return out, paths, done, fired
