"""Write ``constraints.txt``: the exact versions of everything ``lamp[test]`` installs here.

Run: ``python scripts/write_constraints.py`` in an environment where the test suite has
just passed (``make test``). It reads the requirements of ``pyproject.toml`` (runtime and
every extra), follows them through the installed packages' metadata, and pins each one
to its installed version (local labels such as ``+cpu`` dropped, so that the pins resolve
on PyPI and on the PyTorch CPU index alike). ``make setup`` installs with
``-c constraints.txt``, so CI runs on exactly the tested set; ``pyproject.toml`` keeps the
looser ranges users install from.
"""

from __future__ import annotations

import argparse
import platform
import sys
from importlib import metadata
from pathlib import Path

import tomllib
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]


def top_level(pyproject: Path) -> list[Requirement]:
    """Runtime requirements and those of every extra of ``pyproject``."""
    project = tomllib.loads(pyproject.read_text())["project"]
    reqs = list(project.get("dependencies", []))
    for extra in project.get("optional-dependencies", {}).values():
        reqs += extra
    return [Requirement(r) for r in reqs]


def pins(requirements: list[Requirement], own_name: str) -> dict[str, str]:
    """name -> installed public version, for ``requirements`` and all they pull in here."""
    out: dict[str, str] = {}
    seen: set[tuple[str, frozenset[str]]] = set()
    stack = [(r, "") for r in requirements]
    while stack:
        req, extra = stack.pop()
        if req.marker is not None and not req.marker.evaluate({"extra": extra}):
            continue
        name = canonicalize_name(req.name)
        key = (name, frozenset(req.extras))
        if name == canonicalize_name(own_name) or key in seen:
            continue
        seen.add(key)
        try:
            dist = metadata.distribution(req.name)
        except metadata.PackageNotFoundError:
            raise SystemExit(f"{req.name} is required but not installed; run make setup first"
                             ) from None
        out[name] = Version(dist.version).public
        for spec in dist.requires or []:
            sub = Requirement(spec)
            for e in ("", *sorted(req.extras)):
                stack.append((sub, e))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "constraints.txt")
    args = ap.parse_args()
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    found = pins(top_level(ROOT / "pyproject.toml"), project["name"])
    header = [
        "# The versions the test suite last passed with (make test installs with -c constraints.txt).",
        f"# Python {platform.python_version()} on {platform.system()} {platform.machine()}.",
        "# Regenerate with: python scripts/write_constraints.py",
    ]
    lines = [f"{name}=={version}" for name, version in sorted(found.items())]
    args.out.write_text("\n".join(header + lines) + "\n")
    print(f"wrote {args.out} ({len(lines)} pins)", file=sys.stderr)


if __name__ == "__main__":
    main()
