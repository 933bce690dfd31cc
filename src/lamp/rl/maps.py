"""The mid-level policy's training maps: drawn apart from the benchmark suites.

The benchmark's single-object families (``lamp.suites.generators``: random, maze, tilt,
warehouse) are pure functions of ``(family, index)`` with the random stream
``numpy.random.default_rng([SUITE_SEED, family, index])``. The training maps come from the
same generators, with the same checks, on streams with another base seed,
``default_rng([seed, family, index])`` with ``seed != SUITE_SEED``: maps of the same kinds
that the benchmark scenes are not among, named ``<family>-<seed>-NN`` (``maze-1-07``).
The policy is then scored (``lamp rl eval``, ``lamp bench``) on the benchmark scenes,
which it never saw in training.
"""

from __future__ import annotations

from typing import Any

from lamp.rl.tasks import FAMILIES
from lamp.scene.model import Scene

#: Base seed of the training maps' random streams (the suites' is ``SUITE_SEED``).
TRAIN_MAP_SEED = 1
#: Training maps per family (the generator draws indices 0..24 of a stream).
MAPS_PER_FAMILY = 25


def check_map_seed(seed: int, per_family: int) -> None:
    """ValueError when ``seed`` is the benchmark suites' (or not a seed) or ``per_family``
    is outside 1..25."""
    from lamp.suites.generators import SCENES_PER_FAMILY, SUITE_SEED

    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"map_seed = {seed!r}: must be an integer >= 0")
    if seed == SUITE_SEED:
        raise ValueError(f"map_seed = {seed}: the benchmark suites' seed; training maps "
                         "must come from another stream")
    if (not isinstance(per_family, int) or isinstance(per_family, bool)
            or not 1 <= per_family <= SCENES_PER_FAMILY):
        raise ValueError(f"maps_per_family = {per_family!r}: must be an integer in "
                         f"[1, {SCENES_PER_FAMILY}]")


def training_maps(seed: int = TRAIN_MAP_SEED, per_family: int = MAPS_PER_FAMILY,
                  families=FAMILIES) -> list[Scene]:
    """``per_family`` generated maps of each family with base seed ``seed`` (see the module
    docstring); deterministic in the arguments."""
    from lamp.suites.generators import generate_scene

    check_map_seed(seed, per_family)
    return [generate_scene(f, k, full_checks=False, seed=seed).scene
            for f in families for k in range(per_family)]


def maps_record(seed: int = TRAIN_MAP_SEED, per_family: int = MAPS_PER_FAMILY,
                families=FAMILIES) -> dict[str, Any]:
    """What a policy's description records about its training maps."""
    return {"generator": "lamp.suites.generators.generate_scene", "families": list(families),
            "seed": seed, "rng": "numpy.random.default_rng([seed, family, index])",
            "indices": [0, per_family - 1], "per_family": per_family,
            "maps": per_family * len(families)}
