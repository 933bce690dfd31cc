"""How the bench report shows planners: one validated presentation per registered planner."""

from __future__ import annotations

from dataclasses import replace

import pytest

from lamp.bench import presentation
from lamp.pipeline import registry


def test_every_registered_planner_has_a_presentation_and_nothing_else_does():
    assert set(presentation.presentations()) == set(registry.names())


def test_builtin_presentations_say_what_the_tables_said():
    assert presentation.table_order() == ("mapush", "gco-ori", "gco-var", "astar",
                                          "astar-replan", "lazy")
    assert presentation.table_ii_planners() == ("astar", "astar-replan", "lazy")
    assert presentation.paper_success("lazy") == {"random": 100, "maze": 96, "tilt": 100,
                                                  "warehouse": 88}
    assert presentation.paper_full_horizon("astar") == {"random": 100, "maze": 8, "tilt": 32,
                                                        "warehouse": 40}
    assert presentation.label("astar-replan") == "LAMP-A*_replan"
    assert presentation.color("lazy") == "#2ca02c" and presentation.marker("gco-var") == "s"


def test_a_name_without_one_is_shown_under_its_name_last():
    assert presentation.label("gone") == "gone"
    assert presentation.color("gone") == presentation.DEFAULT_COLOR
    assert presentation.marker("gone") == presentation.DEFAULT_MARKER
    assert presentation.rank("gone") > max(map(presentation.rank, registry.names()))
    assert presentation.paper_success("gone") == presentation.paper_full_horizon("gone") == {}


LAZY = presentation.presentations()["lazy"]


@pytest.mark.parametrize("change, field", [
    ({"label": " "}, "label"),
    ({"row": 1.5}, "row"),
    ({"color": "green"}, "color"),
    ({"marker": "star"}, "marker"),
    ({"paper_success": {"random": 101}}, "paper_success"),
    ({"paper_full_horizon": {"maze": 5}, "table_ii": False}, "paper_full_horizon"),
])
def test_presentation_validation_names_the_field(change, field):
    with pytest.raises(ValueError, match=field):
        replace(LAZY, **change)


def test_presentation_is_frozen_and_only_for_registered_planners():
    with pytest.raises(AttributeError):
        LAZY.label = "x"  # type: ignore[misc]
    with pytest.raises(TypeError):
        LAZY.paper_success["maze"] = 1  # type: ignore[index]
    with pytest.raises(ValueError, match="unknown planner"):
        presentation.register("not-registered", replace(LAZY))
    with pytest.raises(ValueError, match="already"):
        presentation.register("lazy", replace(LAZY))
