"""The scaling benchmark's maps (pillar density) and its plot (one figure per sweep, a clear
error when a file is not one sweep)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))
from bench_scale import DEFAULT_DENSITY, pillar_scene  # noqa: E402

from lamp.scene.loader import scene_from_dict  # noqa: E402


@pytest.mark.parametrize("density", [0.05, DEFAULT_DENSITY, 0.3])
def test_pillar_density_and_clearance(density):
    d = pillar_scene(12, density=density)
    assert len(d["obstacles"]) == round(density * 144)  # all fit on a 12 m map
    assert d == pillar_scene(12, density=density)  # deterministic
    scene_from_dict(d)  # a valid scene
    centres = [o["center"] for o in d["obstacles"]]
    for k, (x, y) in enumerate(centres):
        for x2, y2 in centres[k + 1:]:
            assert (x - x2) ** 2 + (y - y2) ** 2 >= 0.8**2


def test_default_maps_unchanged():
    assert len(pillar_scene(50)["obstacles"]) == 375
    assert pillar_scene(8) == pillar_scene(8, 3, 1, DEFAULT_DENSITY)


def _row(size, robots=3, objects=1, density=0.15, s_per_m=0.1, success=True):
    return {"size_m": size, "robots": robots, "objects": objects, "density": density,
            "s_per_m": s_per_m, "peak_gb": 0.5, "success": success,
            "runs": [{"s_per_m": s_per_m * f, "peak_gb": 0.5} for f in (0.9, 1.0, 1.2)]}


def test_plot_scale(tmp_path):
    sizes = tmp_path / "sizes.json"
    sizes.write_text(json.dumps([_row(4), _row(8, success=False), _row(16)]))
    robots = tmp_path / "robots.json"
    robots.write_text(json.dumps([_row(8, robots=r) for r in (3, 6)]))
    out = tmp_path / "fig" / "scale.png"
    cmd = [sys.executable, str(BENCH / "plot_scale.py"), str(sizes), str(robots), "--out",
           str(out)]
    subprocess.run(cmd, check=True, capture_output=True)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    mixed = tmp_path / "mixed.json"
    mixed.write_text(json.dumps([_row(4), _row(8, robots=6)]))
    bad = subprocess.run(cmd[:2] + [str(mixed), "--out", str(tmp_path / "x.png")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "mixed.json" in bad.stderr and "one varying" in bad.stderr
    assert not (tmp_path / "x.png").exists()


def test_fleet_scale_points_of_other_scenes_never_share_a_folder(tmp_path):
    """A finished point is reused only for the same scene: the same size on another map
    (or kind, or map size) gets a folder of its own."""
    from bench_fleet_scale import point_folder

    from lamp.suites.fleet import generate_custom

    a = generate_custom("aisles", (20.0, 15.0), 2, 6).scene
    b = generate_custom("rooms", (20.0, 15.0), 2, 6).scene
    fa = point_folder(tmp_path, 6, 2, a)
    (fa / "point.json").write_text("{}")
    assert point_folder(tmp_path, 6, 2, a) == fa  # the same scene: the finished run
    fb = point_folder(tmp_path, 6, 2, b)
    assert fb != fa and not (fb / "point.json").exists()
    assert (fa / "scene.yaml").read_bytes() != (fb / "scene.yaml").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([fa.name, fb.name])
