"""The learned proposer: API contract, sampler, training, the shipped checkpoint, the simulator."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from lamp.manip import GeometricProposer, ProposalModel, load_model
from lamp.manip.contacts import CONTACT_OFFSET, contacts_valid, signed_distance
from lamp.manip.dataset import execute_push, synthetic_dataset
from lamp.manip.evaluate import execute_proposal
from lamp.manip.network import DEFAULT_CHECKPOINT, FlowNet, FlowProposer, NetConfig
from lamp.manip.train import TrainConfig, train
from lamp.scene.model import Circle, Polygon, Rectangle

TINY = NetConfig(image_size=32, channels=(4, 8), image_dim=16, token_dim=8, traj_dim=32,
                 cond_dim=16, time_dim=16, hidden=64, blocks=1)
SHAPES = [Rectangle((0.4, 0.3)), Circle(0.2), Polygon(((0.0, 0.25), (-0.2, -0.1), (0.2, -0.1)))]
L_SHAPE = Polygon(((-0.2, -0.2), (0.2, -0.2), (0.2, 0.0), (0.0, 0.0), (0.0, 0.2), (-0.2, 0.2)))


@pytest.fixture(scope="module")
def random_model() -> FlowProposer:
    torch.manual_seed(0)
    return FlowProposer(FlowNet(TINY), traj_scale=0.07)


@pytest.fixture(scope="module")
def shipped() -> FlowProposer:
    return load_model()


def _check_contract(props, shape, budget, k, horizon=20):
    assert len(props) == k
    for p in props:
        b = p.n_robots
        assert 1 <= b <= budget
        assert p.contacts.shape == (b, 2)
        assert p.pushes.shape == (b, horizon, 2)
        np.testing.assert_array_equal(p.pushes[:, 0], p.contacts)
        assert np.all(np.isfinite(p.pushes))
        assert contacts_valid(shape, p.contacts)


@pytest.mark.parametrize("budget", [1, 2, 3])
@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: type(s).__name__)
def test_random_model_obeys_the_contract(random_model, shape, budget):
    props = random_model.propose(shape, (0.1, -0.05, 0.2), budget, k=8, seed=1)
    _check_contract(props, shape, budget, 8)
    for p in props:  # contacts sit on the contact ring (snapped)
        np.testing.assert_allclose(signed_distance(shape, p.contacts), CONTACT_OFFSET, atol=2e-3)


def test_concave_shapes_get_valid_contacts(random_model):
    for seed in range(5):
        props = random_model.propose(L_SHAPE, (0.1, 0.1, 0.3), 3, k=16, seed=seed)
        _check_contract(props, L_SHAPE, 3, 16)


def test_sampling_is_deterministic_per_seed(random_model):
    shape = {"type": "rectangle", "size": [0.4, 0.3]}
    a = random_model.propose(shape, (0.2, 0.0, 0.0), 3, k=6, seed=11)
    b = random_model.propose(shape, (0.2, 0.0, 0.0), 3, k=6, seed=11)
    c = random_model.propose(shape, (0.2, 0.0, 0.0), 3, k=6, seed=12)
    for pa, pb in zip(a, b, strict=True):
        np.testing.assert_array_equal(pa.contacts, pb.contacts)
        np.testing.assert_array_equal(pa.pushes, pb.pushes)
    assert any(not np.array_equal(pa.pushes, pc.pushes) for pa, pc in zip(a, c, strict=True))


def test_propose_batch_matches_shapes(random_model):
    motions = [(0.1, 0, 0), (0, 0.1, 0.3), (-0.1, 0.05, -0.2)]
    out = random_model.propose_batch(Circle(0.15), motions, 2, k=5, seed=0)
    assert len(out) == 3
    for props in out:
        _check_contract(props, Circle(0.15), 2, 5)


def test_overlapping_robots_are_moved_apart_or_dropped(random_model):
    box = Rectangle((0.4, 0.3))
    # slot 1 sits 2 cm from slot 0: it slides along the ring to >= 2r + margin away
    contacts = np.array([[[-0.255, 0.0], [-0.255, 0.02], [np.nan, np.nan]]])
    raw = random_model._finish(box, contacts, np.zeros((1, 3, 19, 2)), np.zeros((1, 3)))
    (p,) = random_model._to_proposals(raw, range(1))
    assert p.n_robots == 2 and contacts_valid(box, p.contacts)
    assert np.linalg.norm(p.contacts[1] - p.contacts[0]) >= 0.105 - 1e-9
    assert np.linalg.norm(p.contacts[1] - [-0.255, 0.02]) <= 0.15
    np.testing.assert_array_equal(p.pushes[:, 0], p.contacts)
    # a robot squeezed between two others with no free spot within REPAIR_SHIFT is dropped
    small = Circle(0.1)
    ang = np.array([-0.36, 0.36, 0.0])
    c = 0.155 * np.stack([np.cos(ang), np.sin(ang)], axis=1)[None]
    raw = random_model._finish(small, c, np.zeros((1, 3, 19, 2)), np.zeros((1, 3)))
    (p,) = random_model._to_proposals(raw, range(1))
    assert p.n_robots == 2 and contacts_valid(small, p.contacts)
    np.testing.assert_allclose(p.contacts, c[0, :2], atol=1e-3)


def test_tiny_training_run_lowers_the_loss_and_resumes(tmp_path):
    ds = synthetic_dataset(96, seed=0)
    cfg = TrainConfig(epochs=6, images_per_step=16, draws_per_image=2, lr=3e-3, seed=0,
                      val_fraction=0.1)
    summary = train(ds, tmp_path, cfg, TINY, progress=False)
    hist = [json.loads(x) for x in (tmp_path / "losses.jsonl").read_text().splitlines()]
    assert len(hist) == 6 and summary["epochs_done"] == 6
    first = hist[0]["train_ce"] + hist[0]["train_mse"]
    last = hist[-1]["train_ce"] + hist[-1]["train_mse"]
    assert last < first - 0.3
    assert hist[-1]["val_ce"] < hist[0]["val_ce"]
    # resuming continues from the saved epoch instead of starting over
    train(ds, tmp_path, TrainConfig(**{**cfg.__dict__, "epochs": 7}), TINY, progress=False)
    hist = [json.loads(x) for x in (tmp_path / "losses.jsonl").read_text().splitlines()]
    assert [h["epoch"] for h in hist] == [1, 2, 3, 4, 5, 6, 7]
    # a finished run trains nothing more and reports its history
    again = train(ds, tmp_path, TrainConfig(**{**cfg.__dict__, "epochs": 7}), TINY,
                  progress=False)
    assert again["epochs_done"] == 7
    assert len((tmp_path / "losses.jsonl").read_text().splitlines()) == 7
    model = load_model(tmp_path / "model.pt")
    _check_contract(model.propose(Circle(0.2), (0.1, 0, 0), 2, k=3, seed=0), Circle(0.2), 2, 3)


def test_shipped_checkpoint_loads_weights_only_and_gives_valid_contacts(shipped):
    assert DEFAULT_CHECKPOINT.stat().st_size <= 10 * 2**20
    payload = torch.load(DEFAULT_CHECKPOINT, map_location="cpu", weights_only=True)
    assert payload["format"] == "lamp-flow-dc/1"
    meta_file = DEFAULT_CHECKPOINT.with_suffix(".json")
    meta = json.loads(meta_file.read_text())
    assert meta["data"]["samples"] > 0 and meta["epochs_done"] > 0
    assert isinstance(shipped, ProposalModel)
    for shape in SHAPES:
        for budget in (1, 2, 3):
            props = shipped.propose(shape, (0.15, 0.05, 0.2), budget, k=16, seed=0)
            _check_contract(props, shape, budget, 16)
    props = shipped.propose({"type": "rectangle", "size": [0.4, 0.3]}, motion=(0.2, 0.0, 0.0),
                            budget=3, k=16, seed=0)
    assert np.mean([p.n_robots for p in props]) > 2.5  # budget 3 mostly uses 3 robots


def test_shipped_model_pushes_a_box_roughly_the_requested_way(shipped):
    box = Rectangle((0.4, 0.3))
    motion = np.array([0.15, 0.0, 0.0])
    props = shipped.propose(box, motion, 3, k=4, seed=0)
    errs = [execute_proposal(box, p, motion)["err_t"] for p in props]
    assert np.median(errs) < 0.06


@pytest.mark.parametrize("motion", [(0.15, 0.0, 0.0), (0.05, 0.1, 0.25), (0.0, 0.0, -0.4)])
def test_geometric_pushes_move_a_box_the_requested_way_in_the_simulator(motion):
    box = Rectangle((0.4, 0.3))
    m = np.array(motion)
    props = GeometricProposer().propose(box, m, 3, k=4, seed=0)
    err_t, err_r = [], []
    for p in props:
        out = execute_push(box, p.contacts, p.pushes)
        err_t.append(np.hypot(*(out.achieved[:2] - m[:2])))
        err_r.append(abs(out.achieved[2] - m[2]))
        # recorded robot paths follow the commanded pushes closely (robots are not blocked)
        assert np.max(np.abs(out.robot_paths - p.pushes)) < 0.02
    assert max(err_t) < 0.05 and max(err_r) < 0.2
    assert np.median(err_t) < 0.02 and np.median(err_r) < 0.06
    # and the same with the approach phase of the evaluation
    res = execute_proposal(box, props[0], m)
    assert res["err_t"] < 0.05 and res["err_r"] < 0.2 and res["valid"] == 1.0
