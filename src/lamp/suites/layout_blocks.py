"""The block-lattice map families ``tilt`` and ``warehouse`` (see :mod:`lamp.suites.generators`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from lamp.geometry.shapes import obstacle_geometry
from lamp.suites.layout import (
    END_CLEARANCE,
    WORKSPACE,
    Layout,
    ObjectSpec,
    circle,
    graph_distances,
    obstacles_of,
    polygon,
    rect,
    street_width,
    tight_gap,
    wrap_angle,
)


# --------------------------------------------------------------------------- block lattice
def _street_offsets(streets: np.ndarray, blocks: np.ndarray) -> tuple[list[float], list[float]]:
    """Along one lattice axis, alternating streets and blocks from 0: the start of every
    street (``len(blocks) + 1`` of them) and of every block."""
    pos = 0.0
    street0, block0 = [], []
    for i in range(len(blocks)):
        street0.append(pos)
        pos += streets[i]
        block0.append(pos)
        pos += blocks[i]
    street0.append(pos)
    return street0, block0


@dataclass
class _Lattice:
    """Blocks on a (possibly rotated) lattice: columns of widths ``bu`` separated by
    streets ``su`` (one before the first column and one after the last), rows likewise;
    frame origin ``origin`` (world), rotation ``angle``."""

    bu: np.ndarray
    su: np.ndarray
    bv: np.ndarray
    sv: np.ndarray
    origin: np.ndarray
    angle: float

    def __post_init__(self) -> None:
        # street i spans [us0[i], us0[i] + su[i]] in u; column i follows street i (v alike)
        self.us0, self.uc0 = _street_offsets(self.su, self.bu)
        self.vs0, self.vr0 = _street_offsets(self.sv, self.bv)

    def world(self, u: float, v: float) -> np.ndarray:
        c, s = math.cos(self.angle), math.sin(self.angle)
        return self.origin + np.array([c * u - s * v, s * u + c * v])

    def box(self, u0: float, u1: float, v0: float, v1: float) -> tuple[float, float, float, float]:
        """World centre and size of the frame-aligned box [u0, u1] x [v0, v1]."""
        cx, cy = self.world(0.5 * (u0 + u1), 0.5 * (v0 + v1))
        return float(cx), float(cy), u1 - u0, v1 - v0


def _clip_box(
    lat: _Lattice, u0: float, u1: float, v0: float, v1: float, min_area: float = 0.02
) -> dict[str, Any] | None:
    """Obstacle dict of a lattice box clipped to the workspace (rectangle when entirely
    inside, else the convex polygon of the intersection; None when too small)."""
    W, H = WORKSPACE
    cx, cy, sx, sy = lat.box(u0, u1, v0, v1)
    d = rect(cx, cy, sx, sy, lat.angle)
    geom = obstacle_geometry(obstacles_of([d])[0])
    x0, y0, x1, y1 = geom.bounds
    if x0 >= -1e-9 and y0 >= -1e-9 and x1 <= W + 1e-9 and y1 <= H + 1e-9:
        return d
    clipped = geom.intersection(shapely.box(0.0, 0.0, W, H))
    if clipped.is_empty or clipped.geom_type != "Polygon" or clipped.area < min_area:
        return None
    # thin slivers along the border make meaningless obstacles
    if clipped.area / max(clipped.length, 1e-9) < 0.03:
        return None
    pts = np.asarray(shapely.simplify(clipped, 1e-6).exterior.coords)[:-1]
    pts = np.clip(pts, 0.0, [W, H])
    return polygon(pts)


def _lattice_graph(
    lat: _Lattice, states: dict[tuple[str, int, int], str], margin: float
) -> tuple[np.ndarray, list[tuple[int, int, float, str]]]:
    """Intersections X(i, j) of column-street i and row-street j that lie inside the
    workspace (shrunk by ``margin``) and the street segments between them with states."""
    W, H = WORKSPACE
    nu, nv = len(lat.su), len(lat.sv)
    node_id = -np.ones((nu, nv), dtype=int)
    pts = []
    for i in range(nu):
        for j in range(nv):
            if lat.su[i] <= 0 or lat.sv[j] <= 0:
                continue
            x, y = lat.world(lat.us0[i] + 0.5 * lat.su[i], lat.vs0[j] + 0.5 * lat.sv[j])
            if margin <= x <= W - margin and margin <= y <= H - margin:
                node_id[i, j] = len(pts)
                pts.append((x, y))
    edges = []
    for i in range(nu):
        for j in range(nv):
            a = node_id[i, j]
            if a < 0:
                continue
            if j + 1 < nv and node_id[i, j + 1] >= 0:  # along column-street i past row j
                b = node_id[i, j + 1]
                edges.append(
                    (a, b, float(math.dist(pts[a], pts[b])), states.get(("c", i, j), "roomy"))
                )
            if i + 1 < nu and node_id[i + 1, j] >= 0:  # along row-street j past column i
                b = node_id[i + 1, j]
                edges.append(
                    (a, b, float(math.dist(pts[a], pts[b])), states.get(("r", i, j), "roomy"))
                )
    return np.array(pts).reshape(-1, 2), edges


def _segment_box(lat: _Lattice, kind: str, i: int, j: int) -> tuple[float, float, float, float]:
    """Frame box of street segment: ('c', i, j) = column-street i beside row j;
    ('r', i, j) = row-street j beside column i."""
    if kind == "c":
        return lat.us0[i], lat.us0[i] + lat.su[i], lat.vr0[j], lat.vr0[j] + lat.bv[j]
    return lat.uc0[i], lat.uc0[i] + lat.bu[i], lat.vs0[j], lat.vs0[j] + lat.sv[j]


def _lattice_layout(
    rng: np.random.Generator,
    lat: _Lattice,
    obj: ObjectSpec,
    p_plug: float,
    p_tight: float,
    render_plug: Callable[[tuple[float, float, float, float], str], list[dict[str, Any]]],
    render_tight: Callable[[tuple[float, float, float, float], str, float], list[dict[str, Any]]],
    extra: list[dict[str, Any]],
    info: dict[str, Any],
) -> Layout:
    """Blocks + segment states -> Layout (obstacles, sites at intersections and segment
    midpoints, passage-graph distances)."""
    nu, nv = len(lat.su), len(lat.sv)
    states: dict[tuple[str, int, int], str] = {}
    seg_keys = [("c", i, j) for i in range(1, nu - 1) for j in range(len(lat.bv))]
    seg_keys += [("r", i, j) for i in range(len(lat.bu)) for j in range(1, nv - 1)]
    for key in seg_keys:
        x = rng.random()
        states[key] = "plug" if x < p_plug else ("tight" if x < p_plug + p_tight else "roomy")
    obstacles: list[dict[str, Any]] = []
    for i in range(len(lat.bu)):
        for j in range(len(lat.bv)):
            d = _clip_box(
                lat, lat.uc0[i], lat.uc0[i] + lat.bu[i], lat.vr0[j], lat.vr0[j] + lat.bv[j]
            )
            if d is not None:
                obstacles.append(d)
    pts, edges = _lattice_graph(lat, states, margin=0.25)
    used = {("c", i, j) for i in range(nu) for j in range(len(lat.bv))} | {
        ("r", i, j) for i in range(len(lat.bu)) for j in range(nv)
    }
    for key in sorted(used):
        st = states.get(key, "roomy")
        if st == "roomy":
            continue
        box = _segment_box(lat, *key)
        if st == "plug":
            obstacles.extend(render_plug(box, key[0]))
        else:
            obstacles.extend(render_tight(box, key[0], tight_gap(rng, obj)))
    obstacles.extend(extra)
    n = len(pts)
    d_roomy = graph_distances(n, [(a, b, w) for a, b, w, st in edges if st == "roomy"])
    d_all = graph_distances(n, [(a, b, w) for a, b, w, st in edges if st in ("roomy", "tight")])
    # sites: intersections plus midpoints of roomy segments (distance via the end nodes)
    site_xy = [tuple(p) for p in pts]
    rows_r = [d_roomy[k] for k in range(n)]
    rows_a = [d_all[k] for k in range(n)]
    for a, b, w, st in edges:
        if st != "roomy":
            continue
        site_xy.append(tuple(0.5 * (pts[a] + pts[b])))
        rows_r.append(np.minimum(d_roomy[a], d_roomy[b]) + 0.5 * w)
        rows_a.append(np.minimum(d_all[a], d_all[b]) + 0.5 * w)
    m = len(site_xy)
    dr = np.full((m, m), np.inf)
    da = np.full((m, m), np.inf)
    rr = np.array(rows_r).reshape(m, n)
    ra = np.array(rows_a).reshape(m, n)
    # distance between two sites through graph nodes (exact for nodes, near for midpoints)
    for s in range(m):
        dr[s] = np.min(rr[s][None, :] + rr[:, :], axis=1) if n else dr[s]
        da[s] = np.min(ra[s][None, :] + ra[:, :], axis=1) if n else da[s]
    np.fill_diagonal(dr, 0.0)
    np.fill_diagonal(da, 0.0)
    heading = np.full((m, 1), lat.angle)
    sites = np.concatenate([np.array(site_xy).reshape(-1, 2), heading], axis=1)
    info = dict(info)
    info["tight_passages"] = sum(1 for v in states.values() if v == "tight")
    info["closed_passages"] = sum(1 for v in states.values() if v == "plug")
    return Layout(obstacles, sites, dr, da, info)


def _fill_widths(
    rng: np.random.Generator, total: float, block: tuple[float, float], street: Callable[[], float]
) -> tuple[np.ndarray, np.ndarray]:
    """Alternate streets and blocks until ``total`` is covered (street first and last)."""
    bs, ss = [], [street()]
    pos = ss[0]
    while pos < total:
        b = rng.uniform(*block)
        bs.append(b)
        s = street()
        ss.append(s)
        pos += b + s
    return np.array(bs), np.array(ss)


def layout_tilt(rng: np.random.Generator, obj: ObjectSpec, want_tight: bool) -> Layout:
    """Blocks on a lattice rotated by an oblique angle (a multiple of 11.25 degrees, so a
    rectangle can line up with the channels on the checks' heading lattice), clipped to
    the workspace; some channel segments closed, some narrowed to a tight channel as long
    as the block beside it."""
    W, H = WORKSPACE
    angle = math.radians(float(rng.choice([22.5, 33.75, 45.0, 56.25, 67.5]))) * float(
        rng.choice([-1.0, 1.0])
    )
    span = math.hypot(W, H) + 1.5

    def street() -> float:
        return street_width(rng, obj, 0.32, 0.42)

    bu, su = _fill_widths(rng, span, (0.35, 0.75), street)
    bv, sv = _fill_widths(rng, span, (0.35, 0.75), street)
    total_u = float(np.sum(bu) + np.sum(su))
    total_v = float(np.sum(bv) + np.sum(sv))
    shift = rng.uniform(-0.4, 0.4, size=2)
    c, s = math.cos(angle), math.sin(angle)
    off = np.array(
        [
            c * (-0.5 * total_u + shift[0]) - s * (-0.5 * total_v + shift[1]),
            s * (-0.5 * total_u + shift[0]) + c * (-0.5 * total_v + shift[1]),
        ]
    )
    lat = _Lattice(bu, su, bv, sv, np.array([W / 2, H / 2]) + off, angle)

    def plug(box: tuple[float, float, float, float], kind: str) -> list[dict[str, Any]]:
        u0, u1, v0, v1 = box
        d = _clip_box(lat, u0, u1, v0, v1, min_area=0.005)
        return [] if d is None else [d]

    def tight(
        box: tuple[float, float, float, float], kind: str, gap: float
    ) -> list[dict[str, Any]]:
        u0, u1, v0, v1 = box
        side = rng.random() < 0.5
        if kind == "c":  # narrow the column street across u
            u0, u1 = (u0, u1 - gap) if side else (u0 + gap, u1)
        else:
            v0, v1 = (v0, v1 - gap) if side else (v0 + gap, v1)
        if u1 - u0 <= 0.01 or v1 - v0 <= 0.01:
            return []
        d = _clip_box(lat, u0, u1, v0, v1, min_area=0.005)
        return [] if d is None else [d]

    p_plug, p_tight = (0.25, 0.25) if want_tight else (0.2, 0.15)
    return _lattice_layout(
        rng,
        lat,
        obj,
        p_plug,
        p_tight,
        plug,
        tight,
        [],
        {"angle_deg": round(math.degrees(angle), 2)},
    )


def _warehouse_rows(rng: np.random.Generator, aisle: Callable[[], float], dock: float
                    ) -> tuple[list[float], list[float]]:
    """Shelf depths and the streets before each (the first is the dock) up to the far wall,
    in the frame before transposing; a last row may stand against the far wall."""
    H = WORKSPACE[1]
    bv_list, sv_list = [], [dock]
    pos = dock
    while True:
        depth = rng.uniform(0.35, 0.6)
        a = aisle()
        if pos + depth + a > H + 1e-9:
            break
        bv_list.append(depth)
        pos += depth
        sv_list.append(a)
        pos += a
    rest = H - pos
    if rest >= 0.3:
        depth = min(rest, rng.uniform(0.3, 0.5))
        bv_list.append(depth)
        sv_list[-1] += rest - depth
        sv_list.append(0.0)
    else:
        sv_list[-1] += rest
    return bv_list, sv_list


def _warehouse_columns(rng: np.random.Generator, aisle: Callable[[], float]
                       ) -> tuple[list[float], list[float]]:
    """Shelf segment lengths and the cross-aisles around them; the first may leave an aisle
    along the side wall, the last shelf reaches the other wall unless an aisle fits there."""
    W = WORKSPACE[0]
    bu_list, su_list = [], []
    first = aisle() if rng.random() < 0.6 else 0.0
    su_list.append(first)
    pos = first
    while True:
        pos += rng.uniform(0.8, 1.5)
        bu_list.append(pos - sum(bu_list) - sum(su_list))
        a = aisle()
        if W - pos < a + 0.4:  # no room for another shelf: this one reaches the wall
            bu_list[-1] += W - pos
            su_list.append(0.0)
            break
        if W - pos < a + 0.8:  # room for an aisle along the wall only
            su_list.append(W - pos)
            break
        su_list.append(a)
        pos += a
    return bu_list, su_list


def _warehouse_plug(rng: np.random.Generator, lat: _Lattice,
                    box: tuple[float, float, float, float], kind: str) -> list[dict[str, Any]]:
    """A closed aisle segment: a traffic barrier across it or a pallet stack filling it."""
    u0, u1, v0, v1 = box
    if rng.random() < 0.5:  # traffic barrier across the aisle
        t = rng.uniform(0.05, 0.08)
        if kind == "c":
            vm = rng.uniform(v0 + t, v1 - t)
            return [rect(*lat.box(u0, u1, vm - t / 2, vm + t / 2))]
        um = rng.uniform(u0 + t, u1 - t)
        return [rect(*lat.box(um - t / 2, um + t / 2, v0, v1))]
    # a pallet stack filling the aisle
    if kind == "c":
        ln = min(v1 - v0, rng.uniform(0.35, 0.55))
        vm = rng.uniform(v0 + ln / 2, v1 - ln / 2)
        return [rect(*lat.box(u0, u1, vm - ln / 2, vm + ln / 2))]
    ln = min(u1 - u0, rng.uniform(0.35, 0.55))
    um = rng.uniform(u0 + ln / 2, u1 - ln / 2)
    return [rect(*lat.box(um - ln / 2, um + ln / 2, v0, v1))]


def _warehouse_tight(
    rng: np.random.Generator, lat: _Lattice, box: tuple[float, float, float, float], kind: str,
    gap: float,
) -> list[dict[str, Any]]:
    """Cargo against one side of an aisle segment leaving a ``gap`` wide passage: a barrel
    (disk) or a box; nothing when the aisle is hardly wider than the gap."""
    u0, u1, v0, v1 = box
    side = rng.random() < 0.5
    across = (u1 - u0) if kind == "c" else (v1 - v0)
    fill = across - gap
    if fill <= 0.02:
        return []
    along0, along1 = (v0, v1) if kind == "c" else (u0, u1)
    if rng.random() < 0.3 and 0.2 <= fill <= 0.6 and along1 - along0 >= fill:
        # a barrel (disk) against one side, its widest point leaving the gap
        r = fill / 2
        am = rng.uniform(along0 + r, along1 - r)
        if kind == "c":
            cu = u0 + r if side else u1 - r
            x, y = lat.world(cu, am)
        else:
            cv = v0 + r if side else v1 - r
            x, y = lat.world(am, cv)
        return [circle(x, y, r)]
    ln = min(along1 - along0, rng.uniform(0.3, 0.55))
    am = rng.uniform(along0 + ln / 2, along1 - ln / 2)
    if kind == "c":
        a0, a1 = (u0, u0 + fill) if side else (u1 - fill, u1)
        return [rect(*lat.box(a0, a1, am - ln / 2, am + ln / 2))]
    a0, a1 = (v0, v0 + fill) if side else (v1 - fill, v1)
    return [rect(*lat.box(am - ln / 2, am + ln / 2, a0, a1))]


def _dock_cargo(rng: np.random.Generator, lat: _Lattice, obj: ObjectSpec, dock: float
                ) -> list[dict[str, Any]]:
    """2-5 pieces of cargo (boxes, barrels) against the dock wall (v = 0), leaving the
    object room to cross the dock."""
    W = WORKSPACE[0]
    extra: list[dict[str, Any]] = []
    n_cargo = int(rng.integers(2, 6))
    room = dock - (obj.width + 2 * END_CLEARANCE)
    for _ in range(n_cargo):
        if room < 0.2:
            break
        depth = rng.uniform(0.2, min(0.45, room))
        ln = rng.uniform(0.25, 0.5)
        um = rng.uniform(ln / 2, W - ln / 2)
        if rng.random() < 0.35:
            r = depth / 2
            x, y = lat.world(um, r)
            extra.append(circle(x, y, r))
        else:
            extra.append(rect(*lat.box(um - ln / 2, um + ln / 2, 0.0, depth)))
    return extra


def layout_warehouse(rng: np.random.Generator, obj: ObjectSpec, want_tight: bool) -> Layout:
    """Shelf rows (long, shallow blocks) with aisles and cross-aisles sized for the
    object, a dock area along one wall, pallets and cargo (boxes, barrels) narrowing some
    aisles to tight passages, traffic barriers closing others, and cargo stacked against
    the walls. The whole layout is randomly mirrored/transposed."""

    def aisle() -> float:
        return street_width(rng, obj, 0.30, 0.40)

    dock = max(aisle(), rng.uniform(0.7, 1.0))
    bv_list, sv_list = _warehouse_rows(rng, aisle, dock)
    bu_list, su_list = _warehouse_columns(rng, aisle)
    lat = _Lattice(
        np.array(bu_list), np.array(su_list), np.array(bv_list), np.array(sv_list), np.zeros(2), 0.0
    )
    transpose = rng.random() < 0.5
    flip_x = rng.random() < 0.5
    flip_y = rng.random() < 0.5

    def plug(box: tuple[float, float, float, float], kind: str) -> list[dict[str, Any]]:
        return _warehouse_plug(rng, lat, box, kind)

    def tight(box: tuple[float, float, float, float], kind: str, gap: float
              ) -> list[dict[str, Any]]:
        return _warehouse_tight(rng, lat, box, kind, gap)

    extra = _dock_cargo(rng, lat, obj, dock)
    p_plug, p_tight = (0.2, 0.3) if want_tight else (0.15, 0.15)
    layout = _lattice_layout(rng, lat, obj, p_plug, p_tight, plug, tight, extra, {})
    layout.obstacles = [_transform(d, transpose, flip_x, flip_y) for d in layout.obstacles]
    layout.sites = np.array(
        [_transform_pose(p, transpose, flip_x, flip_y) for p in layout.sites]
    ).reshape(-1, 3)
    layout.info.update({"shelf_rows": len(bv_list), "transposed": transpose})
    return layout


def _transform_pose(p: np.ndarray, transpose: bool, fx: bool, fy: bool) -> np.ndarray:
    W, H = WORKSPACE
    x, y, th = float(p[0]), float(p[1]), float(p[2])
    if transpose:
        x, y, th = y, x, 0.5 * math.pi - th
    if fx:
        x, th = W - x, math.pi - th
    if fy:
        y, th = H - y, -th
    return np.array([x, y, wrap_angle(th)])


def _transform(d: dict[str, Any], transpose: bool, fx: bool, fy: bool) -> dict[str, Any]:
    """Mirror/transpose an axis-aligned layout's obstacle (rectangles stay axis-aligned)."""
    if d["type"] == "polygon":
        pts = [
            _transform_pose(np.array([x, y, 0.0]), transpose, fx, fy)[:2] for x, y in d["points"]
        ]
        return polygon(np.array(pts))
    x, y, _ = _transform_pose(np.array([*d["center"], 0.0]), transpose, fx, fy)
    if d["type"] == "circle":
        return circle(x, y, d["radius"])
    sx, sy = d["size"]
    if transpose:
        sx, sy = sy, sx
    return rect(x, y, sx, sy, 0.0)
