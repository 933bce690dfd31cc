"""``lamp show``: a valid scene gives a PNG (exit 0); an invalid one exits 2 with the message."""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import pytest
from typer.testing import CliRunner

from lamp.cli import app

DATA = Path(__file__).parent / "data"


def test_show_writes_png(tmp_path: Path) -> None:
    out = tmp_path / "pics" / "scene.png"
    result = CliRunner().invoke(
        app, ["show", str(DATA / "spec_example_fixed.yaml"), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert iio.imread(out).shape[:2] == (720, 720)  # 6 inches at the default 120 dpi


def test_show_json(tmp_path: Path) -> None:
    out = tmp_path / "m.png"
    result = CliRunner().invoke(app, ["show", str(DATA / "minimal.json"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.is_file()


def test_show_invalid_scene_exits_2(tmp_path: Path) -> None:
    out = tmp_path / "x.png"
    scene = tmp_path / "bad.yaml"  # objects[2].goal put on obstacles[0], a circle at (3, 1)
    text = (DATA / "spec_example.yaml").read_text()
    scene.write_text(text.replace("goal:  [3.2, 0.5, 0.0]", "goal:  [3.0, 1.0, 0.0]"))
    result = CliRunner().invoke(app, ["show", str(scene), "--out", str(out)])
    assert result.exit_code == 2
    assert f"error: {scene}: objects[2].goal: " in result.stderr
    assert "overlaps obstacles[0]" in result.stderr
    assert not out.exists()


def test_show_missing_file_exits_2(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app, ["show", str(tmp_path / "nope.yaml"), "--out", str(tmp_path / "x.png")]
    )
    assert result.exit_code == 2
    assert "nope.yaml: (file): file not found" in result.stderr


@pytest.mark.parametrize("suffix, magic", [(".png", b"\x89PNG"), (".svg", b"<?xml"),
                                           (".pdf", b"%PDF")])
def test_show_honours_the_extension(tmp_path: Path, suffix: str, magic: bytes) -> None:
    out = tmp_path / f"scene{suffix}"
    result = CliRunner().invoke(app, ["show", str(DATA / "spec_example.yaml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_bytes().startswith(magic)
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary left


@pytest.mark.parametrize("name", ["scene.jpg", "scene", "scene.PNG.txt"])
def test_show_refuses_other_extensions(tmp_path: Path, name: str) -> None:
    out = tmp_path / name
    result = CliRunner().invoke(app, ["show", str(DATA / "spec_example.yaml"), "-o", str(out)])
    assert result.exit_code == 2
    assert "--out" in result.stderr and "unsupported image extension" in result.stderr
    assert ".png, .svg, .pdf" in result.stderr
    assert not out.exists()
