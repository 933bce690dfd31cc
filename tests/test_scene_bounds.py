"""``bench.scene_bounds``: a report measures every run against the bound of its scene as
``lamp.scene.bounds`` computes it now, whatever the record says, once per scene; lifelong
runs and runs whose scene is gone keep their recorded bound; the records are not changed."""

from __future__ import annotations

import pytest

from lamp.bench import scene_bounds
from lamp.bench.scene_bounds import record_scene, with_scene_bounds
from lamp.scene.bounds import makespan_lower_bound
from lamp.scene.save import save_scene
from lamp.suites import resolve_scene


def test_bounds_come_from_the_scenes_once_each(tmp_path, monkeypatch) -> None:
    built_in = resolve_scene("maze-03")
    path = tmp_path / "mine.yaml"
    save_scene(resolve_scene("random-01"), path)
    stale = {"scene": "maze-03", "scene_file": "", "makespan_s": 40.0,
             "makespan_lower_bound_s": 1.0, "makespan_over_bound": 40.0, "success": True}
    none = {"scene": "mine", "scene_file": str(path), "makespan_s": 30.0, "success": True}
    lifelong = {"scene": "maze-03", "makespan_s": 90.0, "makespan_lower_bound_s": 60.0,
                "makespan_over_bound": 1.5, "tasks": [{"object": 0}]}
    gone = {"scene": "no-such-scene", "scene_file": str(tmp_path / "gone.yaml"),
            "makespan_s": 5.0, "makespan_lower_bound_s": 2.0, "makespan_over_bound": 2.5}
    calls = []
    real = scene_bounds.makespan_lower_bound
    monkeypatch.setattr(scene_bounds, "makespan_lower_bound",
                        lambda s: calls.append(s.name) or real(s))
    records = [stale, none, dict(stale), lifelong, gone]
    before = [dict(r) for r in records]
    out = with_scene_bounds(records)
    assert records == before  # copies
    for rec, scene in ((out[0], built_in), (out[1], record_scene(none)), (out[2], built_in)):
        want = makespan_lower_bound(scene).seconds
        assert rec["makespan_lower_bound_s"] == pytest.approx(want, abs=1e-6)
        assert rec["makespan_over_bound"] == pytest.approx(rec["makespan_s"] / want, abs=1e-4)
    assert out[0]["makespan_lower_bound_s"] > 1.0  # the stale value replaced
    assert out[3] == lifelong and out[4] == gone
    assert sorted(calls) == sorted([built_in.name, record_scene(none).name])  # once each
