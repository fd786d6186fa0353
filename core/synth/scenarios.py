"""The named scenarios: `highway`, `exurban`, `stop_and_go`.

Each builder lays out one drive with the difficulties the papers describe (paper 001: pitch
from road roughness and braking, radar points off the vehicle, vehicles close together,
trucks taller than the search area; paper 002: fragmented guard rails with many slow radar
returns; paper 000: pedestrians among poles and tree trunks, the ego car standing still).
Randomness (sizes, greys, gaps, exact positions) comes only from `rng`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from core.synth.road import Road, Segment
from core.synth.scene import (
    GuardRail,
    Marking,
    Patch,
    Pedestrian,
    Scene,
    StaticObject,
    Surface,
    Trajectory,
    Vehicle,
)

# Vehicle size ranges (length, width, height) in metres and radar cross-sections (dBsm).
VEHICLE_SIZES = {
    "car": ((3.9, 4.8), (1.6, 1.95), (1.4, 1.6), 10.0),
    "van": ((5.0, 6.0), (1.9, 2.1), (2.1, 2.6), 14.0),
    "truck": ((10.0, 13.0), (2.45, 2.6), (3.6, 4.0), 20.0),
}
BRAKING_MPS2 = 3.0  # a firm, ordinary stop


class _Ids:
    def __init__(self) -> None:
        self.next = 1

    def __call__(self) -> int:
        self.next += 1
        return self.next - 1


def _grey(rng: np.random.Generator) -> int:
    """Paint as a grey camera sees it: dark, bright or asphalt-like, all common."""
    kind = rng.integers(3)
    if kind == 0:
        return int(rng.integers(25, 60))
    if kind == 1:
        return int(rng.integers(165, 225))
    return int(rng.integers(70, 140))


def _vehicle(
    ids: _Ids,
    rng: np.random.Generator,
    cls: str,
    trajectory: Trajectory,
    facing_back: bool = False,
) -> Vehicle:
    (l0, l1), (w0, w1), (h0, h1), rcs = VEHICLE_SIZES[cls]
    return Vehicle(
        id=ids(),
        cls=cls,
        length_m=float(rng.uniform(l0, l1)),
        width_m=float(rng.uniform(w0, w1)),
        height_m=float(rng.uniform(h0, h1)),
        body_grey=_grey(rng),
        trajectory=trajectory,
        facing_back=facing_back,
        radar_rcs_dbsm=rcs,
    )


def _pedestrian(
    ids: _Ids, rng: np.random.Generator, trajectory: Trajectory, height_m: float | None = None
) -> Pedestrian:
    return Pedestrian(
        id=ids(),
        height_m=float(rng.uniform(1.55, 1.9)) if height_m is None else height_m,
        shirt_grey=_grey(rng),
        trousers_grey=int(rng.integers(20, 90)),
        trajectory=trajectory,
    )


def _fragments(
    rng: np.random.Generator, s0: float, s1: float, gaps: int
) -> tuple[tuple[float, float], ...]:
    """(s0, s1) with `gaps` holes of 6-20 m at random places."""
    cuts = np.sort(rng.uniform(s0 + 20, s1 - 20, size=gaps))
    pieces: list[tuple[float, float]] = []
    start = s0
    for c in cuts:
        gap = float(rng.uniform(6.0, 20.0))
        if c - start > 5:
            pieces.append((start, float(c)))
        start = float(c) + gap
    pieces.append((start, s1))
    return tuple(pieces)


def _stop_keys(v0: float, t_brake: float, t_go: float, v_after: float) -> list[tuple[float, float]]:
    return [
        (0.0, v0),
        (t_brake, v0),
        (t_brake + v0 / BRAKING_MPS2, 0.0),
        (t_go, 0.0),
        (t_go + 3.0, v_after),
    ]


def _stop_distance(v0: float, t_brake: float) -> float:
    return v0 * t_brake + v0 * v0 / (2 * BRAKING_MPS2)


def highway(seconds: float, rng: np.random.Generator) -> Scene:
    """Three lanes each way, guard rails on both sides, traffic with trucks, a braking event."""
    ids = _Ids()
    v_ego = 25.0
    length = v_ego * seconds + 500
    road = Road.from_segments(
        [Segment(150, 0.0), Segment(250, 1 / 1500), Segment(100, 0.0), Segment(length, -1 / 2000)]
    )
    t_b = 0.45 * seconds
    ego = Trajectory.from_speed(
        road,
        0.0,
        0.0,
        [
            (0, v_ego),
            (t_b, v_ego),
            (t_b + 2.0, v_ego - 6.0),
            (t_b + 4.0, v_ego - 6.0),
            (0.8 * seconds, v_ego),
        ],
        seconds,
    )
    lane = 3.75
    surfaces = (
        Surface(-60, -10.0, 82, 0.35),
        Surface(-10.0, -5.7, 122, 0.12),
        Surface(-5.7, 5.7, 104, 0.10),
        Surface(5.7, 7.8, 116, 0.12),
        Surface(7.8, 19.2, 100, 0.10),
        Surface(19.2, 60, 80, 0.35),
    )
    markings = (
        Marking(-5.6, "solid", 0.2),
        Marking(-lane / 2, "dashed"),
        Marking(lane / 2, "dashed"),
        Marking(5.6, "solid", 0.2),
        Marking(7.9, "solid", 0.2),
        Marking(7.9 + lane, "dashed"),
        Marking(7.9 + 2 * lane, "dashed"),
        Marking(19.1, "solid", 0.2),
    )
    s_end = float(ego.s_m[-1]) + 120
    rails = (
        GuardRail(ids(), "right", -9.2, _fragments(rng, -20, s_end, gaps=3)),
        GuardRail(ids(), "left", 6.75, _fragments(rng, -20, s_end, gaps=1)),
    )
    vehicles: list[Vehicle] = []
    # Lead car in the ego lane: keeps its distance, brakes with the traffic.
    lead_keys = [
        (0, v_ego),
        (t_b - 0.5, v_ego),
        (t_b + 1.5, v_ego - 6.5),
        (t_b + 4.0, v_ego - 6.0),
        (0.8 * seconds, v_ego + 0.5),
    ]
    vehicles.append(
        _vehicle(ids, rng, "car", Trajectory.from_speed(road, 32.0, 0.0, lead_keys, seconds))
    )
    # A truck in the right lane that the ego car slowly approaches (taller than a search area).
    vehicles.append(
        _vehicle(ids, rng, "truck", Trajectory.from_speed(road, 42.0, -lane, [(0, 22.0)], seconds))
    )
    # An overtaking car in the left lane, receding.
    vehicles.append(
        _vehicle(ids, rng, "car", Trajectory.from_speed(road, 6.0, lane, [(0, 29.0)], seconds))
    )
    # A van far ahead in the right lane.
    vehicles.append(
        _vehicle(ids, rng, "van", Trajectory.from_speed(road, 70.0, -lane, [(0, 23.5)], seconds))
    )
    # Two cars side by side (one radar point for both, paper 001 fig. 8a), approached slowly.
    vehicles.append(
        _vehicle(ids, rng, "car", Trajectory.from_speed(road, 95.0, lane, [(0, 22.5)], seconds))
    )
    vehicles.append(
        _vehicle(ids, rng, "car", Trajectory.from_speed(road, 96.5, 0.0, [(0, 22.5)], seconds))
    )
    # A second truck in the left lane, passing us.
    vehicles.append(
        _vehicle(ids, rng, "truck", Trajectory.from_speed(road, -25.0, lane, [(0, 28.5)], seconds))
    )
    # Oncoming traffic beyond the median, seen from the front.
    for k in range(int(seconds / 3)):
        cls = "truck" if k % 3 == 1 else "car"
        d = 7.9 + lane * (0.5 + (k % 2))
        s0 = 120.0 + 75.0 * k + float(rng.uniform(-10, 10))
        vehicles.append(
            _vehicle(
                ids,
                rng,
                cls,
                Trajectory.from_speed(road, s0, d, [(0, -24.0)], seconds),
                facing_back=True,
            )
        )
    statics: list[StaticObject] = []
    for s in np.arange(60.0, s_end, 160.0):
        statics.append(
            StaticObject(ids(), "sign", float(s + rng.uniform(-20, 20)), -10.6, 1.4, 3.2, 200, 8.0)
        )
    for s in np.arange(30.0, s_end, 55.0):
        statics.append(StaticObject(ids(), "pole", float(s), 7.2, 0.18, 9.0, 150, 6.0))
    s_bridge = float(ego.s_m[int(0.6 * len(ego.s_m))])
    patches = [Patch(s_bridge, 5.0, 9.0, 60.0, 0.45, round_shape=False)]
    for s in rng.uniform(0, s_end, size=int(s_end / 60)):
        patches.append(
            Patch(
                float(s),
                float(rng.uniform(-5, 5)),
                float(rng.uniform(2, 8)),
                float(rng.uniform(1, 3)),
                0.82,
            )
        )
    return Scene(
        name="highway",
        seconds=seconds,
        road=road,
        ego=ego,
        surfaces=surfaces,
        markings=markings,
        crosswalks_s_m=(),
        patches=tuple(patches),
        vehicles=tuple(vehicles),
        pedestrians=(),
        statics=tuple(statics),
        guard_rails=rails,
        illumination_keys=(
            (0.0, 1.0),
            (0.3 * seconds, 1.0),
            (0.4 * seconds, 0.78),
            (0.55 * seconds, 0.8),
            (0.7 * seconds, 1.06),
        ),
    )


def exurban(seconds: float, rng: np.random.Generator) -> Scene:
    """Two-lane country road: curves, parked cars, pedestrians, poles, trees and shadows."""
    ids = _Ids()
    v_ego = 15.0
    length = v_ego * seconds + 400
    road = Road.from_segments(
        [
            Segment(60, 0.0),
            Segment(110, 1 / 160),
            Segment(40, 0.0),
            Segment(130, -1 / 190),
            Segment(length, 0.0),
        ]
    )
    ego = Trajectory.from_speed(
        road, 0.0, 0.0, [(0, v_ego), (0.5 * seconds, v_ego - 2), (seconds, v_ego)], seconds
    )
    surfaces = (
        Surface(-60, -3.4, 84, 0.4),
        Surface(-3.4, -1.8, 128, 0.25),
        Surface(-1.8, 5.3, 100, 0.12),
        Surface(5.3, 6.4, 125, 0.25),
        Surface(6.4, 60, 86, 0.4),
    )
    markings = (Marking(-1.65, "solid"), Marking(1.75, "dashed"), Marking(5.15, "solid"))
    s_end = float(ego.s_m[-1]) + 110
    vehicles: list[Vehicle] = []
    lead_keys = [(0, v_ego), (0.5 * seconds, v_ego - 2.5), (seconds, v_ego + 0.5)]
    vehicles.append(
        _vehicle(ids, rng, "car", Trajectory.from_speed(road, 22.0, 0.0, lead_keys, seconds))
    )
    vehicles.append(
        _vehicle(ids, rng, "van", Trajectory.from_speed(road, 48.0, 0.0, lead_keys, seconds))
    )
    for k in range(int(seconds / 2.5)):
        cls = "van" if k % 4 == 2 else "car"
        s0 = 90.0 + 55.0 * k + float(rng.uniform(-8, 8))
        vehicles.append(
            _vehicle(
                ids,
                rng,
                cls,
                Trajectory.from_speed(road, s0, 3.5, [(0, -14.0)], seconds),
                facing_back=True,
            )
        )
    for s in np.arange(70.0, s_end, 70.0):
        facing_back = bool(rng.integers(2))
        vehicles.append(
            _vehicle(
                ids,
                rng,
                "car",
                Trajectory.from_speed(
                    road, float(s + rng.uniform(-10, 10)), -2.7, [(0, 0.0)], seconds
                ),
                facing_back,
            )
        )
    pedestrians: list[Pedestrian] = []
    for s in np.arange(45.0, s_end, 60.0):
        s0 = float(s + rng.uniform(-10, 10))
        pedestrians.append(
            _pedestrian(
                ids,
                rng,
                Trajectory.from_waypoints([(0, s0, -4.3), (seconds, s0 + 1.3 * seconds, -4.3)]),
            )
        )
    for s in np.arange(80.0, s_end, 95.0):
        pedestrians.append(
            _pedestrian(
                ids,
                rng,
                Trajectory.from_waypoints([(0, float(s), -3.9), (seconds, float(s), -3.9)]),
            )
        )
    t_cross = 0.55 * seconds
    s_cross = float(ego.at(t_cross)[0]) + 26.0
    pedestrians.append(
        _pedestrian(
            ids,
            rng,
            Trajectory.from_waypoints(
                [
                    (0, s_cross, 7.5),
                    (t_cross - 5, s_cross, 7.5),
                    (t_cross + 3, s_cross, -4.5),
                    (seconds + 1, s_cross, -4.5),
                ]
            ),
        )
    )
    statics: list[StaticObject] = []
    patches: list[Patch] = []
    for s in np.arange(20.0, s_end, 40.0):
        statics.append(StaticObject(ids(), "pole", float(s), -5.0, 0.2, 7.5, 165, 6.0))
    for side in (-1, 1):
        for s in np.arange(10.0, s_end, 22.0):
            s_t = float(s + rng.uniform(-6, 6))
            d_t = side * float(rng.uniform(7.0, 10.0))
            statics.append(
                StaticObject(
                    ids(),
                    "tree",
                    s_t,
                    d_t,
                    float(rng.uniform(0.3, 0.5)),
                    float(rng.uniform(6, 10)),
                    55,
                    4.0,
                )
            )
            if side == 1 and rng.uniform() < 0.6:  # sun from the left: shadows fall across the road
                patches.append(
                    Patch(
                        s_t + 1.5,
                        d_t - 7.0,
                        float(rng.uniform(3, 6)),
                        float(rng.uniform(7, 11)),
                        0.55,
                    )
                )
    for s in np.arange(100.0, s_end, 130.0):
        statics.append(StaticObject(ids(), "sign", float(s), -4.0, 0.7, 2.6, 215, 8.0))
    rails = (GuardRail(ids(), "right", -3.7, _fragments(rng, 55.0, 175.0, gaps=1)),)
    return Scene(
        name="exurban",
        seconds=seconds,
        road=road,
        ego=ego,
        surfaces=surfaces,
        markings=markings,
        crosswalks_s_m=(),
        patches=tuple(patches),
        vehicles=tuple(vehicles),
        pedestrians=tuple(pedestrians),
        statics=tuple(statics),
        guard_rails=rails,
        illumination_keys=((0.0, 1.05), (0.5 * seconds, 0.92), (seconds, 1.0)),
        sun_shadow_offset_m=(0.5, -0.9),
    )


def stop_and_go(seconds: float, rng: np.random.Generator) -> Scene:
    """A queue at a crossing: the ego car brakes, stands while pedestrians cross, drives on."""
    ids = _Ids()
    v0 = 9.0
    t_brake = 0.12 * seconds
    t_go = 0.75 * seconds
    road = Road.from_segments([Segment(150, 0.0), Segment(300, 1 / 400)])
    ego = Trajectory.from_speed(road, 0.0, 0.0, _stop_keys(v0, t_brake, t_go, 6.0), seconds)
    s_stop = _stop_distance(v0, t_brake)
    s_zebra = s_stop + 7.0
    surfaces = (
        Surface(-60, -5.5, 90, 0.3),
        Surface(-5.5, -2.0, 150, 0.08),
        Surface(-2.0, 5.2, 98, 0.12),
        Surface(5.2, 7.5, 150, 0.08),
        Surface(7.5, 60, 90, 0.3),
    )
    markings = (Marking(-1.85, "solid"), Marking(1.7, "dashed"), Marking(5.05, "solid"))
    vehicles: list[Vehicle] = []
    gap_s = 0.0
    for k, cls in enumerate(("car", "van", "car", "truck")):
        veh = _vehicle(ids, rng, cls, Trajectory.from_speed(road, 0.0, 0.0, [(0, 0.0)], seconds))
        stop_at = s_zebra + 6.0 + gap_s + veh.length_m / 2
        gap_s += veh.length_m + float(rng.uniform(1.5, 3.0))
        t_b = t_brake - 0.4 + 0.3 * k
        t_g = t_go - 1.5 + 0.8 * k
        s0 = stop_at - _stop_distance(v0, t_b)
        traj = Trajectory.from_speed(road, s0, 0.0, _stop_keys(v0, t_b, t_g, 6.5), seconds)
        vehicles.append(
            Vehicle(
                veh.id,
                veh.cls,
                veh.length_m,
                veh.width_m,
                veh.height_m,
                veh.body_grey,
                traj,
                False,
                veh.radar_rcs_dbsm,
            )
        )
    for k in range(5):
        s0 = 8.0 + 14.0 * k + float(rng.uniform(-2, 2))
        keys = [(0, 5.0), (0.3 * seconds, 1.5), (0.6 * seconds, 4.0), (seconds, 3.0)]
        vehicles.append(
            _vehicle(
                ids,
                rng,
                "van" if k == 2 else "car",
                Trajectory.from_speed(road, s0, 3.4, keys, seconds),
            )
        )
    pedestrians: list[Pedestrian] = []
    t_stand = t_brake + v0 / BRAKING_MPS2
    pedestrians.append(
        _pedestrian(
            ids,
            rng,
            Trajectory.from_waypoints(
                [
                    (0, s_zebra + 1.0, -5.0),
                    (t_stand + 0.5, s_zebra + 1.0, -5.0),
                    (t_stand + 8.5, s_zebra + 1.0, 6.2),
                    (seconds + 1, s_zebra + 1.0, 6.2),
                ]
            ),
        )
    )
    pedestrians.append(
        _pedestrian(
            ids,
            rng,
            Trajectory.from_waypoints(
                [
                    (0, s_zebra + 2.5, 6.5),
                    (t_stand + 2.0, s_zebra + 2.5, 6.5),
                    (t_stand + 10.0, s_zebra + 2.5, -4.5),
                    (seconds + 1, s_zebra + 2.5, -4.5),
                ]
            ),
        )
    )
    pedestrians.append(
        _pedestrian(
            ids,
            rng,
            Trajectory.from_waypoints([(0, s_zebra - 1.0, -3.0), (seconds, s_zebra - 1.0, -3.0)]),
            height_m=1.2,
        )
    )
    pedestrians.append(
        _pedestrian(
            ids,
            rng,
            Trajectory.from_waypoints(
                [(0, s_zebra + 25.0, -3.8), (seconds, s_zebra + 25.0 - 1.2 * seconds, -3.8)]
            ),
        )
    )
    statics: list[StaticObject] = []
    for s in np.arange(12.0, 250.0, 24.0):
        statics.append(StaticObject(ids(), "pole", float(s), -4.8, 0.2, 8.0, 160, 6.0))
    statics.append(StaticObject(ids(), "sign", s_zebra - 2.0, -3.2, 0.6, 2.5, 220, 8.0))
    for s in np.arange(6.0, 250.0, 18.0):
        statics.append(
            StaticObject(
                ids(),
                "tree",
                float(s + rng.uniform(-4, 4)),
                float(rng.uniform(8.0, 10.0)),
                0.35,
                7.0,
                55,
                4.0,
            )
        )
    patches = tuple(
        Patch(
            float(s),
            float(rng.uniform(-1, 4)),
            float(rng.uniform(4, 7)),
            float(rng.uniform(6, 9)),
            0.55,
        )
        for s in rng.uniform(-10, 200, size=8)
    )
    return Scene(
        name="stop_and_go",
        seconds=seconds,
        road=road,
        ego=ego,
        surfaces=surfaces,
        markings=markings,
        crosswalks_s_m=(s_zebra,),
        patches=patches,
        vehicles=tuple(vehicles),
        pedestrians=tuple(pedestrians),
        statics=tuple(statics),
        guard_rails=(),
        illumination_keys=((0.0, 0.95), (seconds, 1.02)),
        sun_shadow_offset_m=(0.7, 0.5),
    )


SCENARIOS: dict[str, Callable[[float, np.random.Generator], Scene]] = {
    "highway": highway,
    "exurban": exurban,
    "stop_and_go": stop_and_go,
}
