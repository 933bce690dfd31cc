"""D* Lite (Koenig and Likhachev, 2002), optimised version, generic over a graph protocol.

The search runs backwards from the goal: ``g(s)`` and ``rhs(s)`` estimate the cost from
``s`` to the goal, and the priority queue ``U`` orders locally inconsistent vertices by
``[min(g, rhs) + h(s_start, s) + k_m; min(g, rhs)]``. Comments ``{NN'}`` cite the lines of
the optimised pseudocode (Fig. 4 of S. Koenig and M. Likhachev, "D* Lite", AAAI 2002).

LAMP-Lazy (the paper's Alg. 2) uses it through the paper's three procedures:
``initialize(goal)`` (Alg. 2 line 1), ``plan_shortest_path(start)`` (line 11) and
``update_change(u, v, cost)`` (lines 18 and 31: a failed transition is penalised).

Departures from the pseudocode, each for a reason:

* Moving start, lazily: instead of updating ``k_m`` when edge costs change ({38'}),
  ``plan_shortest_path`` adds ``h(s_last, s_start)`` whenever the start has moved since the
  last call. Keys computed earlier stay lower bounds because ``h`` obeys the triangle
  inequality, which is all {14'} needs.
* Virtual start: the start may be a continuous pose that is not a graph vertex; it is a
  virtual vertex with the out-edges given to ``plan_shortest_path(start_edges=...)``. It
  has no in-edges, so replacing it by the next virtual start never invalidates another
  vertex's ``rhs``. ``graph.heuristic`` must accept it (``ObjectLattice`` takes poses).
* Start edges cheaper than the heuristic: an edge (s_start, v) may cost less than
  ``h(s_start, v)`` (a lattice's joining motion costs its true length, its heuristic is the
  lattice metric). With ``slack = max(0, max_v h(s_start, v) - c(s_start, v))`` the keys
  use ``h'(s) = max(0, h(s_start, s) - slack)``: a constant shift keeps {01'}'s keys
  monotone along graph edges, and ``h'(v) <= c(s_start, v)`` on the start's edges, so h'
  is consistent. Moving the start adds ``h(s_last, s_start) + slack`` to k_m (the new
  start's slack; then every old key stays a lower bound). Replanning from the same start
  recomputes the slack with the costs ``update_change`` gave its edges; when it grows,
  k_m grows by as much.
* Termination {10'} uses ``rhs(s_start) != g(s_start)`` (the basic version's test) rather
  than ``>``, so the start is always locally consistent when the path is read off; and it
  keeps expanding vertices whose first key component is within a relative ``1e-9`` of the
  start's. On a lattice whose heuristic is exact along straight paths (the octile metric
  of ``ObjectLattice``) every vertex of a straight shortest path has exactly the start's
  first key component, so floating-point rounding alone decides whether it is expanded;
  an inconsistent one left behind breaks the path read off by {34'} (found by
  ``benchmarks/bench_search.py``, now a regression test).
* ``UpdateVertex`` ({21'}, {28'}) is called only for vertices whose ``rhs`` changed: for
  the others g, rhs and queue membership are unchanged and a queued key, being a lower
  bound, stays valid ({14'} refreshes it). This saves most calls on a 26-connected lattice.
* ``g`` is stored only where it differs from ``rhs`` (``_gx``): a vertex is locally
  inconsistent exactly when it has an entry there, and every other vertex's ``g`` is its
  ``rhs``. Expanded vertices are consistent, so a search keeps one table of its closed
  set, not two (on the depots' 300,000-expansion searches, ~300,000 entries fewer).
  Every write to ``rhs`` keeps ``g`` as it was; the values and the order of expansions
  are those of two tables.
* ``h(s_start, .)`` is memoised per start, for at most :data:`H_KEPT` vertices at once.
* Between calls a search may hold its tables in arrays (``pack``,
  :mod:`lamp.search.dstar_tables`); the next call unpacks the same tables and queue order.
* ``U`` is a ``heapq`` with lazy deletion: a dict holds each queued vertex's one current
  heap entry (key, sequence number, vertex); any other entry is stale and skipped when it
  reaches the top. Re-queueing a vertex with the key it is queued with keeps its entry.
  Ties of keys go to the lower number, so the order in which vertices leave the queue is
  fixed by the live entries alone, and the heap is rebuilt from them, keeping their
  numbers, whenever the stale entries pass :data:`HEAP_SLACK` times the live ones (and
  :data:`HEAP_FLOOR`): when it is rebuilt changes nothing.
* Expansion and time limits: ``compute_shortest_path`` stops with a status; its state stays
  consistent, so a later call simply continues.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass, field

from lamp.search.dstar_tables import PackedTables
from lamp.search.graph import Graph, SearchStatus

INF = math.inf
#: relative tolerance on key comparisons in the termination test (see compute_shortest_path)
KEY_RTOL = 1e-9
#: The heap is rebuilt from its live entries when its stale ones pass this many times the
#: live ones plus :data:`HEAP_FLOOR` (memory against the rebuilds' time; order unchanged).
HEAP_SLACK, HEAP_FLOOR = 0.5, 1024
#: The memo of h(s_start, .) is emptied when it holds this many vertices (memory; h is a
#: function of the vertex and the start, so nothing else changes).
H_KEPT = 1 << 14
#: ``pack`` holds a search's tables in arrays from this many vertices with an ``rhs`` on.
PACK_FROM = 4096

Key = tuple[float, float]
#: Marks a vertex with no entry in ``DStarLite._gx`` (its g is its rhs).
_SAME = object()


@dataclass
class DStarStats:
    """Counters since construction (``expansions``) and for the last call (``last_*``)."""

    expansions: int = 0
    calls: int = 0
    last_expansions: int = 0
    last_time_s: float = 0.0
    edge_updates: int = 0
    history: list[tuple[int, float]] = field(default_factory=list)


class DStarLite:
    """Incremental shortest paths to a fixed goal from a moving start.

    Args:
        graph: see :class:`Graph`.
        max_expansions: per ``plan_shortest_path`` call (None: unlimited).
        time_limit: seconds per ``plan_shortest_path`` call (None: unlimited).
    """

    def __init__(
        self,
        graph: Graph,
        *,
        max_expansions: int | None = None,
        time_limit: float | None = None,
    ) -> None:
        if max_expansions is not None and max_expansions < 1:
            raise ValueError(f"max_expansions must be >= 1 or None, got {max_expansions!r}")
        if time_limit is not None and not time_limit > 0:
            raise ValueError(f"time_limit must be > 0 or None, got {time_limit!r}")
        self.graph = graph
        self.max_expansions = max_expansions
        self.time_limit = time_limit
        self.goal: Hashable | None = None
        self.status = SearchStatus.NOT_INITIALIZED
        self.stats = DStarStats()
        self._reset()

    def _reset(self) -> None:
        self.km = 0.0
        self._gx: dict[Hashable, float] = {}  # g where it differs from rhs (departures)
        self.rhs: dict[Hashable, float] = {}
        self._heap: list[tuple[float, float, int, Hashable]] = []
        self._open: dict[Hashable, tuple[float, float, int, Hashable]] = {}  # its entry
        self._seq = itertools.count()
        self.start: Hashable | None = None
        self._hcache: dict[Hashable, float] = {}
        self._hslack = 0.0
        self._last: Hashable | None = None
        self._vstart: Hashable | None = None
        self._vedges: dict[Hashable, float] = {}
        self._over_out: dict[Hashable, dict[Hashable, float]] = {}
        self._over_in: dict[Hashable, dict[Hashable, float]] = {}
        self._packed: PackedTables | None = None  # the tables while packed (``pack``)

    def g_of(self, s: Hashable) -> float:
        """g(s): its entry in ``_gx`` where it has one, else rhs(s) (``inf`` when unknown)."""
        v = self._gx.get(s, _SAME)
        return self.rhs.get(s, INF) if v is _SAME else v  # type: ignore[return-value]

    def _set_rhs(self, s: Hashable, v: float) -> None:
        """rhs(s) = v, g(s) unchanged."""
        gx, rhs = self._gx, self.rhs
        if s not in gx:
            gx[s] = rhs.get(s, INF)
        rhs[s] = v
        if gx[s] == v:
            del gx[s]

    def _set_g(self, s: Hashable, v: float) -> None:
        """g(s) = v."""
        if v == self.rhs.get(s, INF):
            self._gx.pop(s, None)
        else:
            self._gx[s] = v

    # ----------------------------------------------------------- edges
    def _succ(self, u: Hashable) -> Iterable[tuple[Hashable, float]]:
        if u == self._vstart and self._vstart is not None:
            edges: Iterable[tuple[Hashable, float]] = self._vedges.items()
        else:
            edges = self.graph.successors(u)
        ov = self._over_out.get(u)
        if ov:
            return [(v, ov.get(v, c)) for v, c in edges]
        return edges

    def _pred(self, v: Hashable) -> list[tuple[Hashable, float]] | Iterable[tuple[Hashable, float]]:
        vs = self._vstart
        if vs is not None and v == vs:
            return ()  # the virtual start has no in-edges
        edges: Iterable[tuple[Hashable, float]] = self.graph.predecessors(v)
        if vs is not None and v in self._vedges:
            edges = [*edges, (vs, self._vedges[v])]
        ov = self._over_in.get(v)
        if ov:
            return [(u, ov.get(u, c)) for u, c in edges]
        return edges

    def base_cost(self, u: Hashable, v: Hashable) -> float:
        """The edge cost before any ``update_change`` (``inf`` when not an edge)."""
        if u == self._vstart and self._vstart is not None:
            return self._vedges.get(v, INF)
        return self.graph.cost(u, v)

    def cost(self, u: Hashable, v: Hashable) -> float:
        """The current cost c(u, v), including changes made by ``update_change``."""
        ov = self._over_out.get(u)
        if ov is not None and v in ov:
            return ov[v]
        return self.base_cost(u, v)

    # ----------------------------------------------------------- queue
    def _h(self, s: Hashable) -> float:
        """h'(s) = max(0, h(s_start, s) - slack), memoised for the current start."""
        memo = self._hcache
        h = memo.get(s)
        if h is None:
            if len(memo) >= H_KEPT:
                memo.clear()
            h = self.graph.heuristic(self.start, s) - self._hslack
            h = memo[s] = h if h > 0.0 else 0.0
        return h

    def _start_slack(self, start: Hashable, edges: dict[Hashable, float]) -> float:
        """max_v h(start, v) - c(start, v) over the virtual start's edges ``{v: c}``."""
        h = self.graph.heuristic
        return max((h(start, v) - c for v, c in edges.items()), default=0.0) if edges else 0.0

    def calculate_key(self, s: Hashable) -> Key:
        """{01'} [min(g, rhs) + h(s_start, s) + k_m; min(g, rhs)]."""
        m = self.rhs.get(s, INF)
        g = self._gx.get(s, m)
        if g < m:
            m = g
        return (m + self._h(s) + self.km, m)

    def _push(self, s: Hashable, key: Key) -> None:
        open_ = self._open
        cur = open_.get(s)
        if cur is not None and cur[0] == key[0] and cur[1] == key[1]:
            return  # queued with this key: its entry stays current
        entry = open_[s] = (key[0], key[1], next(self._seq), s)
        heapq.heappush(self._heap, entry)
        if len(self._heap) - len(open_) > HEAP_SLACK * len(open_) + HEAP_FLOOR:
            self._heap = list(open_.values())
            heapq.heapify(self._heap)

    def _top(self) -> tuple[Key, Hashable | None]:
        heap, open_ = self._heap, self._open
        while heap:
            entry = heap[0]
            if open_.get(entry[3]) is entry:
                return (entry[0], entry[1]), entry[3]
            heapq.heappop(heap)
        return (INF, INF), None

    def update_vertex(self, u: Hashable) -> None:
        """{07'}-{09'}: (re)queue ``u`` iff it is locally inconsistent."""
        if u in self._gx:  # g != rhs
            self._push(u, self.calculate_key(u))  # {07'} update / {08'} insert
        elif u in self._open:
            del self._open[u]  # {09'} remove (lazily from the heap)

    # ----------------------------------------------------------- API
    def initialize(self, goal: Hashable) -> None:
        """{02'}-{06'}: an empty search rooted at ``goal`` (Alg. 2 line 1).

        The goal's first key uses h = 0 (the start is not known yet); {14'} corrects it.
        """
        self._reset()
        self.goal = goal
        self._set_rhs(goal, 0.0)  # {05'}
        self._push(goal, (0.0, 0.0))  # {06'}
        self.status = SearchStatus.NOT_INITIALIZED

    def _set_start(
        self, start: Hashable, start_edges: Sequence[tuple[Hashable, float]] | None
    ) -> None:
        """Move the start, update k_m ({38'}-{39'}) and the virtual start's edges."""
        edges: dict[Hashable, float] = {}
        for v, c in start_edges or ():
            if not (c >= 0):
                raise ValueError(f"start edge cost must be >= 0, got {c!r} to {v!r}")
            edges[v] = min(float(c), edges.get(v, INF))
        # the same virtual start keeps the costs update_change gave its edges
        kept = self._over_out.get(start, {}) if edges and start == self._vstart else {}
        slack = max(0.0, self._start_slack(start, {v: kept.get(v, c) for v, c in edges.items()}))
        if self._last is None:
            self._last = start  # {29'}
        elif start != self._last:
            self.km += self.graph.heuristic(self._last, start) + slack  # {38'}
            self._last = start  # {39'}
        elif slack > self._hslack:  # same start, cheaper edges: see the departures
            self.km += slack - self._hslack
        if start != self.start or slack != self._hslack:
            self._hcache = {}
        self._hslack = slack
        self.start = start
        old_v = self._vstart
        if old_v is not None and (start_edges is None or old_v != start):
            # the previous virtual start has no in-edges: dropping it affects no rhs
            self._gx.pop(old_v, None)
            self.rhs.pop(old_v, None)
            self._open.pop(old_v, None)
            self._over_out.pop(old_v, None)
            for v in self._vedges:
                d = self._over_in.get(v)
                if d is not None:
                    d.pop(old_v, None)
            self._vstart, self._vedges = None, {}
        if start_edges is None:
            return
        if start == self.goal:
            raise ValueError("a virtual start must not be the goal vertex")
        self._vstart, self._vedges = start, edges
        # rhs of the virtual start from its (possibly new) out-edges, {27'}-style
        g_of = self.g_of
        self._set_rhs(start, min((c + g_of(v) for v, c in self._succ(start)), default=INF))
        self.update_vertex(start)

    def compute_shortest_path(self) -> SearchStatus:
        """{10'}-{28'}: repair g until the start is consistent and no key below it is queued."""
        if self.goal is None or self.start is None:
            raise RuntimeError("call initialize(goal) and plan_shortest_path(start) first")
        t0 = time.perf_counter()
        start = self.start
        gx, rhs, g_of = self._gx, self.rhs, self.g_of
        goal = self.goal
        n = 0
        max_exp = self.max_expansions
        deadline = None if self.time_limit is None else t0 + self.time_limit
        status = SearchStatus.SUCCESS
        while True:
            k_old, u = self._top()  # {11'}-{12'}
            k_start = self.calculate_key(start)
            # {10'} with a rounding tolerance on the first key component: vertices on a
            # shortest path have k1 equal to the start's in exact arithmetic, and a stale one
            # left behind by an ulp would derail the path extraction
            tol = KEY_RTOL * (1.0 + abs(k_start[0])) if k_start[0] < INF else 0.0
            if not (k_old[0] <= k_start[0] + tol or start in gx):
                break
            if u is None:  # queue empty: the start cannot be made consistent
                break
            if max_exp is not None and n >= max_exp:
                status = SearchStatus.EXPANSION_LIMIT
                break
            if deadline is not None and (n & 63) == 0 and time.perf_counter() > deadline:
                status = SearchStatus.TIME_LIMIT
                break
            n += 1
            k_new = self.calculate_key(u)  # {13'}
            rhs_u = rhs.get(u, INF)
            g_u = gx.get(u, rhs_u)
            if k_old < k_new:  # {14'}
                self._push(u, k_new)  # {15'}
            elif g_u > rhs_u:  # {16'} overconsistent
                del gx[u]  # {17'} g(u) = rhs(u)
                del self._open[u]  # {18'}
                for s, c in self._pred(u):  # {19'}
                    if s != goal:
                        v = c + rhs_u
                        if v < rhs.get(s, INF):
                            self._set_rhs(s, v)  # {20'}
                            self.update_vertex(s)  # {21'} (only when rhs(s) changed)
            else:  # {22'} underconsistent
                g_old = g_u  # {23'}
                self._set_g(u, INF)  # {24'}
                for s, c in self._pred(u):  # {25'}
                    if s != goal and rhs.get(s, INF) == c + g_old:  # {26'}
                        self._set_rhs(s, min(  # {27'}
                            (c2 + g_of(s2) for s2, c2 in self._succ(s)), default=INF
                        ))
                        self.update_vertex(s)  # {28'} (only when rhs(s) was recomputed)
                self.update_vertex(u)  # {25'}-{28'} for s = u
        dt = time.perf_counter() - t0
        self.stats.expansions += n
        self.stats.last_expansions = n
        self.stats.last_time_s = dt
        return status

    def plan_shortest_path(
        self,
        start: Hashable,
        start_edges: Sequence[tuple[Hashable, float]] | None = None,
    ) -> list[Hashable]:
        """Compute or repair the shortest path from ``start`` to the goal (Alg. 2 line 11).

        ``start`` is a graph vertex, or, when ``start_edges`` is given, a virtual vertex
        (hashable, not in the graph, e.g. a pose tuple) with out-edges ``[(v, cost)]``.
        Returns the vertex path ``[start, ..., goal]``, or ``[]`` on failure; ``status``
        says why (``NO_PATH``, ``EXPANSION_LIMIT``, ``TIME_LIMIT``) and ``path_cost()``
        gives the cost.
        """
        if self.goal is None:
            raise RuntimeError("call initialize(goal) before plan_shortest_path")
        self._unpack()
        self.stats.calls += 1
        self._set_start(start, start_edges)
        status = self.compute_shortest_path()
        self.stats.history.append((self.stats.last_expansions, self.stats.last_time_s))
        if status is not SearchStatus.SUCCESS:
            self.status = status
            return []
        if self.g_of(start) == INF:
            self.status = SearchStatus.NO_PATH
            return []
        self.status = SearchStatus.SUCCESS
        return self._extract_path(start)

    def path_cost(self, start: Hashable | None = None) -> float:
        """g(start): the cost of the current shortest path (``inf`` when none)."""
        self._unpack()
        return self.g_of(self.start if start is None else start)

    def _extract_path(self, start: Hashable) -> list[Hashable]:
        """{34'}: follow argmin_{s'} c(s, s') + g(s') from the start to the goal."""
        path = [start]
        s = start
        seen = {start}
        g_of = self.g_of
        while s != self.goal:
            best, best_v = INF, None
            for v, c in self._succ(s):
                val = c + g_of(v)
                if val < best:
                    best, best_v = val, v
            if best_v is None or best_v in seen:
                # cannot happen for a consistent start and positive costs
                raise RuntimeError(f"D* Lite path extraction failed at {s!r}")
            path.append(best_v)
            seen.add(best_v)
            s = best_v
        return path

    def update_change(self, u: Hashable, v: Hashable, new_cost: float) -> None:
        """{40'}-{47'}: the cost of edge u -> v becomes ``new_cost`` (``inf`` marks it
        invalid). Used by LAMP-Lazy to penalise a transition that failed verification
        (``UpdateChange``, Alg. 2 lines 18 and 31). The path is repaired by the next ``plan_shortest_path``.
        """
        if self.goal is None:
            raise RuntimeError("call initialize(goal) before update_change")
        if not (new_cost >= 0):
            raise ValueError(f"new_cost must be >= 0 (or inf), got {new_cost!r}")
        self._unpack()
        if self.base_cost(u, v) == INF:
            raise ValueError(f"({u!r}, {v!r}) is not an edge of the graph")
        c_old = self.cost(u, v)  # {41'}
        new_cost = float(new_cost)
        self._over_out.setdefault(u, {})[v] = new_cost  # {42'}
        self._over_in.setdefault(v, {})[u] = new_cost
        self.stats.edge_updates += 1
        if u == self.goal:
            return
        g_of = self.g_of
        g_v = g_of(v)
        if c_old > new_cost:  # {43'}
            if new_cost + g_v < self.rhs.get(u, INF):
                self._set_rhs(u, new_cost + g_v)  # {44'}
        elif self.rhs.get(u, INF) == c_old + g_v:  # {45'}
            self._set_rhs(u, min(  # {46'}
                (c + g_of(s) for s, c in self._succ(u)), default=INF
            ))
        if self.start is not None:
            self.update_vertex(u)  # {47'}
        elif u in self._gx:  # g(u) != rhs(u)
            self._push(u, (0.0, 0.0))  # no start yet: a lower-bound key, fixed by {14'}

    def pack(self) -> None:
        """Hold the tables in arrays (:mod:`lamp.search.dstar_tables`) until the next
        ``plan_shortest_path``, ``update_change`` or ``path_cost``, which unpack them: the
        same tables and queue order, so nothing changes; for a search waiting between
        calls. Searches of fewer than :data:`PACK_FROM` vertices stay as they are."""
        if self._packed is None and len(self.rhs) >= PACK_FROM:
            self._packed = PackedTables.of(self.rhs, self._gx, self._open)
            self.rhs = self._gx = self._open = self._heap = None  # type: ignore[assignment]
            self._hcache = {}

    def _unpack(self) -> None:
        if self._packed is not None:
            self.rhs, self._gx, self._open, self._heap = self._packed.tables()
            self._packed = None

    def release(self) -> None:
        """Forget the search (g, rhs, the queue and the memo of h), keeping the goal, the
        edge costs ``update_change`` gave, the status and the counters: a search its
        caller will not continue gives its memory back. A later ``plan_shortest_path``
        searches anew from the goal, with those costs."""
        if self.goal is None:
            raise RuntimeError("call initialize(goal) before release")
        over_out, over_in = self._over_out, self._over_in
        status, stats = self.status, self.stats
        self.initialize(self.goal)
        self._over_out, self._over_in = over_out, over_in
        self.status, self.stats = status, stats

    def penalize(self, u: Hashable, v: Hashable, penalty: float) -> float:
        """Increase the cost of u -> v by ``penalty`` (the paper's edge penalty); returns
        the new cost."""
        if not (penalty >= 0):
            raise ValueError(f"penalty must be >= 0, got {penalty!r}")
        new = self.cost(u, v) + penalty
        self.update_change(u, v, new)
        return new
