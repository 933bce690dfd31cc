"""Hypothesis profiles, chosen with the HYPOTHESIS_PROFILE environment variable.

- ``dev`` (default): random examples on every run, so local runs keep exploring;
- ``ci``: derandomised, so a CI run is reproducible and never fails on luck;
- ``stress``: ten times the examples, for hunting bugs before a release.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("dev", print_blob=True)
settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("stress", max_examples=1000, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "dev"))
