"""The manipulation model's robot radius is part of its contract with the scene.

Both proposers state the radius they make contacts for (``ProposalModel.robot_radius``);
a scene with other robots is refused before planning, naming ``robots.radius``, instead
of a run in which every proposal silently fails ``Collide``.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from lamp import solve
from lamp.cli import app
from lamp.manip import ROBOT_RADIUS, GeometricProposer, load_model
from lamp.manip.models import check_robot_radius
from lamp.scene import SceneError, scene_from_dict

DATA = Path(__file__).parent / "data"


def _scene_dict(radius: float) -> dict:
    d = json.loads((DATA / "minimal.json").read_text())
    d["robots"]["radius"] = radius
    return d


def test_proposers_state_their_robot_radius():
    assert GeometricProposer().robot_radius == ROBOT_RADIUS
    model = load_model()
    assert model.robot_radius == ROBOT_RADIUS
    # the contacts really are made for that radius: a robot centred on a contact is
    # robot_radius (+ the small gap) away from the object boundary, never closer
    props = model.propose({"type": "circle", "radius": 0.2}, (0.1, 0.0, 0.0), budget=2,
                          k=4, seed=0)
    for p in props:
        d = [float((c[0] ** 2 + c[1] ** 2) ** 0.5) - 0.2 for c in p.contacts]
        assert min(d) >= model.robot_radius - 0.01


def test_other_radius_is_refused_by_name():
    scene = scene_from_dict(_scene_dict(0.07), source="big-robots.json")
    with pytest.raises(SceneError, match=r"big-robots.json: robots.radius: .*0.05 m, got 0.07"):
        check_robot_radius(scene, GeometricProposer())
    with pytest.raises(SceneError, match="robots.radius"):
        solve(scene, "lazy", 0, model="geometric")
    check_robot_radius(scene_from_dict(_scene_dict(ROBOT_RADIUS)), GeometricProposer())


def test_lamp_run_exits_2_for_unsupported_robots(tmp_path):
    path = tmp_path / "big.json"
    path.write_text(json.dumps(_scene_dict(0.07)))
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["run", str(path), "--model", "geometric", "--out", str(out)])
    assert result.exit_code == 2, result.output
    assert "robots.radius" in result.output
    assert not (out / "result.json").exists()


def test_one_owner_for_the_team_constants():
    """Radius, row step and speed come from ``geometry.team.DEFAULT_TEAM`` everywhere."""
    from lamp.contract.trajectory import MAX_STEP
    from lamp.geometry.team import DEFAULT_TEAM, RobotTeam
    from lamp.manip.dataset import SIM_STEP
    from lamp.scene.loader import DEFAULT_ROBOT_RADIUS
    from lamp.scene.model import Scene
    from lamp.sim.simulator import MAX_STEP as SIM_MAX_STEP
    from lamp.sim.simulator import ROBOT_SPEED

    assert ROBOT_RADIUS == DEFAULT_ROBOT_RADIUS == DEFAULT_TEAM.radius
    assert Scene("s", (1.0, 1.0), (), ()).robot_radius == DEFAULT_TEAM.radius
    assert MAX_STEP == SIM_MAX_STEP == DEFAULT_TEAM.row_step and SIM_STEP < MAX_STEP
    assert DEFAULT_TEAM.speed == ROBOT_SPEED
    assert DEFAULT_TEAM.row_time == pytest.approx(0.08)
    with pytest.raises(ValueError, match="RobotTeam.speed"):
        RobotTeam(speed=0.0)


def test_validate_applies_the_model_radius_check_as_run_does(tmp_path: Path) -> None:
    """``lamp validate`` refuses robots the model does not serve (exit 2, naming
    robots.radius), as ``lamp run`` would; ``--model any`` checks the format alone."""
    from lamp.manip.models import model_robot_radius

    assert model_robot_radius("learned") == pytest.approx(load_model().robot_radius)
    assert model_robot_radius("geometric") == pytest.approx(ROBOT_RADIUS)
    bad = tmp_path / "r8.json"
    bad.write_text(json.dumps(_scene_dict(0.08)))
    runner = CliRunner()
    res = runner.invoke(app, ["validate", str(bad)])
    assert res.exit_code == 2 and "robots.radius" in res.output
    assert runner.invoke(app, ["validate", "--model", "any", str(bad)]).exit_code == 0
    good = tmp_path / "ok.json"
    good.write_text(json.dumps(_scene_dict(ROBOT_RADIUS)))
    assert runner.invoke(app, ["validate", str(good)]).exit_code == 0
