"""Hypothesis profiles, chosen with the HYPOTHESIS_PROFILE environment variable.

- ``dev`` (default): random examples on every run, so local runs keep exploring;
- ``ci``: derandomised, so a CI run is reproducible and never fails on luck;
- ``stress``: ten times the examples, for hunting bugs before a release.

No profile has a per-example deadline: how fast a machine is, or how busy, never decides
a test's outcome.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("dev", print_blob=True, deadline=None)
settings.register_profile("ci", derandomize=True, print_blob=True, deadline=None)
settings.register_profile("stress", max_examples=1000, print_blob=True, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "dev"))
