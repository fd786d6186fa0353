"""A view as a URL query and back (app.view_link): every part round-trips exactly, a new
tab's view is an empty query, and every part that cannot be used is named and left alone."""

from __future__ import annotations

from urllib.parse import parse_qs

import pytest
from hypothesis import given
from hypothesis import strategies as st

from app.state import STAGES, Layers, Panels
from app.view_link import ViewLink, link_query, parse_link_query
from core.params import Params


def test_a_new_tab_is_an_empty_query() -> None:
    assert link_query(ViewLink()) == "?"
    assert parse_link_query("") == (ViewLink(), ())
    assert parse_link_query("?") == (ViewLink(), ())


def test_every_part_round_trips() -> None:
    link = ViewLink(
        recording="highway",
        frame=90,
        layers=Layers(radar=False, areas=True, truth=True),
        panels=Panels(bird_eye=False, can=True, stage="symmetry"),
        params=Params().with_values({"vehicle.search_width_m": 2.0 / 3.0, "pitch.row_step_px": 4}),
        params_b=Params().with_value("tracking.confirm_frames", 5),
        clip=(30, 89),
        present=True,
    )
    query = link_query(link)
    assert parse_link_query(query) == (link, ())
    parts = parse_qs(query[1:], keep_blank_values=True)
    on = "areas,vehicles,guardrails,pedestrians,rejected,horizon,tracks,coasting,truth"
    assert parts["layers"] == [on]
    assert parts["a.vehicle.search_width_m"] == [repr(2.0 / 3.0)]  # every digit of the float
    assert parts["b.tracking.confirm_frames"] == ["5"]
    assert parts["clip"] == ["30-89"] and parts["present"] == ["1"]


def test_comparing_with_the_papers_values_and_no_layers_round_trip() -> None:
    link = ViewLink(layers=Layers(**dict.fromkeys(Layers.names(), False)), params_b=Params())
    query = link_query(link)
    assert "compare=1" in query and "layers=&" in query + "&"
    assert parse_link_query(query) == (link, ())


@given(
    frame=st.integers(0, 10**6),
    on=st.lists(st.sampled_from(Layers.names()), unique=True),
    stage=st.sampled_from(STAGES),
    width=st.floats(0.5, 5.0, allow_nan=False),
)
def test_any_view_round_trips(frame: int, on: list[str], stage: str, width: float) -> None:
    link = ViewLink(
        recording="a drive & more",
        frame=frame,
        layers=Layers(**{n: n in on for n in Layers.names()}),
        panels=Panels(stage=stage),
        params=Params().with_value("vehicle.search_width_m", width),
    )
    assert parse_link_query(link_query(link)) == (link, ())


@pytest.mark.parametrize(
    ("query", "named"),
    [
        ("frame=ten", "frame: expected a frame index (a whole number from 0), got 'ten'"),
        ("frame=-3", "frame: expected a frame index"),
        ("layers=radar,lasers", "layers: expected layer names of radar, areas"),
        ("panels=sonar", "panels: expected panel names of bird_eye, can, got sonar"),
        ("stage=everything", "panels: stage: expected one of motion_stereo"),
        ("clip=9-3", "clip: expected the first frame at most the last, got '9-3'"),
        ("clip=30", "clip: expected first-last frames such as 30-89, got '30'"),
        ("present=yes", "present: expected 0 or 1, got 'yes'"),
        ("zoom=3", "zoom: not a part of a view (expected one of recording, frame"),
        ("a.pitch.row_step_px=four", "a.pitch.row_step_px: expected a number, true/false"),
        ("a.pitch.no_such=1", "a: "),
        ("b.pitch.row_step_px=-1", "set B left at the defaults"),
    ],
)
def test_a_part_that_cannot_be_used_is_named_and_left_alone(query: str, named: str) -> None:
    link, problems = parse_link_query("?recording=highway&frame=7&" + query)
    assert len(problems) == 1 and named in problems[0], problems
    assert link.recording == "highway"
    assert link.frame == (7 if not query.startswith("frame") else None)
    assert link.params == Params()


def test_a_refused_set_keeps_none_of_its_values() -> None:
    link, problems = parse_link_query("a.pitch.row_step_px=4&a.pitch.sobel_threshold=-5")
    assert link.params == Params() and len(problems) == 1
