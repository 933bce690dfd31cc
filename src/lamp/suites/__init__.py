"""Built-in benchmark suites: the LAMP paper's map families (random, maze, tilt, warehouse;
25 scenes each) and the ``iros`` sequential case study, with seeded generators and checks.

Reading: ``list_suites()``, ``suite_scenes(name)``, ``suite_dir(name)``,
``export_suite(name, directory)``, ``suite_manifest(name)``. Generating:
``lamp.suites.generators`` (families), ``lamp.suites.iros`` and
``scripts/generate_suites.py``. Checking: ``lamp.suites.checks``.
"""

from lamp.suites.registry import (
    SUITES,
    SuiteInfo,
    export_suite,
    list_suites,
    resolve_scene,
    suite_dir,
    suite_files,
    suite_info,
    suite_manifest,
    suite_scenes,
)

__all__ = [
    "SUITES",
    "SuiteInfo",
    "export_suite",
    "list_suites",
    "resolve_scene",
    "suite_dir",
    "suite_files",
    "suite_info",
    "suite_manifest",
    "suite_scenes",
]
