"""The bird's-eye view of one engine frame in viser's 3D scene: the road seen from above.

Two parts. `bird_eye_geometry` is pure: it places what a `core.engine.FrameResult` found
(radar targets, vehicles, confirmed tracks, guard-rail lines), the ego car and the ground
texture as numpy arrays, tested without a browser; the render worker runs it.
`BirdEyeScene` sends that geometry to a viser scene on a fixed set of node names, updated in
place frame after frame; `top_down_pose` is where a viewer's camera looks at it from,
`top_down_view` points a client's camera there.

Frame: the vehicle frame of `core.camera` and `core.tracking`, which is viser's world frame
here: x forward, y left, z up, metres, origin on the ground under the rear axle. A scene
shifted sideways by `offset_y_m` (a second parameter set drawn beside the first) has every
point at y + offset_y_m.

Ground texture: a `core.camera.BirdEyeGrid` image, row 0 the far edge (x_max_m), column 0
the left edge (y_max_m), laid on the ground over `app.panels.bird_eye_extent_m` a hair
below z = 0 (`TEXTURE_Z_M`) so that boxes and markers sit on it. viser draws an image on
its node's x-y plane with the image's right along +x and its up along -y (a three.js plane
turned half a turn about x, client `ViserImage`); `TEXTURE_WXYZ` turns the node so that
the image's up is +x (far ahead) and its right -y (the car's right):
    R = [[0, -1, 0], [-1, 0, 0], [0, 0, -1]]  (columns: images of the node's x, y, z),
half a turn about (1, -1, 0)/sqrt(2), wxyz = (0, sqrt(1/2), -sqrt(1/2), 0).

Vehicles are boxes `VEHICLE_FOOTPRINT_LENGTH_M` long (`app.panels`)
starting at the radar distance and extending away, as wide as vision measured them,
`VEHICLE_HEIGHT_M` high. Colours are those of the camera overlays (`app.overlays`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from app.draw import Rgb, RgbImage, require_rgb_image
from app.overlays import (
    GUARD_RAIL_LINE_COLOUR,
    PEDESTRIAN_COLOUR,
    VEHICLE_COLOUR,
    measured_shown,
    radar_colour,
)
from app.panels import VEHICLE_FOOTPRINT_LENGTH_M, bird_eye_extent_m
from app.state import INSPECTOR_LAYERS, Layers
from core.engine import FrameResult
from core.params import Params
from core.tracking import Kind

if TYPE_CHECKING:  # only annotations name viser: the video export does without importing it
    import viser

FloatArray = npt.NDArray[np.float64]
ColourArray = npt.NDArray[np.uint8]

SQRT_HALF = math.sqrt(0.5)
TEXTURE_WXYZ = (0.0, SQRT_HALF, -SQRT_HALF, 0.0)  # image up -> +x, image right -> -y
TEXTURE_Z_M = -0.01  # a hair below the road, so boxes and markers are drawn over it

# Display only: the radar and vision give neither a vehicle's length nor its height.
VEHICLE_HEIGHT_M = 1.5
# The ego car around the origin (under the rear axle): a mid-size car's outline.
EGO_REAR_X_M = -1.0
EGO_FRONT_X_M = 3.5
EGO_WIDTH_M = 1.8
EGO_HEIGHT_M = 1.5
EGO_COLOUR: Rgb = (90, 140, 200)  # steel blue

RADAR_MARKER_Z_M = 0.5  # markers float at bumper height, on a car's rear face
TRACK_LINE_Z_M = 0.05  # trails just over the road
TRACK_LABEL_Z_M = 2.0  # "#id" over the car's roof
RAIL_STEP_M = 2.0  # a guard-rail line is drawn as segments this long
TRACK_COLOURS: Mapping[Kind, Rgb] = {
    "vehicle": VEHICLE_COLOUR,
    "pedestrian": PEDESTRIAN_COLOUR,
    "guard_rail": GUARD_RAIL_LINE_COLOUR,
}

# Scene look
RADAR_MARKER_SIZE_M = 0.5
TRACK_LINE_THICKNESS_M = 0.15
VEHICLE_OPACITY = 0.85
JPEG_QUALITY = 90
MAX_VEHICLE_BOXES = 16
MAX_TRACK_LABELS = 16

# top_down_view: from behind and above the ego car, looking down at the road ahead
VIEW_ELEVATION_RAD = math.radians(50.0)
VIEW_DISTANCE_FACTOR = 0.85  # distance to the look-at point per metre of road shown
UP_DIRECTION = (0.0, 0.0, 1.0)


@dataclass(frozen=True, eq=False)
class BirdEyeGeometry:
    """What the bird's-eye view of one frame draws, vehicle frame (x forward, y left, z up),
    metres, shifted by offset_y_m along y. Empty parts have zero rows, never None.

    radar_points_m: (N, 3) float64, one marker per radar target at `RADAR_MARKER_Z_M`;
    radar_colours: (N, 3) uint8 RGB, `app.overlays.radar_colour` of each target's verdict.
    vehicle_centres_m, vehicle_sizes_m: (M, 3) float64 boxes (length along x, width along
    y, height), one per final vehicle; vehicle colour `VEHICLE_COLOUR`.
    track_segments_m: (K, 2, 3) float64 start and end of each step of the confirmed tracks'
    history (oldest first) at `TRACK_LINE_Z_M`; track_colours: (K, 3) uint8, by kind
    (`TRACK_COLOURS`).
    rail_segments_m: (R, 2, 3) float64 the guard-rail lines of `core.rail_lines`, sampled
    every RAIL_STEP_M at `TRACK_LINE_Z_M`, drawn in `GUARD_RAIL_LINE_COLOUR`.
    label_positions_m: (T, 3) float64, one per confirmed track over its position;
    label_texts: T strings, "#id", or "#id ?" for a track missed this frame (as the camera
    overlay).
    ego_centre_m, ego_size_m: (3,) float64, the ego car's box.
    texture_position_m: (3,) float64 centre of the ground image; texture_wxyz: (4,)
    float64 its orientation (`TEXTURE_WXYZ`); texture_width_m, texture_height_m: its size
    along y and along x (viser's render_width and render_height).
    """

    radar_points_m: FloatArray
    radar_colours: ColourArray
    vehicle_centres_m: FloatArray
    vehicle_sizes_m: FloatArray
    track_segments_m: FloatArray
    track_colours: ColourArray
    rail_segments_m: FloatArray
    label_positions_m: FloatArray
    label_texts: tuple[str, ...]
    ego_centre_m: FloatArray
    ego_size_m: FloatArray
    texture_position_m: FloatArray
    texture_wxyz: FloatArray
    texture_width_m: float
    texture_height_m: float


def _points(rows: list[tuple[float, float, float]]) -> FloatArray:
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


def _colours(rows: list[Rgb]) -> ColourArray:
    return np.array(rows, dtype=np.uint8).reshape(-1, 3)


def bird_eye_geometry(
    result: FrameResult, params: Params, offset_y_m: float = 0.0, layers: Layers = INSPECTOR_LAYERS
) -> BirdEyeGeometry:
    """The bird's-eye geometry of one engine frame (see `BirdEyeGeometry`).

    result: the frame; params: the parameters it was computed with (the ground texture
    covers `bird_eye_extent_m(params.motion_stereo)`); offset_y_m: added to every y; layers:
    the camera's layers, of which the view follows six: `radar` (the markers), `vehicles`
    (the boxes), `guardrails` (the rail lines), `tracks` (trail and label of each track
    measured this frame), `coasting` (those of the tracks missed this frame) and `confirmed`
    (the boxes of the vehicle tracks measured this frame, and the trails and labels of the
    vehicle and pedestrian ones). ValueError when offset_y_m is not finite.
    """
    if not math.isfinite(offset_y_m):
        raise ValueError(f"offset_y_m: expected a finite number of metres, got {offset_y_m}")
    dy = offset_y_m

    targets = result.vehicle.targets if layers.radar else ()
    radar_points = _points([(t.target.x_m, t.target.y_m + dy, RADAR_MARKER_Z_M) for t in targets])
    radar_colours = _colours([radar_colour(t.verdict) for t in targets])

    # (distance, lateral, width) of the boxes: the frame's vehicles, the confirmed tracks
    vehicles = [
        (v.distance_m, v.lateral_m, v.width_m)
        for v in (result.vehicle.vehicles if layers.vehicles else ())
    ]
    vehicles += [
        (t.x_m, t.y_m, t.width_m)
        for t in (measured_shown(result.tracked_vehicles) if layers.confirmed else ())
    ]
    length, height = VEHICLE_FOOTPRINT_LENGTH_M, VEHICLE_HEIGHT_M
    centres = _points([(x + length / 2, y + dy, height / 2) for x, y, _ in vehicles])
    sizes = _points([(length, w, height) for _, _, w in vehicles])

    segments: list[tuple[tuple[float, float, float], tuple[float, float, float]]] = []
    segment_colours: list[Rgb] = []
    labels: list[tuple[float, float, float]] = []
    texts: list[str] = []
    for track in result.tracking.shown:
        demo = layers.confirmed and track.kind != "guard_rail"  # as the camera's confirmed
        if not (layers.coasting if track.misses else layers.tracks or demo):
            continue
        steps = zip(track.history_m[:-1], track.history_m[1:], strict=True)
        for (x0, y0), (x1, y1) in steps:
            segments.append(((x0, y0 + dy, TRACK_LINE_Z_M), (x1, y1 + dy, TRACK_LINE_Z_M)))
            segment_colours.append(TRACK_COLOURS[track.kind])
        labels.append((track.x_m, track.y_m + dy, TRACK_LABEL_Z_M))
        texts.append(f"#{track.id}" if track.misses == 0 else f"#{track.id} ?")

    rails = [
        ((x0, y0 + dy, TRACK_LINE_Z_M), (x1, y1 + dy, TRACK_LINE_Z_M))
        for line in (result.rail_lines if layers.guardrails else ())
        for (x0, y0), (x1, y1) in itertools.pairwise(line.sampled_m(RAIL_STEP_M))
    ]

    x_min_m, x_max_m, y_min_m, y_max_m = bird_eye_extent_m(params.motion_stereo)
    return BirdEyeGeometry(
        radar_points_m=radar_points,
        radar_colours=radar_colours,
        vehicle_centres_m=centres,
        vehicle_sizes_m=sizes,
        track_segments_m=np.array(segments, dtype=np.float64).reshape(-1, 2, 3),
        track_colours=_colours(segment_colours),
        rail_segments_m=np.array(rails, dtype=np.float64).reshape(-1, 2, 3),
        label_positions_m=_points(labels),
        label_texts=tuple(texts),
        ego_centre_m=np.array(
            [(EGO_REAR_X_M + EGO_FRONT_X_M) / 2, dy, EGO_HEIGHT_M / 2], dtype=np.float64
        ),
        ego_size_m=np.array(
            [EGO_FRONT_X_M - EGO_REAR_X_M, EGO_WIDTH_M, EGO_HEIGHT_M], dtype=np.float64
        ),
        texture_position_m=np.array(
            [(x_min_m + x_max_m) / 2, (y_min_m + y_max_m) / 2 + dy, TEXTURE_Z_M],
            dtype=np.float64,
        ),
        texture_wxyz=np.array(TEXTURE_WXYZ, dtype=np.float64),
        texture_width_m=y_max_m - y_min_m,
        texture_height_m=x_max_m - x_min_m,
    )


# --- the scene ------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _Nodes:
    ground: viser.ImageHandle
    ego: viser.BoxHandle
    radar: viser.PointCloudHandle
    tracks: viser.LineSegmentsHandle
    vehicles: tuple[viser.BoxHandle, ...]
    labels: tuple[viser.LabelHandle, ...]

    def all(self) -> tuple[viser.SceneNodeHandle, ...]:
        return (self.ground, self.ego, self.radar, self.tracks, *self.vehicles, *self.labels)


class BirdEyeScene:
    """The bird's-eye view of engine frames on one viser scene, under one node-name prefix.

    scene: e.g. `client.scene`; prefix: the nodes' parent name, "/" and a name (e.g.
    "/bev_a"). A second parameter set is drawn beside the first by its own scene object
    and a geometry computed with an `offset_y_m`.

    The first `show` creates a fixed set of nodes; later calls update their attributes and
    never add or remove a node (a new name per frame would grow viser's message buffer):
    prefix/ground (image), /ego (box), /radar (point cloud), /tracks (line segments: the
    tracks' trails and the rail lines), and
    pools /vehicles/0 .. /vehicles/{MAX_VEHICLE_BOXES - 1} (boxes) and /labels/0 ..
    /labels/{MAX_TRACK_LABELS - 1} (labels), the unused ones hidden. A frame with more
    vehicles or tracks than a pool holds shows the nearest (least x) and drops the others.
    An empty radar or track node is hidden with its last contents. The scene's default
    lights cast no shadows. Wrap `show` in `client.atomic()` for the client to apply a frame
    at once.
    """

    def __init__(self, scene: viser.SceneApi, prefix: str) -> None:
        if not prefix.startswith("/") or prefix.endswith("/") or len(prefix) < 2:
            raise ValueError(f"prefix: expected '/' and a name such as '/bev_a', got {prefix!r}")
        self.scene = scene
        self.prefix = prefix
        self._nodes: _Nodes | None = None

    def show(self, geometry: BirdEyeGeometry, texture_rgb: RgbImage) -> None:
        """Draw one frame's `geometry` (`bird_eye_geometry`) on `texture_rgb`.

        texture_rgb: (H, W, 3) uint8 bird's-eye image of the frame, row 0 far, column 0 left
        (e.g. the grey `MotionStereoResult.bird_eye` as RGB), sent as JPEG. ValueError when
        it is not an RGB image.
        """
        require_rgb_image("texture_rgb", texture_rgb)
        nodes = self._nodes
        if nodes is None:
            nodes = self._nodes = self._create(geometry, texture_rgb)
        else:
            nodes.ground.image = texture_rgb
            nodes.ground.position = geometry.texture_position_m
            nodes.ground.render_width = geometry.texture_width_m
            nodes.ground.render_height = geometry.texture_height_m
            nodes.ego.position = geometry.ego_centre_m

        if len(geometry.radar_points_m):
            nodes.radar.points = geometry.radar_points_m.astype(np.float32)
            nodes.radar.colors = geometry.radar_colours
        nodes.radar.visible = len(geometry.radar_points_m) > 0

        # the tracks' trails and the rail lines share one node of line segments
        segments = np.concatenate([geometry.track_segments_m, geometry.rail_segments_m])
        if len(segments):
            rail_colours = np.tile(GUARD_RAIL_LINE_COLOUR, (len(geometry.rail_segments_m), 1))
            colours = np.concatenate([geometry.track_colours, rail_colours]).astype(np.uint8)
            nodes.tracks.points = segments.astype(np.float32)
            nodes.tracks.colors = np.repeat(colours[:, None, :], 2, axis=1)
        nodes.tracks.visible = len(segments) > 0

        nearest = np.argsort(geometry.vehicle_centres_m[:, 0], kind="stable")
        for k, box in enumerate(nodes.vehicles):
            if k < len(nearest):
                i = nearest[k]
                box.position = geometry.vehicle_centres_m[i]
                box.dimensions = _tuple3(geometry.vehicle_sizes_m[i])
            box.visible = k < len(nearest)

        nearest = np.argsort(geometry.label_positions_m[:, 0], kind="stable")
        for k, label in enumerate(nodes.labels):
            if k < len(nearest):
                i = nearest[k]
                label.position = geometry.label_positions_m[i]
                label.text = geometry.label_texts[i]
            label.visible = k < len(nearest)

    def remove(self) -> None:
        """Remove every node of this view from the scene; a later `show` creates them again."""
        if self._nodes is not None:
            for handle in self._nodes.all():
                handle.remove()
            self._nodes = None

    def _create(self, geometry: BirdEyeGeometry, texture_rgb: RgbImage) -> _Nodes:
        scene, p = self.scene, self.prefix
        # viser's default light casts shadows: three shadow-map passes a frame, for nothing
        # here (the ground image receives none). Without a GPU, each frame drawn in the
        # browser costs 18 ms instead of 25 (SwiftShader, headless Chromium).
        scene.configure_default_lights(cast_shadow=False)
        ground = scene.add_image(
            f"{p}/ground",
            texture_rgb,
            geometry.texture_width_m,
            geometry.texture_height_m,
            format="jpeg",
            jpeg_quality=JPEG_QUALITY,
            cast_shadow=False,
            wxyz=geometry.texture_wxyz,
            position=geometry.texture_position_m,
        )
        ego = scene.add_box(
            f"{p}/ego",
            color=EGO_COLOUR,
            dimensions=_tuple3(geometry.ego_size_m),
            position=geometry.ego_centre_m,
        )
        # viser needs a point and a segment to create the nodes; show() fills them.
        radar = scene.add_point_cloud(
            f"{p}/radar",
            np.zeros((1, 3)),
            np.zeros((1, 3), dtype=np.uint8),
            point_size=RADAR_MARKER_SIZE_M,
            point_shape="diamond",
            point_shading="flat",
            visible=False,
        )
        tracks = scene.add_line_segments(
            f"{p}/tracks",
            np.zeros((1, 2, 3)),
            np.zeros((1, 2, 3), dtype=np.uint8),
            thickness=TRACK_LINE_THICKNESS_M,
            visible=False,
        )
        vehicles = tuple(
            scene.add_box(
                f"{p}/vehicles/{k}",
                color=VEHICLE_COLOUR,
                dimensions=(VEHICLE_FOOTPRINT_LENGTH_M, EGO_WIDTH_M, VEHICLE_HEIGHT_M),
                opacity=VEHICLE_OPACITY,
                visible=False,
            )
            for k in range(MAX_VEHICLE_BOXES)
        )
        labels = tuple(
            scene.add_label(f"{p}/labels/{k}", "", anchor="bottom-center", visible=False)
            for k in range(MAX_TRACK_LABELS)
        )
        return _Nodes(ground, ego, radar, tracks, vehicles, labels)


class BirdEyeViews:
    """A's bird's-eye view and B's beside it on one client's scene ("/bird_eye_a",
    "/bird_eye_b"); the client's camera is pointed at them when their number changes."""

    def __init__(self, client: viser.ClientHandle) -> None:
        self._camera = client.camera
        self._scenes = (
            BirdEyeScene(client.scene, "/bird_eye_a"),
            BirdEyeScene(client.scene, "/bird_eye_b"),
        )
        self._aimed_at = 0  # views the camera was last pointed at

    def show(self, views: tuple[tuple[BirdEyeGeometry, RgbImage], ...], params: Params) -> None:
        """Draw `views` (A's, then B's; none: nothing) under A's `params`."""
        for scene, (geometry, texture) in zip(self._scenes, views, strict=False):
            scene.show(geometry, texture)
        for scene in self._scenes[len(views) :]:
            scene.remove()
        if views and len(views) != self._aimed_at:
            top_down_view(self._camera, pose_of_views(views, params))
        self._aimed_at = len(views)

    def remove(self) -> None:
        for scene in self._scenes:
            scene.remove()
        self._aimed_at = 0


def _tuple3(values: FloatArray) -> tuple[float, float, float]:
    return float(values[0]), float(values[1]), float(values[2])


@dataclass(frozen=True)
class CameraPose:
    """Where a viewer's camera stands and looks, in the scene's metres, and which way is up."""

    position_m: tuple[float, float, float]
    look_at_m: tuple[float, float, float]
    up: tuple[float, float, float] = UP_DIRECTION


def top_down_pose(params: Params, centre_y_m: float = 0.0, views: int = 1) -> CameraPose:
    """From behind and above the ego car at the road ahead, so the ego car and the ground
    texture of `params` fill the view, +z up.

    centre_y_m: the lateral middle of what to show; views: how many bird's-eye views stand
    side by side there (A, and B beside it).
    """
    x_min_m, x_max_m, y_min_m, y_max_m = bird_eye_extent_m(params.motion_stereo)
    near_m = min(x_min_m, EGO_REAR_X_M)
    look_at = np.array([(near_m + x_max_m) / 2, centre_y_m, 0.0])
    distance_m = VIEW_DISTANCE_FACTOR * max(x_max_m - near_m, views * (y_max_m - y_min_m))
    back = np.array([-math.cos(VIEW_ELEVATION_RAD), 0.0, math.sin(VIEW_ELEVATION_RAD)])
    return CameraPose(_tuple3(look_at + distance_m * back), _tuple3(look_at))


def pose_of_views(views: Sequence[tuple[BirdEyeGeometry, RgbImage]], params: Params) -> CameraPose:
    """`top_down_pose` of the bird's-eye views shown side by side (A's first), under A's
    `params`: centred between the first and the last."""
    centre_y_m = float(views[-1][0].texture_position_m[1]) / 2
    return top_down_pose(params, centre_y_m, len(views))


def top_down_view(camera: viser.CameraHandle, pose: CameraPose) -> None:
    """Point a client's camera as `pose` says."""
    camera.up_direction = pose.up
    camera.position = pose.position_m
    camera.look_at = pose.look_at_m  # after the position: moving the camera moves its look-at too
