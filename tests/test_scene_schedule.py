"""The scene format's ``schedule`` and per-object ``after`` keys: read, written back, and
every bad value refused by field, with the cycle named."""

from __future__ import annotations

import copy
import re
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from scenes import TINY
from test_scene_loader import expect_error, write

from lamp.scene import SceneError, load_scene, scene_from_dict


def three_boxes() -> dict[str, Any]:
    d = copy.deepcopy(TINY)
    d["workspace"] = [4.0, 3.0]
    box = d["objects"][0]
    d["objects"] = [dict(box, start=[0.85 + 1.0 * i, 1.0, 0.0], goal=[0.85 + 1.0 * i, 2.2, 0.0])
                    for i in range(3)]
    return d


def refused(tmp_path: Path, d: dict[str, Any], field: str, *fragments: str) -> str:
    """``d`` written to a file is refused naming ``field`` (``test_scene_loader``'s check)."""
    return expect_error(write(tmp_path, d), field, *fragments)


def test_defaults_are_the_paper_schedule() -> None:
    scene = scene_from_dict(three_boxes())
    assert scene.schedule == "sequential"
    assert all(o.after == () for o in scene.objects)
    assert "schedule" not in scene.to_dict()
    assert all("after" not in o for o in scene.to_dict()["objects"])


def test_schedule_and_after_round_trip(tmp_path: Path) -> None:
    d = three_boxes()
    d["schedule"] = "concurrent"
    d["objects"][2]["after"] = [0, 1]
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(d, sort_keys=False))
    scene = load_scene(path)
    assert scene.schedule == "concurrent"
    assert scene.objects[2].after == (0, 1)
    again = scene_from_dict(scene.to_dict())
    assert again == scene


@pytest.mark.parametrize("value, fragment", [("parallel", "sequential, concurrent"),
                                             (3, "sequential, concurrent")])
def test_bad_schedule_is_refused(tmp_path: Path, value: Any, fragment: str) -> None:
    d = three_boxes()
    d["schedule"] = value
    refused(tmp_path, d, "schedule", fragment)


@pytest.mark.parametrize("after, field, fragment", [
    ([5], "objects[1].after[0]", "no object 5"),
    ([1], "objects[1].after[0]", "cannot wait for itself"),
    ([-1], "objects[1].after[0]", "integer >= 0"),
    ([0.5], "objects[1].after[0]", "integer >= 0"),
    ([True], "objects[1].after[0]", "integer >= 0"),
    ([0, 0], "objects[1].after[1]", "listed twice"),
    ("0", "objects[1].after", ""),
])
def test_bad_after_is_refused_by_field(tmp_path: Path, after: Any, field: str,
                                       fragment: str) -> None:
    d = three_boxes()
    d["objects"][1]["after"] = after
    refused(tmp_path, d, field, fragment)


def test_a_cycle_is_named(tmp_path: Path) -> None:
    d = three_boxes()
    d["objects"][0]["after"] = [1]
    d["objects"][1]["after"] = [2]
    d["objects"][2]["after"] = [0]
    refused(tmp_path, d, "objects[0].after", "cycle", "objects[0] -> objects[1] -> "
            "objects[2] -> objects[0]")


@settings(max_examples=60)
@given(st.lists(st.lists(st.integers(0, 2), max_size=3, unique=True), min_size=3, max_size=3))
def test_after_is_accepted_exactly_when_acyclic(lists: list[list[int]]) -> None:
    """Reference: a DAG admits a topological order (Kahn); the loader accepts exactly those
    (self-loops are cycles)."""
    d = three_boxes()
    for o, after in zip(d["objects"], lists, strict=True):
        o["after"] = after
    pending = {i: set(a) for i, a in enumerate(lists)}
    while True:
        free = [i for i, a in pending.items() if not a]
        if not free:
            break
        for i in free:
            del pending[i]
        for a in pending.values():
            a.difference_update(free)
    acyclic = not pending
    try:
        scene_from_dict(d)
        accepted = True
    except SceneError as exc:
        accepted = False
        if "cycle" in str(exc):  # the cycle named is one: each waits for the next
            named = [int(k) for k in re.findall(r"objects\[(\d+)\] ", str(exc) + " ")]
            assert named[0] == named[-1] == min(named)
            assert all(b in lists[a] for a, b in zip(named[:-1], named[1:], strict=True))
    assert accepted == acyclic
