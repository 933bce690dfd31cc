"""Packaging: one source for the version, licence and metadata, bounded majors, the tested
constraint set, and extras that make the whole suite run.

These read ``pyproject.toml``, ``constraints.txt`` and the ``Makefile`` of this source tree
and the metadata of the installed distribution.
"""

from __future__ import annotations

import re
import sys
from importlib import metadata
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

import lamp

if sys.version_info >= (3, 11):
    import tomllib
else:  # the test extra installs tomli on 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]

#: Dependencies whose next major may change planning results or the CLI: they need an
#: upper bound.
BOUNDED = ("numpy", "scipy", "shapely", "numba", "mujoco", "torch", "typer", "matplotlib",
           "ray", "imageio-ffmpeg")


def requirements(group: str | None = None) -> list[Requirement]:
    specs = PROJECT["dependencies"] if group is None else PROJECT["optional-dependencies"][group]
    return [Requirement(s) for s in specs]


def all_requirements() -> list[Requirement]:
    out = requirements()
    for group in PROJECT["optional-dependencies"]:
        out += requirements(group)
    return out


def constraints() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        name, _, version = line.partition("==")
        assert version, f"constraints.txt: {line!r} is not an exact pin"
        pins[canonicalize_name(name)] = version
    return pins


def test_version_has_one_source():
    assert lamp.__version__ == metadata.version("lamp") == PROJECT["version"]
    literal = re.compile(rf"""["']{re.escape(PROJECT["version"])}["']""")
    hard_coded = [str(p.relative_to(ROOT)) for p in (ROOT / "src").rglob("*.py")
                  if literal.search(p.read_text())]
    assert hard_coded == []


def test_licence_and_metadata():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "WITHOUT WARRANTY OF ANY KIND" in text
    assert PROJECT["license"] == "MIT" and PROJECT["license-files"] == ["LICENSE"]
    assert PROJECT["urls"] and all(u.startswith("https://") for u in PROJECT["urls"].values())
    assert any(c.startswith("Programming Language :: Python :: 3.") for c in PROJECT["classifiers"])
    assert not [c for c in PROJECT["classifiers"] if c.startswith("License ::")]  # SPDX instead


def test_majors_that_matter_are_bounded():
    found = {canonicalize_name(r.name): r for r in all_requirements()}
    for name in BOUNDED:
        spec = found[canonicalize_name(name)].specifier
        assert any(s.operator == "<" for s in spec), f"{name}: no upper bound in {spec}"


def test_test_extra_holds_the_ray_and_video_extras():
    test = {canonicalize_name(r.name): r.specifier for r in requirements("test")}
    for group in ("ray", "video"):
        for r in requirements(group):
            assert test.get(canonicalize_name(r.name)) == r.specifier, (group, r)


def test_constraints_pin_every_requirement_within_its_bounds():
    pins = constraints()
    own = canonicalize_name(PROJECT["name"])
    for r in all_requirements():
        if r.marker is not None and not r.marker.evaluate({"extra": ""}):
            continue
        name = canonicalize_name(r.name)
        if name == own:  # an extra that includes another one (test = [..., "lamp[rl]"])
            continue
        assert name in pins, f"constraints.txt does not pin {r.name}"
        assert r.specifier.contains(pins[name], prereleases=True), (r, pins[name])
    assert canonicalize_name(PROJECT["name"]) not in pins


def test_the_suite_runs_on_the_tested_versions_of_what_matters():
    """The environment running these tests has the constraint set's versions of the
    dependencies that decide results (``make test`` installs with ``-c constraints.txt``)."""
    pins = constraints()
    for name in ("numpy", "scipy", "shapely", "numba", "mujoco", "torch"):
        installed = metadata.version(name).split("+")[0]
        assert installed == pins[name], (name, installed, pins[name])


def test_make_setup_installs_the_constraint_set():
    makefile = (ROOT / "Makefile").read_text()
    assert "CONSTRAINTS ?= constraints.txt" in makefile
    assert "$(PIP_CONSTRAINTS) -e '.[test]'" in makefile
    torch_pin = re.search(r"pip install --quiet torch==([\w.]+)", makefile).group(1)
    assert torch_pin == constraints()["torch"]
