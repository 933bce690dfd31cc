"""The fleet schedule end to end: several objects moved at once by sub-teams in one
simulator, every recording re-checked by the independent safety check
(``lamp.record.safety``), deterministic, and faster than one object after another."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import pytest
import yaml
from fleet_fakes import fleet_at_starts
from run_safety import assert_safe
from typer.testing import CliRunner

import lamp
from lamp.cli import app
from lamp.errors import InputError
from lamp.fleet.config import CLAIM_NEAR, PASS_MARGIN, REJOIN_SLACK
from lamp.fleet.state import ObjectStatus
from lamp.pipeline import RunRequest
from lamp.record.safety import recorded_teams
from lamp.scene import scene_from_dict

#: Two rooms side by side, a box in each to push along its room, six robots: two
#: sub-teams of three, which should work at the same time.
ROOMS = {
    "format": "lamp-scene/1", "name": "two-rooms", "workspace": [5.0, 4.0],
    "schedule": "concurrent",
    "robots": {"starts": [[0.4, 0.5], [0.4, 1.0], [0.4, 1.5], [0.4, 2.5], [0.4, 3.0],
                          [0.4, 3.5]]},
    "obstacles": [{"type": "rectangle", "center": [2.5, 2.0], "size": [5.0, 0.1]}],
    "objects": [
        {"type": "rectangle", "size": [0.4, 0.3], "start": [1.3, 1.0, 0.0],
         "goal": [3.6, 1.0, 0.0]},
        {"type": "rectangle", "size": [0.4, 0.3], "start": [1.3, 3.0, 0.0],
         "goal": [3.6, 3.0, 0.0]},
    ],
}


@pytest.fixture(scope="module")
def rooms_runs():
    scene = scene_from_dict(copy.deepcopy(ROOMS))
    concurrent = lamp.solve(scene, "lazy", 0)
    again = lamp.solve(scene, "lazy", 0)
    sequential = lamp.solve(scene, "lazy", 0, schedule="sequential")
    return concurrent, again, sequential


def test_concurrent_run_places_every_object_safely_and_sooner(rooms_runs) -> None:
    concurrent, _, sequential = rooms_runs
    assert concurrent.success and sequential.success
    assert_safe(concurrent)
    assert_safe(sequential)
    fleet = concurrent.to_dict()["stats"]["fleet"]
    placed = fleet["placed_at_s"]
    assert all(t is not None for t in placed)
    assert max(placed) == pytest.approx(concurrent.makespan_s)
    # both sub-teams worked at once: the two objects' segments overlap in time
    assert concurrent.makespan_s < 0.8 * sequential.makespan_s
    use = fleet["utilisation"]
    assert 0.0 < use["working"] <= 1.0 and 0.0 <= use["moving"] <= use["working"]
    assert use["working"] + use["waiting"] + use["idle"] == pytest.approx(1.0, abs=1e-3)
    assert "fleet" not in sequential.to_dict()["stats"]
    waits = fleet["waits"]  # why segments waited, per object
    assert len(waits) == len(placed)
    for k, why in enumerate(waits):
        for reason, n in why.items():
            kind, j = reason.split()
            assert kind in ("running", "claim") and int(j) != k and n >= 1
    assert sum(sum(w.values()) for w in waits) >= fleet["waited"]


def test_concurrent_runs_are_deterministic(rooms_runs) -> None:
    a, b, _ = rooms_runs
    da, db = a.to_dict(), b.to_dict()
    for d in (da, db):
        d.pop("wall_time_s", None)
        d.pop("planning_time_s", None)
        d.pop("unexecuted_planning_time_s", None)
        for o in d["objects"]:
            o.pop("planning_time_s", None)
    assert da["objects"] == db["objects"]
    assert da["makespan_s"] == db["makespan_s"]
    assert a.recording.arrays["robots"].tobytes() == b.recording.arrays["robots"].tobytes()


@pytest.mark.parametrize("name", ["fleet-13", "fleet-21"])
def test_fleet_family_scenes_run_concurrently_and_safely(name: str) -> None:
    result = lamp.solve(name, "lazy", 0)
    assert result.to_dict()["stats"]["fleet"]["admitted"] > 0
    assert result.success, [o.failure_reason for o in result.objects]
    assert_safe(result)


def test_the_reach_cut_runs_safely_end_to_end() -> None:
    """``fleet_reach_cut`` = 1: admission cuts pushed objects to their reach from where
    they are seen; the run places every object, passes the safety check, and every
    pushed object stayed within that reach (``assert_safe``)."""
    result = lamp.solve("fleet-13", "lazy", 0, params={"fleet_reach_cut": 1})
    assert result.success, [o.failure_reason for o in result.objects]
    assert result.to_dict()["params"]["fleet_reach_cut"] == 1
    assert_safe(result)


def test_schedule_is_refused_by_name_where_it_cannot_run(tmp_path: Path) -> None:
    scene = scene_from_dict(copy.deepcopy(ROOMS))
    with pytest.raises(InputError, match="schedule"):
        RunRequest.build(scene, "lazy", schedule="parallel")
    with pytest.raises(InputError, match="concurrent schedule"):
        RunRequest.build(scene, "mapush")
    path = tmp_path / "rooms.yaml"
    path.write_text(yaml.safe_dump(ROOMS, sort_keys=False))
    out = CliRunner().invoke(app, ["run", str(path), "--schedule", "parallel",
                                   "--out", str(tmp_path / "o")])
    assert out.exit_code == 2, out.output
    assert "--schedule" in out.output and "concurrent" in out.output
    assert not (tmp_path / "o").exists()


def test_cli_schedule_overrides_the_file(tmp_path: Path) -> None:
    d = copy.deepcopy(ROOMS)
    d["objects"] = d["objects"][:1]
    d["robots"]["starts"] = d["robots"]["starts"][:3]
    path = tmp_path / "one.yaml"
    path.write_text(yaml.safe_dump(d, sort_keys=False))
    out = CliRunner().invoke(app, ["run", str(path), "--schedule", "sequential", "--quiet",
                                   "--out", str(tmp_path / "seq")])
    assert out.exit_code == 0, out.output
    result = json.loads((tmp_path / "seq" / "result.json").read_text())
    assert "fleet" not in result["stats"] and result["success"]


def test_recording_keeps_the_sub_teams_and_the_viewer_shows_them(rooms_runs,
                                                                tmp_path: Path) -> None:
    from lamp.record.format import load_recording, save_recording
    from lamp.viz.replay_html import payload

    concurrent, _, sequential = rooms_runs
    save_recording(concurrent.recording, tmp_path)
    rec = load_recording(tmp_path)
    team = rec.arrays["robot_team"]
    assert team.shape == (rec.n_rows, 6)
    assert set(team.ravel().tolist()) <= {-1, 0, 1}
    assert (team[1:] >= 0).any(axis=0).sum() >= 6 - 1  # robots did work for an object
    assert (team[0] == -1).all()
    assert payload(rec)["robot_team"] is not None
    assert "robot_team" not in sequential.recording.arrays
    assert payload(sequential.recording)["robot_team"] is None


def test_timeline_shows_the_sub_teams_time_and_the_placements(rooms_runs,
                                                              tmp_path: Path) -> None:
    from lamp.record.format import save_recording
    from lamp.viz.timeline import IDLE, placement_times, robot_spans

    concurrent, _, sequential = rooms_runs
    rec = concurrent.recording
    fleet = concurrent.to_dict()["stats"]["fleet"]
    assert placement_times(rec) == dict(enumerate(fleet["placed_at_s"]))
    seq = placement_times(sequential.recording)  # from the segments: one after another
    assert set(seq) == {0, 1} and seq[0] < seq[1]
    assert seq[1] == pytest.approx(sequential.makespan_s, abs=0.1)
    # the share of robot-time in a sub-team agrees with the schedule's own accounting
    spans = robot_spans(rec.arrays["times"], rec.arrays["robots"], rec.arrays["robot_team"],
                        rec.scene_model().physics.robot_speed)
    total = 6 * (rec.arrays["times"][-1] - rec.arrays["times"][0])
    busy = sum(s.end - s.start for row in spans for s in row if s.object != IDLE) / total
    share = fleet["utilisation"]
    assert busy == pytest.approx(share["working"] + share["waiting"], abs=0.01)
    save_recording(rec, tmp_path)
    out = tmp_path / "timeline.png"
    res = CliRunner().invoke(app, ["timeline", str(tmp_path), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:4] == b"\x89PNG"
    bad = CliRunner().invoke(app, ["timeline", str(tmp_path), "--out", str(tmp_path / "t.gif")])
    assert bad.exit_code == 2 and "--out" in bad.output and not (tmp_path / "t.gif").exists()


def test_bench_schedule_is_checked_and_recorded(tmp_path: Path) -> None:
    bad = CliRunner().invoke(app, ["bench", "--suites", "fleet", "--planners", "lazy",
                                   "--schedule", "parallel", "--dry-run",
                                   "--out", str(tmp_path / "b")])
    assert bad.exit_code == 2, bad.output
    assert "--schedule" in bad.output and "sequential, concurrent" in bad.output
    from lamp.bench.jobs import enumerate_jobs, load_suite

    jobs = enumerate_jobs([load_suite("fleet")], ["lazy"], [0], scenes_per_suite=2,
                          schedule="sequential")
    assert [j.scene.schedule for j in jobs] == ["sequential", "sequential"]
    kept = enumerate_jobs([load_suite("fleet")], ["lazy"], [0], scenes_per_suite=2)
    assert [j.scene.schedule for j in kept] == ["concurrent", "concurrent"]


def test_a_disturbance_that_never_fires_changes_nothing(rooms_runs) -> None:
    """A robot failure scheduled after the run ends: the disturbed executor runs the fleet
    exactly as the plain simulator does (the same settle between stretches: it was
    settling 0.2 s at every event before), so the result is the undisturbed one."""
    from lamp.contract.disturb import Disturbances

    plain = rooms_runs[0]
    late = lamp.solve(scene_from_dict(copy.deepcopy(ROOMS)), "lazy", 0,
                      disturbances=Disturbances(robot_failures=((0, 1e5),)))
    assert late.success
    assert late.makespan_s == plain.makespan_s
    assert [o.segments for o in late.objects] == [o.segments for o in plain.objects]
    assert late.to_dict()["stats"]["fleet"]["placed_at_s"] == \
        plain.to_dict()["stats"]["fleet"]["placed_at_s"]


def test_a_failed_robot_leaves_its_sub_team_and_a_free_one_takes_its_place() -> None:
    """Concurrent schedule, robot 1 (object 0's sub-team) fails at 2 s: it holds where it
    stopped, never pushes again, the spare robot 6 joins object 0's sub-team, and both
    objects are placed safely."""
    import numpy as np

    from lamp.contract.disturb import Disturbances

    d = copy.deepcopy(ROOMS)
    d["robots"]["starts"].append([0.2, 0.2])  # robot 6: a spare, in no sub-team at first
    scene = scene_from_dict(d)
    res = lamp.solve(scene, "lazy", 0, disturbances=Disturbances(robot_failures=((1, 2.0),)))
    out = res.to_dict()
    assert res.success, [o.failure_reason for o in res.objects]
    assert_safe(res)
    fleet = out["stats"]["fleet"]
    assert set(fleet["robots_failed_at_s"]) == {"1"}
    assert set(out["stats"]["failed_robots"]) == {"1"}
    rec = res.recording.arrays
    team = recorded_teams(res.recording)
    after = rec["times"] > fleet["robots_failed_at_s"]["1"] + 1e-6
    assert np.all(team[after, 1] == -1)  # in no sub-team once it failed
    assert np.any(team[~after, 1] == 0) and np.any(team[after, 6] == 0)  # the spare joined
    place = np.array(out["stats"]["failed_robots"]["1"])
    later = rec["robots"][rec["times"] > 2.5, 1]
    assert np.all(np.linalg.norm(later - place, axis=1) < 0.02)


def _two_boxes(width: float, far_start: tuple[float, float], far_goal_x: float) -> dict:
    """Four robots at the left of a ``width`` x 3 m room; box 0 a short push from them,
    box 1 from ``far_start`` to ``far_goal_x`` along its row."""
    box = {"type": "rectangle", "size": [0.4, 0.3]}
    return {"format": "lamp-scene/1", "name": "help", "workspace": [width, 3.0],
            "schedule": "concurrent",
            "robots": {"starts": [[0.4, 0.6], [0.4, 1.0], [0.4, 2.0], [0.4, 2.4]]},
            "objects": [{**box, "start": [1.2, 0.8, 0.0], "goal": [1.8, 0.8, 0.0]},
                        {**box, "start": [*far_start, 0.0],
                         "goal": [far_goal_x, far_start[1], 0.0]}]}


def test_robots_freed_by_a_placed_object_reinforce_a_moving_team() -> None:
    """Two boxes, four robots: teams of two. The short push is placed first; nothing waits
    to start, so with ``fleet_reinforce_reach`` set its robots, within reach, join the
    other box's team up to the model's three (``Fleet._reinforce``), whose loop plans anew
    with them; both placed safely. Off (the default), nobody joins."""
    import numpy as np

    d = _two_boxes(5.0, (1.2, 2.2), 4.2)
    off = lamp.solve(scene_from_dict(d), "lazy", 0)
    assert off.success and off.to_dict()["stats"]["fleet"]["reinforced"] == 0
    res = lamp.solve(scene_from_dict(d), "lazy", 0, params={"fleet_reinforce_reach": 4.0})
    assert res.success, [o.failure_reason for o in res.objects]
    assert_safe(res)
    fleet = res.to_dict()["stats"]["fleet"]
    first, last = fleet["placed_at_s"]
    assert first < last and fleet["reinforced"] >= 1
    team = recorded_teams(res.recording)
    times = res.recording.arrays["times"]
    assert np.all((team[times < first - 1e-6] == 1).sum(axis=1) <= 2)  # two while 0 moves
    assert (team[-1] == 1).sum() == 3  # three at the end
    assert res.objects[1].replans >= 1  # a new loop with the new team


def test_a_team_reinforced_while_it_drives_to_its_object_keeps_its_robots_apart() -> None:
    """Object 1 lies 8 m from its team, which drives there in transit hops; object 0 is
    placed meanwhile and its robots join object 1's team (``fleet_reinforce_reach``). A hop
    planned for the team as it was runs with exactly those robots (the joiners hold: the
    hop's paths once went to the grown team, and the run stopped with an internal error),
    and the box is placed safely with three robots."""
    import numpy as np

    d = _two_boxes(12.0, (9.0, 2.2), 10.5)
    res = lamp.solve(scene_from_dict(d), "lazy", 0, params={"fleet_reinforce_reach": 20.0})
    assert res.success, [o.failure_reason for o in res.objects]
    assert_safe(res)
    fleet = res.to_dict()["stats"]["fleet"]
    assert fleet["reinforced"] >= 1 and fleet["transit_hops"] >= 1
    team = recorded_teams(res.recording)
    assert (team[-1] == 1).sum() == 3
    assert np.all((team == 1).sum(axis=1) <= 3)


def test_a_plan_made_in_the_world_as_it_stands_is_not_declined() -> None:
    """``Fleet.world_taken``: a loop's segment submitted before any event since its world
    was taken is admitted even when its bodies, as planned, touch a standing robot (the
    planner saw that robot and accepted the contact: declining would plan the same again,
    for ever); once an event has passed, the same segment is declined (the world changed)."""
    import numpy as np

    from lamp.fleet.segments import Segment

    scene = scene_from_dict(_two_boxes(5.0, (1.2, 2.2), 4.2))
    r = scene.robot_radius
    robots = np.array(scene.robot_starts, float)
    robots[3] = [0.4 + 2 * r - 0.01, 0.6]  # 1 cm into robot 0's disk, in no team

    def outcome(events_since: int) -> tuple[bool, bool]:
        fleet = fleet_at_starts(scene, robots)
        o = fleet.objects[0]
        o.status, o.team = ObjectStatus.ACTIVE, [0]
        fleet.owner[0] = 0
        fleet.world_taken(0)
        fleet.stats.counts["events"] += events_since  # segments that ended since
        rows = np.linspace(robots[0], robots[0] + [0.0, 0.1], 5)[None]
        o.request = Segment(0, [0], rows, np.array([scene.objects[0].start]), None,
                            scene.objects[0].shape, r)
        fleet._admit(force=False)
        return o.running is not None, o.reply is not None and o.reply.declined

    assert outcome(events_since=0) == (True, False)  # admitted
    assert outcome(events_since=1) == (False, True)  # declined


def _moving_fleet(scene, cross_near: float = 0.0, cross_waiting: float = 0.0,
                  pass_margin: float = math.inf):
    """A ``Fleet`` on ``scene`` whose objects all move, ranked in file order, over an
    executor that only reports the scene's start poses (no simulator); passing ahead
    (``pass_margin``, tested in ``test_fleet_passing``) off unless asked for."""
    fleet = fleet_at_starts(scene, cross_near=cross_near, cross_waiting=cross_waiting,
                            pass_margin=pass_margin)
    for k, o in enumerate(fleet.objects):
        o.status, o.rank = ObjectStatus.ACTIVE, k
    return fleet


def test_a_blocked_objects_claim_binds_only_those_outside_it() -> None:
    """``Fleet.plan_failed``: the claim of an object whose planner failed stays, but binds
    only the objects outside it then (``Fleet.inside``): one standing in its way may go
    on through it (it may be what it waits for), one outside may not come deeper in (to
    meet it head-on in an aisle)."""

    import numpy as np
    import shapely

    from lamp.fleet.segments import Segment

    d = _two_boxes(6.0, (3.0, 1.3), 5.0)  # object 1's lower edge in the aisle below
    d["objects"].append({**d["objects"][0], "start": [5.4, 2.2, 0.0], "goal": [5.4, 1.6, 0.0]})
    scene = scene_from_dict(d)
    r = scene.robot_radius
    fleet = _moving_fleet(scene)
    aisle = shapely.box(2.0, 0.4, 6.0, 1.2)  # object 0's way: object 1 stands in it
    fleet.objects[0].claim = aisle
    fleet.objects[0].exempt = fleet.inside(aisle)
    assert fleet.objects[0].exempt == {1}

    def deeper(k: int, dy: float) -> Segment:  # object k pushed dy down, into the aisle
        q = np.asarray(scene.objects[k].start, float)
        robot = q[:2] + [0.0, 0.15 + r]
        rows = np.linspace(robot, robot - [0.0, dy], 25)[None]
        return Segment(k, [0], rows, np.array([q, q - [0.0, dy, 0.0]]), None,
                       scene.objects[k].shape, r)

    assert fleet._meets_moving(deeper(1, 0.5)) is None  # inside: goes on, deeper
    assert fleet._meets_moving(deeper(2, 1.0)) == "claim 0"  # outside: may not come in
    fleet.objects[0].exempt = frozenset()
    assert fleet._meets_moving(deeper(1, 0.5)) == "claim 0"  # an ordinary claim binds both


def _crossing(cross_near: float = 0.0, cross_waiting: float = 0.0):
    """Box 0 runs along the row at y = 0.8 to x = 8 (its plan announced); box 1 goes up
    from (6, 0.5) to (6, 2.5), across that row 4.8 m ahead of box 0 (its plan announced):
    (fleet, box 1's first segment, into the row, box 0's and box 1's planned poses)."""
    import numpy as np

    from lamp.fleet.segments import Segment

    d = _two_boxes(9.0, (6.0, 0.5), 6.0)
    d["objects"][1]["goal"] = [6.0, 2.5, 0.0]
    d["objects"][0]["goal"] = [8.0, 0.8, 0.0]
    scene = scene_from_dict(d)
    r = scene.robot_radius
    fleet = _moving_fleet(scene, cross_near, cross_waiting)
    row = np.array([[x, 0.8, 0.0] for x in np.arange(1.2, 8.01, 0.2)])
    fleet.announce(0, row[:2], row[2:])
    q0, q1 = np.array([6.0, 0.5, 0.0]), np.array([6.0, 1.0, 0.0])  # box 1 into the row
    rows = np.linspace(q0[:2] - [0.0, 0.15 + r], q1[:2] - [0.0, 0.15 + r], 25)[None]
    seg = Segment(1, [0], rows, np.array([q0, q1]), None, scene.objects[1].shape, r)
    up = np.array([[6.0, y, 0.0] for y in np.arange(0.5, 2.51, 0.1)])
    fleet.announce(1, up[:2], up[2:])
    return fleet, seg, row, up


@pytest.mark.parametrize("cross_near", [CLAIM_NEAR, 0.0])
def test_an_announced_plan_claims_its_way_and_a_crossing_heeds_only_the_near_part(
        cross_near: float) -> None:
    """``Fleet.announce`` sets an object's claim, its near part and its way (on to its
    goal, ``regions.claims``); with ``cross_near`` (``fleet_cross_near``) set,
    ``Fleet._meets_moving`` hands the lower-ranked object's own way to admission, so a
    segment that crosses a higher-ranked object's way far ahead is admitted, and one that
    would stop in it is not; off (the default), the whole claim binds it."""

    import numpy as np
    import shapely

    fleet, seg, _, up = _crossing(cross_near=cross_near)
    o = fleet.objects[0]
    assert o.way is not None and np.allclose(shapely.get_coordinates(o.way)[-1], [8.0, 0.8])
    if cross_near:
        assert o.near.area < o.claim.area and o.near.bounds[2] < 1.2 + cross_near + 0.5
    else:
        assert o.near is o.claim
    want = None if cross_near else "claim 0"
    assert fleet._meets_moving(seg) == want  # crosses 4.8 m ahead of box 0
    fleet.announce(1, up[:6], np.zeros((0, 3)))
    fleet.objects[1].way = shapely.LineString([[6.0, 0.5], [6.0, 0.9]])  # stops in the row
    assert fleet._meets_moving(seg) == "claim 0"


@pytest.mark.parametrize("cross_waiting", [CLAIM_NEAR, 0.0])
def test_a_crossing_heeds_only_the_near_part_of_a_waiting_objects_claim(
        cross_waiting: float) -> None:
    """``fleet_cross_waiting`` (``admission.heeded_claims``): a segment that crosses a
    higher-ranked object's way far ahead of it is admitted while that object stands
    waiting (its segment not admitted, or its planner waiting for a change), and waits
    while it runs; one that would stop in the way waits either way. Off, the whole claim
    binds it always."""
    import numpy as np
    import shapely

    from lamp.fleet.segments import Segment

    fleet, seg, row, _ = _crossing(cross_waiting=cross_waiting)
    higher = fleet.objects[0]
    assert higher.near.area < higher.claim.area if cross_waiting else higher.near is higher.claim
    r = fleet.scene.robot_radius
    robot = row[0, :2] - [0.15 + r, 0.0]  # box 0's own segment: a short push at x = 1.2
    own = Segment(0, [0], np.linspace(robot, robot + [0.2, 0.0], 10)[None], row[:2], None,
                  fleet.scene.objects[0].shape, r)
    crossing = None if cross_waiting else "claim 0"
    higher.running = own  # it moves: the whole claim binds
    assert not higher.held_up and fleet._meets_moving(seg) == "claim 0"
    higher.running, higher.request = None, own  # its segment waits to be admitted
    assert higher.held_up and fleet._meets_moving(seg) == crossing
    higher.request, higher.blocked_at = None, (0, 0)  # its planner waits for a change
    assert higher.held_up and fleet._meets_moving(seg) == crossing
    fleet.objects[1].way = shapely.LineString([[6.0, 0.5], [6.0, 0.9]])  # stops in the row
    assert fleet._meets_moving(seg) == "claim 0"
    higher.blocked_at = None  # neither running nor waiting (placed, say): not waiting
    assert not higher.held_up


@pytest.mark.parametrize("params, want", [({}, CLAIM_NEAR), ({"fleet_cross_waiting": 0.0}, 0.0),
                                          ({"fleet_cross_waiting": 0.5}, 0.5)])
def test_the_crossing_settings_reach_the_fleet(monkeypatch, params, want) -> None:
    """``lamp.solve(params=...)`` hands ``fleet_cross_waiting`` (default ``CLAIM_NEAR``)
    and ``fleet_cross_near`` to the concurrent schedule's ``Fleet``."""
    assert _fleet_settings(monkeypatch, params, "cross_near", "cross_waiting") == (0.0, want)


@pytest.mark.parametrize("params, want", [
    ({}, (PASS_MARGIN, 0, REJOIN_SLACK)),
    ({"fleet_pass_margin": math.inf, "fleet_rejoin_slack": math.inf}, (math.inf, 0, math.inf)),
    ({"fleet_rejoin_limit": 10, "fleet_rejoin_slack": 0.5}, (PASS_MARGIN, 10, 0.5))])
def test_the_passing_and_rejoin_settings_reach_the_fleet(monkeypatch, params, want) -> None:
    """``lamp.solve(params=...)`` hands ``fleet_pass_margin``, ``fleet_rejoin_limit`` and
    ``fleet_rejoin_slack`` (defaults ``PASS_MARGIN``, 0, ``REJOIN_SLACK``: passing ahead
    and the slack on, the limit off) to the concurrent schedule's ``Fleet``."""
    assert _fleet_settings(monkeypatch, params, "pass_margin", "rejoin_limit",
                           "rejoin_slack") == want


def _fleet_settings(monkeypatch, params: dict, *names: str) -> tuple:
    """The ``names`` attributes of the ``Fleet`` that ``lamp.solve(params=params)`` builds
    for a two-box concurrent scene (its run stopped before anything moves)."""
    from lamp.fleet.coordinator import Fleet

    seen: list[tuple] = []

    class Seen(Exception):
        pass

    def run(self):
        seen.append(tuple(getattr(self.config, n) for n in names))
        raise Seen

    monkeypatch.setattr(Fleet, "run", run)
    with pytest.raises(Seen):
        lamp.solve(scene_from_dict(_two_boxes(5.0, (1.2, 2.2), 4.2)), "lazy", 0, params=params)
    assert len(seen) == 1
    return seen[0]


def test_lamp_check_passes_the_runs_and_fails_a_shove(rooms_runs, tmp_path: Path) -> None:
    """``lamp check``: the recorded runs pass; the same concurrent run with an object
    knocked 0.3 m aside in one row fails on its push lead (exit 1, naming the object),
    which is not judged once the run says pushes knocked objects; a sequential run's lead
    is measured, not judged; bad paths and recordings exit 2."""
    import dataclasses

    import numpy as np
    from run_safety import BOUND

    from lamp.fleet.spacetime import PUSH_LEAD
    from lamp.record.audit import audit_recording
    from lamp.record.format import save_recording

    concurrent, _, sequential = rooms_runs
    save_recording(concurrent.recording, tmp_path / "runs" / "con")
    save_recording(sequential.recording, tmp_path / "runs" / "seq")
    res = CliRunner().invoke(app, ["check", str(tmp_path / "runs")])
    assert res.exit_code == 0, res.output
    assert res.output.count("PASS") == 2 and "not judged: sequential run" in res.output
    assert "2 of 2 run(s) passed" in res.output
    res = CliRunner().invoke(app, ["check", str(tmp_path / "runs"), "--json"])
    rows = [json.loads(line) for line in res.stdout.splitlines()]
    assert res.exit_code == 0 and [r["ok"] for r in rows] == [True, True]
    assert [r["push_lead_judged"] for r in rows] == [True, False]
    assert rows[0]["violations"] == [] and rows[0]["push_lead_m"] <= PUSH_LEAD

    rec = concurrent.recording
    objects = np.array(rec.arrays["objects"])
    row = len(objects) // 2
    objects[row:, 1, 1] += 0.3  # object 1 jumps sideways in one row, the rest follow
    shoved = dataclasses.replace(rec, arrays={**rec.arrays, "objects": objects})
    audit = audit_recording(shoved, BOUND)
    assert not audit.lead_ok and not audit.ok
    assert audit.reach.object == 1 and audit.reach.lead > 0.3 - 0.05 - PUSH_LEAD
    assert audit.reach.until_s == pytest.approx(rec.arrays["times"][row])
    save_recording(shoved, tmp_path / "shoved")
    res = CliRunner().invoke(app, ["check", str(tmp_path / "shoved"), "--no-reach"])
    assert "push lead not measured" in res.output
    res = CliRunner().invoke(app, ["check", str(tmp_path / "shoved")])
    assert res.exit_code == 1 and "FAIL" in res.output and "VIOLATION" in res.output
    assert "object 1" in res.output
    knocked = dataclasses.replace(shoved, result={
        **rec.result, "disturbances": {**rec.result["disturbances"], "push_disturbance": 0.5}})
    audit = audit_recording(knocked, BOUND)
    assert audit.lead_ok and audit.not_judged == "disturbed by push_disturbance"
    assert audit.ok == audit.safety.ok

    res = CliRunner().invoke(app, ["check", str(tmp_path / "nowhere")])
    assert res.exit_code == 2 and "nowhere" in res.output
    (tmp_path / "empty").mkdir()
    res = CliRunner().invoke(app, ["check", str(tmp_path / "empty")])
    assert res.exit_code == 2 and "no recording" in res.output
    (tmp_path / "runs" / "broken").mkdir()
    (tmp_path / "runs" / "broken" / "recording.json").write_text("{")
    res = CliRunner().invoke(app, ["check", str(tmp_path / "runs")])
    assert res.exit_code == 2 and "broken" in res.output and res.output.count("PASS") == 2


def test_fleet_lattices_keep_no_successor_lists(monkeypatch) -> None:
    """The fleet's objects plan on lattices that keep no successor lists
    (``lamp.fleet.objects``: memory, not results; one object alone keeps its default)."""
    from lamp.pipeline.warmup import ensure_warm
    from lamp.search.lattice import SUCC_KEPT, ObjectLattice

    ensure_warm()  # (the process's first run warms the compiled kernels on a scene of its own)
    kept: list[int] = []
    build = ObjectLattice.__init__

    def spy(self, *args, succ_kept: int = SUCC_KEPT, **kwargs) -> None:
        kept.append(succ_kept)
        build(self, *args, succ_kept=succ_kept, **kwargs)

    monkeypatch.setattr(ObjectLattice, "__init__", spy)
    scene = scene_from_dict(copy.deepcopy(ROOMS))
    assert lamp.solve(scene, "lazy", 0).success
    assert kept and set(kept) == {0}
    kept.clear()
    assert lamp.solve(scene, "lazy", 0, schedule="sequential").success
    assert kept and set(kept) == {SUCC_KEPT}
