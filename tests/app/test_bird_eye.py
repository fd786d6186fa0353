"""Bird's-eye view: targets, boxes and trails where the frame says, the ground image lying
flat with far ahead and left on the left, and a scene that reuses its nodes frame after
frame."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np
import pytest
import viser
import viser.transforms as vtf
from engine_frames import DRIVE, engine_result

from app import bird_eye, overlays, panels
from app.bird_eye import (
    BirdEyeGeometry,
    BirdEyeScene,
    bird_eye_geometry,
    top_down_pose,
    top_down_view,
)
from app.draw import grey_to_rgb
from app.state import DEMO_LAYERS, Layers
from core.cli import DEFAULT_RECORDINGS
from core.engine import FrameResult, FusionEngine
from core.io.drive import Drive
from core.io.frame import RadarTarget
from core.params import Params
from core.rail_lines import RailLine
from core.tracking import Track, TrackResult
from core.vehicle import TargetResult, Vehicle, VehicleResult

PARAMS = Params()
LENGTH_M = panels.VEHICLE_FOOTPRINT_LENGTH_M
HEIGHT_M = bird_eye.VEHICLE_HEIGHT_M
MARKER_Z_M = bird_eye.RADAR_MARKER_Z_M
TRAIL_Z_M = bird_eye.TRACK_LINE_Z_M
LABEL_Z_M = bird_eye.TRACK_LABEL_Z_M
FIRST_FRAME, FRAMES = 60, 30  # highway frames 60-89: targets, vehicles and tracks come and go


def radar(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget(float(np.hypot(x_m, y_m)), float(np.arctan2(y_m, x_m)), 0.0, 1.0, x_m, y_m)


def target(verdict: str, x_m: float, y_m: float, index: int = 0) -> TargetResult:
    return TargetResult(
        index,
        radar(x_m, y_m),
        None,
        np.zeros((0, 0), np.int8),
        np.zeros((32, 0), np.float32),
        0.0,
        (),
        None,
        verdict,  # type: ignore[arg-type]
        None,
    )


def car(distance_m: float, lateral_m: float, width_m: float) -> Vehicle:
    return Vehicle((0.0, 0.0, 1.0, 1.0), distance_m, lateral_m, width_m, distance_m, (0,))


def track(
    id_: int,
    kind: str,
    history_m: Sequence[tuple[float, float]],
    misses: int = 0,
    confirmed: bool = True,
) -> Track:
    x_m, y_m = history_m[-1]
    return Track(
        id_,
        kind,  # type: ignore[arg-type]
        x_m,
        y_m,
        0.0,
        0.0,
        1.8,
        0.1,
        0.1,
        (0.0, 0.0, 1.0, 1.0),
        5,
        misses,
        5,
        confirmed,
        None if misses else 0,
        tuple(history_m),
    )


def frame(
    targets: Sequence[TargetResult] = (),
    vehicles: Sequence[Vehicle] = (),
    tracks: Sequence[Track] = (),
    rail_lines: Sequence[RailLine] = (),
) -> FrameResult:
    """The highway engine frame with its detections, tracks and rail lines replaced."""
    return dataclasses.replace(
        engine_result(),
        vehicle=VehicleResult(tuple(targets), tuple(vehicles)),
        tracking=TrackResult(tuple(tracks), ()),
        rail_lines=tuple(rail_lines),
    )


def texture(result: FrameResult) -> np.ndarray:
    return grey_to_rgb(np.asarray(result.motion_stereo.bird_eye))


# --- geometry -------------------------------------------------------------------------------


def test_targets_are_markers_at_their_road_position_in_their_verdict_colour() -> None:
    verdicts = ("vehicle", "guard_rail", "no_symmetry")
    positions = ((25.0, -1.5), (12.0, 3.0), (30.0, 0.0))
    targets = [
        target(v, x, y, k) for k, (v, (x, y)) in enumerate(zip(verdicts, positions, strict=True))
    ]
    g = bird_eye_geometry(frame(targets), PARAMS)
    np.testing.assert_array_equal(
        g.radar_points_m,
        [(25.0, -1.5, MARKER_Z_M), (12.0, 3.0, MARKER_Z_M), (30.0, 0.0, MARKER_Z_M)],
    )
    np.testing.assert_array_equal(g.radar_colours, [overlays.radar_colour(v) for v in verdicts])
    assert g.radar_colours.dtype == np.uint8


def test_vehicle_is_a_box_from_its_radar_distance_away_as_wide_as_vision_saw_it() -> None:
    g = bird_eye_geometry(frame(vehicles=[car(20.0, 1.0, 1.6)]), PARAMS)
    np.testing.assert_allclose(g.vehicle_centres_m, [(20.0 + LENGTH_M / 2, 1.0, HEIGHT_M / 2)])
    np.testing.assert_allclose(g.vehicle_sizes_m, [(LENGTH_M, 1.6, HEIGHT_M)])
    near_bottom = g.vehicle_centres_m - g.vehicle_sizes_m / 2
    np.testing.assert_allclose(near_bottom, [(20.0, 0.2, 0.0)])  # rear at the radar, on the road


def test_the_confirmed_layer_boxes_the_vehicle_tracks_measured_this_frame() -> None:
    tracks = [
        track(7, "vehicle", ((18.0, 0.5), (20.0, 1.0))),
        track(8, "vehicle", ((30.0, -3.0),), misses=1),
        track(9, "vehicle", ((40.0, 3.0),), confirmed=False),
        track(10, "pedestrian", ((9.0, -2.0),)),
        track(11, "guard_rail", ((12.0, 6.0), (11.0, 6.0))),
    ]
    only = dataclasses.replace(DEMO_LAYERS, confirmed=True)
    g = bird_eye_geometry(frame(vehicles=[car(25.0, 0.0, 1.7)], tracks=tracks), PARAMS, layers=only)
    np.testing.assert_allclose(g.vehicle_centres_m, [(20.0 + LENGTH_M / 2, 1.0, HEIGHT_M / 2)])
    np.testing.assert_allclose(g.vehicle_sizes_m, [(LENGTH_M, 1.8, HEIGHT_M)])  # its width
    assert g.label_texts == ("#7", "#10")  # measured and confirmed, not the guard rail's
    np.testing.assert_array_equal(g.track_colours, [overlays.VEHICLE_COLOUR])
    assert len(g.radar_points_m) == 0  # the frame's own proposals are not drawn


def test_track_history_gives_one_segment_per_step_and_a_label_over_its_position() -> None:
    history = ((10.0, 1.0), (12.0, 1.5), (14.0, 2.0))
    g = bird_eye_geometry(frame(tracks=[track(7, "vehicle", history)]), PARAMS)
    z = TRAIL_Z_M
    np.testing.assert_array_equal(
        g.track_segments_m,
        [[(10.0, 1.0, z), (12.0, 1.5, z)], [(12.0, 1.5, z), (14.0, 2.0, z)]],
    )
    np.testing.assert_array_equal(g.track_colours, [overlays.VEHICLE_COLOUR] * 2)
    np.testing.assert_array_equal(g.label_positions_m, [(14.0, 2.0, LABEL_Z_M)])
    assert g.label_texts == ("#7",)


def test_tracks_of_every_kind_are_drawn_in_their_colour_tentative_ones_are_not() -> None:
    tracks = [
        track(3, "pedestrian", ((8.0, -2.0), (8.5, -2.0))),
        track(4, "guard_rail", ((15.0, 6.0), (14.0, 6.0)), misses=1),
        track(5, "vehicle", ((30.0, 0.0), (31.0, 0.0)), confirmed=False),
        track(6, "vehicle", ((40.0, 0.0),)),  # one position: a label, no segment
    ]
    g = bird_eye_geometry(frame(tracks=tracks), PARAMS)
    np.testing.assert_array_equal(
        g.track_colours, [overlays.PEDESTRIAN_COLOUR, overlays.GUARD_RAIL_LINE_COLOUR]
    )
    assert g.label_texts == ("#3", "#4 ?", "#6")  # "?": missed this frame, as on the camera


def test_a_rail_line_is_drawn_along_its_stretch_on_the_guardrails_layer() -> None:
    line = RailLine("right", (-7.0, 0.0, 0.002), 10.0, 20.0, 0.1, 6)
    g = bird_eye_geometry(frame(rail_lines=[line]), PARAMS, offset_y_m=-22.0)
    step = bird_eye.RAIL_STEP_M
    xs = np.arange(10.0, 20.0 + step / 2, step)
    ys = -7.0 + 0.002 * xs**2 - 22.0
    assert g.rail_segments_m.shape == (len(xs) - 1, 2, 3)
    np.testing.assert_allclose(g.rail_segments_m[:, 0, :2], np.c_[xs[:-1], ys[:-1]])
    np.testing.assert_allclose(g.rail_segments_m[:, 1, :2], np.c_[xs[1:], ys[1:]])
    assert (g.rail_segments_m[..., 2] == TRAIL_Z_M).all()
    hidden = bird_eye_geometry(frame(rail_lines=[line]), PARAMS, layers=Layers(guardrails=False))
    assert hidden.rail_segments_m.shape == (0, 2, 3)


def test_the_view_follows_the_camera_layers_of_what_it_draws() -> None:
    result = frame(
        [target("vehicle", 20.0, 1.0)],
        [car(20.0, 1.0, 1.6)],
        [
            track(3, "vehicle", ((18.0, 1.0), (20.0, 1.0))),
            track(4, "pedestrian", ((8.0, -2.0), (8.5, -2.0)), misses=1),
        ],
    )
    everything = bird_eye_geometry(result, PARAMS)  # the inspector's layers: all four on
    assert len(everything.radar_points_m) == len(everything.vehicle_centres_m) == 1
    assert everything.label_texts == ("#3", "#4 ?")
    demo = bird_eye_geometry(result, PARAMS, layers=DEMO_LAYERS)  # a demo hides "#4 ?"
    assert demo.label_texts == ("#3",)
    np.testing.assert_array_equal(demo.track_colours, [overlays.VEHICLE_COLOUR])
    only_coasting = Layers(radar=False, vehicles=False, tracks=False, coasting=True)
    g = bird_eye_geometry(result, PARAMS, layers=only_coasting)
    assert g.label_texts == ("#4 ?",) and len(g.track_segments_m) == 1
    assert g.radar_points_m.shape == (0, 3) and g.vehicle_centres_m.shape == (0, 3)
    none = Layers(**{name: False for name in Layers.names()})
    g = bird_eye_geometry(result, PARAMS, layers=none)
    assert g.label_texts == () and g.track_segments_m.shape == (0, 2, 3)
    assert g.ego_size_m.shape == (3,)  # the ego car and the ground stay


def test_empty_frame_gives_empty_arrays_of_the_documented_shapes() -> None:
    g = bird_eye_geometry(frame(), PARAMS)
    shapes = {
        "radar_points_m": ((0, 3), np.float64),
        "radar_colours": ((0, 3), np.uint8),
        "vehicle_centres_m": ((0, 3), np.float64),
        "vehicle_sizes_m": ((0, 3), np.float64),
        "track_segments_m": ((0, 2, 3), np.float64),
        "track_colours": ((0, 3), np.uint8),
        "rail_segments_m": ((0, 2, 3), np.float64),
        "label_positions_m": ((0, 3), np.float64),
    }
    for name, (shape, dtype) in shapes.items():
        array = getattr(g, name)
        assert array.shape == shape and array.dtype == dtype, name
    assert g.label_texts == ()


def test_ego_car_stands_on_the_road_around_the_rear_axle() -> None:
    g = bird_eye_geometry(frame(), PARAMS)
    low, high = g.ego_centre_m - g.ego_size_m / 2, g.ego_centre_m + g.ego_size_m / 2
    np.testing.assert_allclose(low, (bird_eye.EGO_REAR_X_M, -bird_eye.EGO_WIDTH_M / 2, 0.0))
    np.testing.assert_allclose(
        high, (bird_eye.EGO_FRONT_X_M, bird_eye.EGO_WIDTH_M / 2, bird_eye.EGO_HEIGHT_M)
    )
    assert low[0] < 0.0 < high[0]


def test_ground_image_lies_flat_far_ahead_and_left_on_the_left() -> None:
    """viser draws an image on its node's x-y plane, its right along +x, its up along -y and
    its face along -z (client `ViserImage`: a plane turned half a turn about x). Turned by
    texture_wxyz, up must be +x (far), right -y (the car's right), and the face +z."""
    g = bird_eye_geometry(frame(), PARAMS)
    R = vtf.SO3(g.texture_wxyz).as_matrix()
    np.testing.assert_allclose(R @ (0.0, -1.0, 0.0), (1.0, 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(R @ (1.0, 0.0, 0.0), (0.0, -1.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(R @ (0.0, 0.0, -1.0), (0.0, 0.0, 1.0), atol=1e-12)
    # the image's corners land on the extent's: pixel (row 0, column 0) is far left
    x_min, x_max, y_min, y_max = panels.bird_eye_extent_m(PARAMS.motion_stereo)
    assert (g.texture_height_m, g.texture_width_m) == (x_max - x_min, y_max - y_min)
    w, h = g.texture_width_m, g.texture_height_m
    corners_node = np.array([(-w / 2, -h / 2, 0.0), (w / 2, h / 2, 0.0)])  # top-left, bottom-right
    corners = corners_node @ R.T + g.texture_position_m
    np.testing.assert_allclose(corners[:, :2], [(x_max, y_max), (x_min, y_min)], atol=1e-9)
    assert -0.05 < g.texture_position_m[2] < 0.0  # a hair under what stands on the road


def test_offset_shifts_everything_sideways_only() -> None:
    result = frame(
        [target("vehicle", 25.0, -1.5)],
        [car(20.0, 1.0, 1.6)],
        [track(7, "vehicle", ((10.0, 1.0), (12.0, 1.5)))],
    )
    a, b = bird_eye_geometry(result, PARAMS), bird_eye_geometry(result, PARAMS, -22.0)
    shift = np.array([0.0, -22.0, 0.0])
    for name in (
        "radar_points_m",
        "vehicle_centres_m",
        "track_segments_m",
        "label_positions_m",
        "ego_centre_m",
        "texture_position_m",
    ):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name) + shift, err_msg=name)
    np.testing.assert_array_equal(b.vehicle_sizes_m, a.vehicle_sizes_m)
    np.testing.assert_array_equal(b.texture_wxyz, a.texture_wxyz)


def test_engine_frame_gives_one_marker_per_target_and_one_box_per_vehicle() -> None:
    result = engine_result()
    g = bird_eye_geometry(result, PARAMS)
    assert len(g.radar_points_m) == len(result.vehicle.targets) > 0
    assert len(g.vehicle_centres_m) == len(result.vehicle.vehicles) > 0
    steps = sum(len(t.history_m) - 1 for t in result.tracking.confirmed)
    assert len(g.track_segments_m) == steps > 0
    assert len(g.label_texts) == len(result.tracking.confirmed)


def test_geometry_refuses_an_offset_that_is_not_finite() -> None:
    with pytest.raises(ValueError, match="offset_y_m: expected a finite number of metres, got nan"):
        bird_eye_geometry(frame(), PARAMS, math.nan)


# --- scene ----------------------------------------------------------------------------------


class RecordingScene:
    """A viser scene that keeps every handle its add_* methods return, and the arguments of
    its configure_default_lights calls."""

    def __init__(self, scene: viser.SceneApi) -> None:
        self._scene = scene
        self.added: list[viser.SceneNodeHandle] = []
        self.lights: list[dict[str, Any]] = []

    def configure_default_lights(self, **kwargs: Any) -> None:
        self.lights.append(kwargs)
        self._scene.configure_default_lights(**kwargs)

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._scene, name)
        if not name.startswith("add_"):
            return attr

        def add(*args: Any, **kwargs: Any) -> Any:
            handle = attr(*args, **kwargs)
            self.added.append(handle)
            return handle

        return add

    def names(self) -> list[str]:
        return [h.name for h in self.added]

    def handle(self, name: str) -> Any:
        (found,) = [h for h in self.added if h.name == name]
        return found


@pytest.fixture()
def recorder() -> Iterator[RecordingScene]:
    """The scene of a fresh viser server (no browser), recorded."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield RecordingScene(server.scene)
    server.stop()


def view(recorder: RecordingScene, prefix: str = "/bev") -> BirdEyeScene:
    return BirdEyeScene(recorder, prefix)  # type: ignore[arg-type]


def show(
    scene: BirdEyeScene, result: FrameResult, texture_of: FrameResult, offset_y_m: float = 0.0
) -> BirdEyeGeometry:
    """Draw `result` on `scene` with the texture of `texture_of`; the geometry drawn."""
    geometry = bird_eye_geometry(result, PARAMS, offset_y_m)
    scene.show(geometry, texture(texture_of))
    return geometry


@functools.cache
def drive_frames() -> tuple[FrameResult, ...]:
    """Highway frames FIRST_FRAME .. FIRST_FRAME + FRAMES - 1, processed in order."""
    with Drive(DEFAULT_RECORDINGS / DRIVE) as d:
        engine = FusionEngine(PARAMS, d.camera)
        first = engine.seek(d, FIRST_FRAME)
        rest = [engine.process(d.frame(i)) for i in range(FIRST_FRAME + 1, FIRST_FRAME + FRAMES)]
    return (first, *rest)


def visible(recorder: RecordingScene, group: str) -> list[Any]:
    return [h for h in recorder.added if h.name.startswith(f"/bev/{group}/") and h.visible]


def test_scene_adds_its_fixed_nodes_once_and_updates_them_over_a_drive(
    recorder: RecordingScene,
) -> None:
    results = drive_frames()
    scene = view(recorder)
    show(scene, results[0], results[0])
    first = recorder.names()
    assert set(first) == {
        "/bev/ground",
        "/bev/ego",
        "/bev/radar",
        "/bev/tracks",
        *(f"/bev/vehicles/{k}" for k in range(bird_eye.MAX_VEHICLE_BOXES)),
        *(f"/bev/labels/{k}" for k in range(bird_eye.MAX_TRACK_LABELS)),
    }
    counts = set()
    for result in results[1:]:
        g = show(scene, result, result)
        assert recorder.names() == first  # nothing added again, nothing new
        assert len(visible(recorder, "vehicles")) == len(g.vehicle_centres_m)
        assert len(visible(recorder, "labels")) == len(g.label_texts)
        assert recorder.handle("/bev/radar").visible == (len(g.radar_points_m) > 0)
        counts.add((len(g.vehicle_centres_m), len(g.label_texts)))
    assert len(counts) > 2  # the drive made the pools grow and shrink
    assert recorder.handle("/bev/ground").format == "jpeg"
    assert recorder.lights == [{"cast_shadow": False}]  # once, with the nodes


def test_scene_shows_a_frame_where_its_geometry_says(recorder: RecordingScene) -> None:
    result = frame(
        [target("vehicle", 25.0, -1.5), target("guard_rail", 12.0, 3.0, 1)],
        [car(20.0, 1.0, 1.6)],
        [track(7, "vehicle", ((10.0, 1.0), (12.0, 1.5), (14.0, 2.0)))],
        [RailLine("left", (6.0, 0.0), 10.0, 14.0, 0.1, 4)],
    )
    g = show(view(recorder), result, result, offset_y_m=-22.0)
    radar = recorder.handle("/bev/radar")
    np.testing.assert_allclose(radar.points, g.radar_points_m, atol=0.02)  # float16 on the wire
    np.testing.assert_array_equal(radar.colors, g.radar_colours)
    tracks = recorder.handle("/bev/tracks")
    drawn = np.concatenate([g.track_segments_m, g.rail_segments_m])  # trails, then rails
    assert len(g.rail_segments_m) == 2
    np.testing.assert_allclose(tracks.points, drawn, atol=1e-5)
    assert (tracks.colors[-2:] == overlays.GUARD_RAIL_LINE_COLOUR).all()
    (box,) = visible(recorder, "vehicles")
    np.testing.assert_allclose(box.position, g.vehicle_centres_m[0])
    np.testing.assert_allclose(box.dimensions, g.vehicle_sizes_m[0])
    (label,) = visible(recorder, "labels")
    assert label.text == "#7"
    ground = recorder.handle("/bev/ground")
    np.testing.assert_allclose(ground.position, g.texture_position_m)
    np.testing.assert_allclose(ground.wxyz, g.texture_wxyz)


def test_more_vehicles_and_tracks_than_the_pools_hold_keep_the_nearest(
    recorder: RecordingScene,
) -> None:
    """Boxes and labels beyond MAX_VEHICLE_BOXES / MAX_TRACK_LABELS are dropped, farthest
    first, without error."""
    extra = 4
    n_cars, n_tracks = bird_eye.MAX_VEHICLE_BOXES + extra, bird_eye.MAX_TRACK_LABELS + extra
    cars = [car(60.0 - 2.0 * k, 0.0, 1.8) for k in range(n_cars)]  # the farthest first
    tracks = [track(k + 1, "vehicle", ((60.0 - 2.0 * k, 3.0),)) for k in range(n_tracks)]
    result = frame(vehicles=cars, tracks=tracks)
    show(view(recorder), result, result)
    boxes = visible(recorder, "vehicles")
    assert len(boxes) == bird_eye.MAX_VEHICLE_BOXES
    assert min(b.position[0] for b in boxes) == cars[-1].distance_m + LENGTH_M / 2
    assert max(b.position[0] for b in boxes) == cars[extra].distance_m + LENGTH_M / 2
    labels = visible(recorder, "labels")
    assert len(labels) == bird_eye.MAX_TRACK_LABELS
    assert {lb.text for lb in labels} == {f"#{k + 1}" for k in range(extra, n_tracks)}


def test_empty_frame_hides_radar_tracks_and_pools_and_a_full_one_shows_them_again(
    recorder: RecordingScene,
) -> None:
    full = frame(
        [target("vehicle", 25.0, -1.5)],
        [car(20.0, 1.0, 1.6)],
        [track(7, "vehicle", ((10.0, 1.0), (12.0, 1.5)))],
    )
    scene = view(recorder)
    show(scene, frame(), full)  # empty first: nodes created hidden
    radar, tracks = recorder.handle("/bev/radar"), recorder.handle("/bev/tracks")
    assert not radar.visible and not tracks.visible
    assert not visible(recorder, "vehicles") and not visible(recorder, "labels")
    show(scene, full, full)
    assert radar.visible and tracks.visible
    assert len(visible(recorder, "vehicles")) == len(visible(recorder, "labels")) == 1
    show(scene, frame(), full)
    assert not radar.visible and not tracks.visible
    assert not visible(recorder, "vehicles") and not visible(recorder, "labels")


def test_two_views_side_by_side_use_their_own_nodes(recorder: RecordingScene) -> None:
    result = frame([target("vehicle", 25.0, -1.5)])
    a, b = view(recorder, "/bev_a"), view(recorder, "/bev_b")
    show(a, result, result)
    show(b, result, result, offset_y_m=-22.0)
    names = recorder.names()
    assert len(set(names)) == len(names)
    radar_a, radar_b = recorder.handle("/bev_a/radar"), recorder.handle("/bev_b/radar")
    np.testing.assert_allclose(radar_b.points[:, 1] - radar_a.points[:, 1], -22.0, atol=0.02)


def test_remove_removes_every_node_and_show_creates_them_again(recorder: RecordingScene) -> None:
    result = frame()
    scene = view(recorder)
    show(scene, result, result)
    handles = list(recorder.added)
    scene.remove()
    for h in handles:
        with pytest.raises(RuntimeError, match="removed"):
            h.visible = not h.visible
    show(scene, result, result)
    assert sorted(recorder.names()) == sorted([h.name for h in handles] * 2)


def test_scene_refuses_a_bad_prefix_offset_or_texture(recorder: RecordingScene) -> None:
    for prefix in ("bev", "/bev/", "/"):
        with pytest.raises(ValueError, match="prefix: expected '/' and a name"):
            view(recorder, prefix)
    grey = np.asarray(engine_result().motion_stereo.bird_eye)
    with pytest.raises(ValueError, match=r"texture_rgb: expected an \(H, W, 3\) uint8"):
        view(recorder).show(bird_eye_geometry(frame(), PARAMS), grey)
    assert recorder.added == []


# --- camera ---------------------------------------------------------------------------------


class FakeCamera:
    position: Any = None
    look_at: Any = None
    up_direction: Any = None


def test_the_top_down_pose_looks_down_from_behind_the_ego_car_at_the_road_ahead() -> None:
    pose = top_down_pose(PARAMS, -11.0)
    camera = FakeCamera()
    top_down: Callable[..., None] = top_down_view
    top_down(camera, pose)
    assert (camera.position, camera.look_at, camera.up_direction) == (
        pose.position_m,
        pose.look_at_m,
        pose.up,
    )
    x_max = panels.bird_eye_extent_m(PARAMS.motion_stereo)[1]
    look_at, position = np.asarray(camera.look_at), np.asarray(camera.position)
    assert bird_eye.EGO_REAR_X_M < look_at[0] < x_max and look_at[1:].tolist() == [-11.0, 0.0]
    assert position[0] < bird_eye.EGO_REAR_X_M and position[1] == -11.0 and position[2] > 0
    sight = look_at - position
    elevation = math.atan2(-sight[2], sight[0])
    assert elevation == pytest.approx(bird_eye.VIEW_ELEVATION_RAD)
    assert tuple(camera.up_direction) == (0.0, 0.0, 1.0)
