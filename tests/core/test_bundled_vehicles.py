"""The guard-rail filter and the vehicle detector on the bundled drives, against their exact
ground truth (paper 001's criterion), and on the real RAV4 frame.

Each frame runs as the engine will run it: pitch (with the previous frame's memory), the
search areas with the camera at that pitch, the guard-rail filter on the slow targets, the
vehicle detector on the others. Paper 001 counts a vehicle as refined when its position and
width are within 0.4 m, and as a radar false negative (RFN) when it is not entirely inside
any search area: the refined share below is over the radar-seen vehicles that are. The
floors sit under what the stages reach today, so a regression fails.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS
from core.guardrail import detect_guard_rails
from core.io.drive import Drive
from core.io.groundtruth import TruthObject
from core.params import Params
from core.pitch import detect_pitch
from core.search_area import SearchArea, search_areas
from core.vehicle import detect_vehicles

VEHICLES = ("car", "van", "truck")
STEP = 2  # every other frame
MAX_OCCLUSION = 0.5
MATCH_LATERAL_M, MATCH_DISTANCE_M = 1.5, 3.0  # a detection this close is about that vehicle
# a radar target within this of a vehicle's rear face (laterally within its width) lies on it
ON_VEHICLE_M = 1.0


@dataclass(frozen=True)
class Figures:
    seen: int  # radar-seen vehicles, less than half occluded
    contained: int  # ... entirely inside a search area of a target near their distance
    refined: int  # ... detected with position and width within refined_error_m
    false_positives: int  # detections with no vehicle near them
    detections: int
    rails_on_vehicles: int  # targets on a vehicle labelled guard rail
    slow_targets: int
    guard_rails: int


def _contained(o: TruthObject, areas: tuple[SearchArea, ...]) -> bool:
    x, y, _ = o.position_m
    half = o.size_m[1] / 2
    return any(
        a.y_right_m <= y - half and a.y_left_m >= y + half and abs(a.x_m - x) < MATCH_DISTANCE_M
        for a in areas
    )


def _on_vehicle(x_m: float, y_m: float, objects: list[TruthObject]) -> bool:
    return any(
        abs(y_m - o.position_m[1]) <= o.size_m[1] / 2
        and -ON_VEHICLE_M <= x_m - o.position_m[0] <= o.size_m[0]
        for o in objects
    )


def _run(name: str) -> Figures:
    params = Params()
    tol = params.vehicle.refined_error_m
    counts = dict.fromkeys(Figures.__dataclass_fields__, 0)
    with Drive(DEFAULT_RECORDINGS / name) as drive:
        memory = None
        for i in range(0, len(drive), STEP):
            frame = drive.frame(i)
            truth = drive.truth(i)
            assert truth is not None
            pitch = detect_pitch(frame.image, drive.camera, params.pitch, memory)
            memory = pitch.memory
            camera = drive.camera.with_pitch(pitch.pitch_rad)
            areas = search_areas(frame.image, camera, frame.radar, params.vehicle)
            rails = detect_guard_rails(areas, frame.speed_mps, params.guardrail)
            result = detect_vehicles(
                areas, frame.radar, camera, params.vehicle, rails.guard_rail_targets
            )
            vehicles = [o for o in truth.objects if o.cls in VEHICLES]
            counts["slow_targets"] += len(rails.checks)
            counts["guard_rails"] += len(rails.guard_rail_targets)
            counts["rails_on_vehicles"] += sum(
                _on_vehicle(frame.radar[t].x_m, frame.radar[t].y_m, vehicles)
                for t in rails.guard_rail_targets
            )
            for o in vehicles:
                if not o.radar_seen or o.occlusion >= MAX_OCCLUSION:
                    continue
                counts["seen"] += 1
                if not _contained(o, areas):
                    continue
                counts["contained"] += 1
                x, y, _ = o.position_m
                counts["refined"] += any(
                    abs(v.lateral_m - y) < tol
                    and abs(v.distance_m - x) < tol
                    and abs(v.width_m - o.size_m[1]) < tol
                    for v in result.vehicles
                )
            counts["detections"] += len(result.vehicles)
            counts["false_positives"] += sum(
                not any(
                    abs(v.lateral_m - o.position_m[1]) < MATCH_LATERAL_M
                    and abs(v.distance_m - o.position_m[0]) < MATCH_DISTANCE_M
                    for o in vehicles
                )
                for v in result.vehicles
            )
    return Figures(**counts)


@pytest.fixture(scope="module")
def figures() -> dict[str, Figures]:
    return {name: _run(name) for name in ("highway", "exurban", "stop_and_go")}


# refined share of the contained radar-seen vehicles, a little under today's figures
REFINED_FLOOR = {"highway": 0.75, "exurban": 0.6, "stop_and_go": 0.35}


@pytest.mark.parametrize("name", list(REFINED_FLOOR))
def test_vehicles_are_refined_on_the_bundled_drives(
    figures: dict[str, Figures], name: str, report: Callable[[str], None]
) -> None:
    f = figures[name]
    refined = f.refined / f.contained
    report(
        f"vehicles {name}: {f.refined} of {f.contained} radar-seen vehicles inside a search "
        f"area refined ({refined:.0%}; {f.seen - f.contained} of {f.seen} outside every area, "
        f"paper 001's RFN); {f.detections} detections, {f.false_positives} on no vehicle; "
        f"guard rails: {f.guard_rails} of {f.slow_targets} slow targets, "
        f"{f.rails_on_vehicles} on a vehicle"
    )
    assert f.contained > 40
    assert refined >= REFINED_FLOOR[name]


def test_most_radar_seen_vehicles_in_an_area_are_refined(figures: dict[str, Figures]) -> None:
    contained = sum(f.contained for f in figures.values())
    assert sum(f.refined for f in figures.values()) / contained > 0.5


def test_no_highway_vehicle_is_labelled_guard_rail(figures: dict[str, Figures]) -> None:
    assert figures["highway"].rails_on_vehicles == 0
    assert figures["highway"].guard_rails > 0  # and the highway's rails are found
    # today's counts elsewhere, as a regression guard (see the strict xfail below)
    assert figures["exurban"].rails_on_vehicles <= 4
    assert figures["stop_and_go"].rails_on_vehicles <= 2


@pytest.mark.xfail(
    strict=True,
    reason="exurban: 4 targets on cars parked in line with the rail, 2 covered by a rail's "
    "area, 2 whose area the curve's pitch error puts on the road's edge line; stop_and_go: 2 "
    "stopped cars whose area holds a rail-like line on the road (shadow, zebra) below their "
    "base. Paper 002 saw none.",
)
def test_no_vehicle_is_labelled_guard_rail(figures: dict[str, Figures]) -> None:
    assert all(f.rails_on_vehicles == 0 for f in figures.values())


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
