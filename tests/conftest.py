"""The test session's set-up: the tests folder importable by every process the tests start
(see ``TESTS_DIR``), and the Hypothesis profiles, chosen with the HYPOTHESIS_PROFILE
environment variable:

- ``dev`` (default): random examples on every run, so local runs keep exploring;
- ``ci``: derandomised, so a CI run is reproducible and never fails on luck;
- ``stress``: ten times the examples, for hunting bugs before a release.

No profile has a per-example deadline: how fast a machine is, or how busy, never decides
a test's outcome.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from hypothesis import settings

#: This folder, on ``PYTHONPATH`` (and ``sys.path``) for every process the tests start: the
#: benchmark's job processes (spawned workers, ``lamp bench`` subprocesses, Ray workers)
#: import the stand-in job functions of ``bench_fakes.py`` by name, ``bench_fakes:...``.
TESTS_DIR = str(Path(__file__).resolve().parent)
if TESTS_DIR not in os.environ.get("PYTHONPATH", "").split(os.pathsep):
    os.environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (TESTS_DIR, os.environ.get("PYTHONPATH")) if p)
if TESTS_DIR not in sys.path:
    sys.path.insert(0, TESTS_DIR)

settings.register_profile("dev", print_blob=True, deadline=None)
settings.register_profile("ci", derandomize=True, print_blob=True, deadline=None)
settings.register_profile("stress", max_examples=1000, print_blob=True, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "dev"))
