"""The vehicle detector and the guard-rail filter on the bundled drives, scored by
core.evaluation (paper 001's frame statistics, paper 002's guard-rail errors) against their
exact ground truth, and on the real RAV4 frame.

Paper 001 counts a framed vehicle as refined (RD) when a detection is within 0.4 m of it in
distance, lateral position and width, and as a radar false negative (RFN) when no search
area contains it: the refined share below is RD / (RD + FN), over the vehicles that an area
contains. The floors sit under what the engine reaches today, so a regression fails.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from core.evaluation.evaluate import RecordingReport
from core.io.drive import Drive
from core.params import Params
from core.search_area import search_areas
from core.vehicle import detect_vehicles

# refined share of the vehicles inside a search area, a little under today's figures
REFINED_FLOOR = {"highway": 0.75, "exurban": 0.65, "stop_and_go": 0.33}


def _by_name(reports: list[RecordingReport]) -> dict[str, RecordingReport]:
    return {r.name: r for r in reports}


@pytest.mark.parametrize("name", list(REFINED_FLOOR))
def test_vehicles_are_refined_on_the_bundled_drives(
    bundled_reports: list[RecordingReport], name: str, report: Callable[[str], None]
) -> None:
    r = _by_name(bundled_reports)[name]
    v, g = r.vehicles, r.guardrails
    contained = v.rd + v.fn
    refined = v.rd / contained
    report(
        f"vehicles {name}: {v.rd} of {contained} framed vehicles inside a search area refined "
        f"({refined:.0%}; {v.rfn} of {v.framed} outside every area, paper 001's RFN); "
        f"{v.fp} FP, {v.nvo} NVO; guard rails: {g.labelled} of {g.slow_targets} slow targets "
        f"labelled, {g.vehicles_labelled} on a vehicle"
    )
    assert contained > 40
    assert refined >= REFINED_FLOOR[name]


def test_most_vehicles_in_an_area_are_refined(bundled_reports: list[RecordingReport]) -> None:
    rd = sum(r.vehicles.rd for r in bundled_reports)
    assert rd / (rd + sum(r.vehicles.fn for r in bundled_reports)) > 0.6


def test_no_highway_or_stop_and_go_vehicle_is_labelled_guard_rail(
    bundled_reports: list[RecordingReport],
) -> None:
    """The cars crawling in stop_and_go's queues are faster than a rail (1.5 m/s)."""
    by_name = _by_name(bundled_reports)
    assert by_name["highway"].guardrails.vehicles_labelled == 0
    assert by_name["highway"].guardrails.labelled > 0  # and the highway's rails are found
    assert by_name["stop_and_go"].guardrails.vehicles_labelled == 0
    # today's count on exurban, as a regression guard (see the strict xfail below): 6
    # before the vehicle border and base checks (core/vehicle.py, steps 6-7), 7 after them,
    # through the tracker (which vehicles are tracked decides which slow targets are checked);
    # 12 since rail lines leave out wrong returns (core/rail_lines.py Notes: cars parked
    # beside the rail get a line along them), 13 with the line 0.15 m up (core/guardrail.py
    # Notes; on drives of new seeds it labelled 1-5 fewer)
    assert by_name["exurban"].guardrails.vehicles_labelled <= 13


@pytest.mark.xfail(
    strict=True,
    reason="exurban: targets on cars parked in line with the rail, some covered by a rail's "
    "area, some whose area the curve's pitch error puts on the road's edge line (causes found "
    "on every other frame in issue 5; the counts here are every frame's). Paper 002 saw none.",
)
def test_no_vehicle_is_labelled_guard_rail(bundled_reports: list[RecordingReport]) -> None:
    assert all(r.guardrails.vehicles_labelled == 0 for r in bundled_reports)


def test_rav4_silver_car_ahead_is_found(rav4: Path) -> None:
    """The real frame with its real radar tracks: the 29.3 m track straight ahead yields a
    box on the silver car in the ego lane (measured on the frame: 565..624 px across, base
    at 432 px in the 1164x874 original)."""
    params = Params().vehicle
    with Drive(rav4) as drive:
        frame, camera = drive.frame(0), drive.camera
    sx = camera.intrinsics.width_px / 1164
    sy = camera.intrinsics.height_px / 874
    ahead = min(
        range(len(frame.radar)),
        key=lambda i: np.hypot(frame.radar[i].x_m - 29.3, frame.radar[i].y_m),
    )
    result = detect_vehicles(
        search_areas(frame.image, camera, frame.radar, params), frame.radar, camera, params
    )
    r = result.targets[ahead]
    assert r.verdict == "vehicle" and r.vehicle_index is not None
    v = result.vehicles[r.vehicle_index]
    u0, _, u1, vb = v.box_px
    assert 565 * sx - 4 <= u0 and u1 <= 624 * sx + 4  # on the car, within 4 px
    assert (u1 - u0) >= 0.7 * (624 - 565) * sx  # most of its width
    assert vb == pytest.approx(432 * sy, abs=6)  # its base
    assert v.distance_m == pytest.approx(29.3, abs=0.3)
    assert abs(v.lateral_m) < 0.5 and 1.3 <= v.width_m <= 2.0
