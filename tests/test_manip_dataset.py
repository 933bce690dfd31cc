"""The MuJoCo push dataset: acceptance, labels, determinism, storage."""

from __future__ import annotations

import numpy as np

from lamp.geometry.se2 import wrap_angle
from lamp.manip.contacts import contacts_valid
from lamp.manip.dataset import PushDataset, densify, generate


def test_generated_samples_are_consistent_and_reproducible(tmp_path):
    ds = generate(24, seed=3, chunk=8, accept_translation=0.1, accept_rotation=0.3,
                  progress=False)
    again = generate(24, seed=3, chunk=8, accept_translation=0.1, accept_rotation=0.3,
                     progress=False)
    assert 0 < len(ds) <= 24 and ds.meta["accepted"] == len(ds)
    np.testing.assert_array_equal(ds.paths, again.paths)
    per = ds.meta["per_strategy"]
    assert sum(v["tried"] for v in per.values()) == 24
    assert sum(v["kept"] for v in per.values()) == len(ds)
    for i, shape in enumerate(ds.shapes()):
        b = int(ds.budget[i])
        assert np.isnan(ds.contacts[i, b:]).all() and not np.isnan(ds.contacts[i, :b]).any()
        np.testing.assert_allclose(ds.paths[i, :b, 0], ds.contacts[i, :b])
        assert contacts_valid(shape, ds.contacts[i, :b])
        # the label is the achieved motion, accepted only near the request
        assert np.hypot(*(ds.achieved[i, :2] - ds.requested[i, :2])) <= 0.1
        assert abs(wrap_angle(ds.achieved[i, 2] - ds.requested[i, 2])) <= 0.3
    ds.save(tmp_path / "d.npz")
    back = PushDataset.load(tmp_path / "d.npz")
    np.testing.assert_allclose(back.paths, ds.paths, atol=1e-6)  # stored as float32
    assert back.meta["per_strategy"] == per


def test_densify_bounds_the_step_and_keeps_waypoints():
    rng = np.random.default_rng(0)
    p = np.cumsum(rng.normal(0, 0.05, size=(3, 12, 2)), axis=1)
    d = densify(p, 0.018)
    steps = np.hypot(*np.moveaxis(np.diff(d, axis=1), 2, 0))
    assert steps.max() <= 0.018 + 1e-12
    # every original waypoint is still there, in order (rows stay synchronised)
    idx = [int(np.flatnonzero(np.all(np.isclose(d, p[:, [t]]), axis=(0, 2)))[0])
           for t in range(p.shape[1])]
    assert idx == sorted(idx) and idx[0] == 0 and idx[-1] == d.shape[1] - 1
