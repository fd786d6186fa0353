"""The parameter panel's labels: every parameter once, its unit from its name, a field step."""

from __future__ import annotations

import pytest

from app.params_panel import _step, hint, parameter_names, unit_of
from core.params import Params, to_dict


@pytest.mark.parametrize(
    ("name", "unit"),
    [
        ("max_distance_m", "m"),
        ("edge_threshold", ""),
        ("merge_angle_rad", "rad"),
        ("min_speed_mps", "m/s"),
        ("band_height_px", "px"),
        ("gate_s", "s"),
        ("max_decel_mps2", "m/s²"),
        ("yaw_rate_radps", "rad/s"),
    ],
)
def test_a_parameters_unit_is_the_end_of_its_name(name: str, unit: str) -> None:
    assert unit_of(name) == unit


def test_every_parameter_is_listed_once_in_its_stage() -> None:
    rows = parameter_names(Params())
    data = to_dict(Params())
    assert len(rows) == sum(len(group) for group in data.values())
    assert len({(stage, name) for stage, name, _ in rows}) == len(rows)
    assert all(data[stage][name] == value for stage, name, value in rows)


def test_the_hint_gives_unit_and_the_papers_value() -> None:
    assert hint("max_distance_m", 40.0, 40.0) == "m; default: 40.0"
    assert hint("scan_bins", 8, 8) == "default: 8"
    assert hint("vp_region_px", 14.0, 40.0) == "px; default: 14.0 (papers: 40.0)"


@pytest.mark.parametrize(
    ("value", "step"), [(40.0, 0.1), (0.35, 0.001), (2.0, 0.01), (0.0, 0.001), (-3.0, 0.01)]
)
def test_a_fields_step_is_about_a_hundredth_of_its_value(value: float, step: float) -> None:
    assert _step(value) == pytest.approx(step)
