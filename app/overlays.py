"""Overlays of one engine frame on the camera picture: one drawing function per layer.

Each `put_*` function draws one layer in place on an RGB picture of the full camera frame,
from parts of a `core.engine.FrameResult`, so the inspector can toggle layers by choosing
which functions it runs. `LAYERS` names them all with one signature, (out, result) -> None;
`draw_layers` draws the chosen ones on a copy. (In place: a copy of a camera picture per
layer was a fifth of an exported video frame's drawing time.)

Colours follow the papers where they say: paper 000 fig. 5 (vehicles: orange box, yellow
cross for the radar target that refined it, blue crosses for discarded ones), fig. 6-7
(pedestrians: bright green kept, dark green rejected, a grey search strip) and fig. 2
(pitch: blue line hints, red intersections, green cross for the calibrated vanishing point,
red cross for the detected one). Guard rails found by the engine are magenta, apart from
the ground truth's orange rails (`app.draw.GUARD_RAIL_COLOUR`).

Images: RGB (H, W, 3) uint8 indexed [row, col]; pixels (u, v) = (column, row) as in
`core.camera`.

Boxes: vehicle boxes are pixel-edge bounds (pixel centres at whole numbers, `core.vehicle`);
search areas and pedestrian boxes end exclusive on pixel centres (`core.search_area`,
`core.pedestrian`), i.e. their pixel edges are half a pixel lower. A box outline is drawn
on the pixels holding its edges (`core.search_area.box_pixels`), `BOX_THICKNESS_PX` deep
inwards, so it never covers a pixel outside the box.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence

import cv2
import numpy as np

from app.draw import (
    FONT,
    LINE_THICKNESS_PX,
    RADAR_CROSS_SIZE_PX,
    TEXT_COLOUR,
    Rgb,
    RgbImage,
    put_dashed_rectangle,
    put_horizon,
    put_road_crosses,
    put_tag,
    require_rgb_image,
)
from core.appearance import AppearanceMatch
from core.camera import CameraModel
from core.engine import FrameResult
from core.guardrail import GuardRailCheck
from core.pedestrian import CONSTRAINT_VERDICTS, FUSION_VERDICTS, PedestrianCandidate
from core.pitch import Lines, PitchResult
from core.search_area import SearchArea, box_pixels
from core.tracking import Track
from core.vehicle import TargetResult, Vehicle

Box = tuple[float, float, float, float]

# paper 000 fig. 5
RADAR_REFINED_COLOUR: Rgb = (255, 220, 0)  # yellow: the target refined a vehicle
RADAR_DISCARDED_COLOUR: Rgb = (40, 90, 255)  # blue: searched, no vehicle
RADAR_GUARD_RAIL_COLOUR: Rgb = (255, 0, 255)  # magenta: labelled guard rail
VEHICLE_COLOUR: Rgb = (255, 120, 0)  # orange: a final vehicle
VEHICLE_REJECTED_COLOUR: Rgb = (150, 90, 60)  # brown: a box the size filter dropped
SEARCH_AREA_COLOUR: Rgb = (225, 225, 225)  # near white
# paper 002, engine's findings
GUARD_RAIL_LINE_COLOUR: Rgb = (255, 0, 255)  # magenta: a followed line long enough
SHORT_LINE_COLOUR: Rgb = (140, 0, 140)  # dark magenta: a followed line too short
OVERLAP_COLOUR: Rgb = (255, 0, 255)  # hatching of areas labelled guard rail by overlap or line
# paper 000 fig. 6-7
PEDESTRIAN_COLOUR: Rgb = (0, 255, 0)  # bright green: kept
PEDESTRIAN_REJECTED_COLOUR: Rgb = (0, 120, 0)  # dark green: rejected
STRIP_GREY: Rgb = (128, 128, 128)
# paper 000 fig. 2
LINE_HINT_COLOUR: Rgb = (60, 120, 255)  # blue
INTERSECTION_COLOUR: Rgb = (255, 40, 40)  # red circles
CALIBRATED_VP_COLOUR: Rgb = (0, 220, 0)  # green cross
VANISHING_POINT_COLOUR: Rgb = (255, 40, 40)  # red cross

# the "rejected" layer's pedestrian candidates: those a fusion filter rejected
REJECTED_BY_FUSION = tuple(v for v in FUSION_VERDICTS if v != "pedestrian")

BOX_THICKNESS_PX = 2
STRIP_ALPHA = 0.25  # share of the grey in the translucent pedestrian strip
HATCH_STEP_PX = 8  # distance between hatching lines along a row
TAG_FONT_SCALE = 0.4
INTERSECTION_RADIUS_PX = 3
VP_CROSS_SIZE_PX = 18
TRACK_TAG_GAP_PX = 2
# dashes of what came without a radar return: vehicles vision found where a track expected
# them, and the areas searched for them (`core.track_search`)
DASH_PX = 6

# Short words for the verdicts of pedestrian candidates (`core.pedestrian.Verdict`).
PEDESTRIAN_REASONS: Mapping[str, str] = {
    "pedestrian": "",
    "no_top": "no top",
    "perspective": "persp",
    "size": "size",
    "aspect": "aspect",
    "motion_stereo": "motion",
    "vehicle": "vehicle",
    "radar": "radar",
    "image_motion": "moving",
    "hog": "HOG",
}


def radar_colour(verdict: str) -> Rgb:
    """The cross colour of a radar target with `core.vehicle.Verdict` `verdict`."""
    if verdict == "vehicle":
        return RADAR_REFINED_COLOUR
    if verdict == "guard_rail":
        return RADAR_GUARD_RAIL_COLOUR
    return RADAR_DISCARDED_COLOUR


def exclusive_to_edges(box_px: Box) -> Box:
    """A box ending exclusive on pixel centres (search areas, pedestrians) as pixel edges."""
    u0, v0, u1, v1 = box_px
    return u0 - 0.5, v0 - 0.5, u1 - 0.5, v1 - 0.5


def _outline(
    out: RgbImage, box_edges_px: Box, colour: Rgb, thickness_px: int, dashed: bool = False
) -> None:
    """In place: `thickness_px` nested one-pixel rectangles from the box's edge pixels in,
    in DASH_PX dashes when `dashed` (`app.draw.put_dashed_rectangle`)."""
    c0, r0, c1, r1 = box_pixels(box_edges_px)
    for k in range(thickness_px):
        if c0 + k > c1 - k or r0 + k > r1 - k:
            break
        if dashed:
            put_dashed_rectangle(out, (c0 + k, r0 + k), (c1 - k, r1 - k), colour, DASH_PX)
        else:
            cv2.rectangle(out, (c0 + k, r0 + k), (c1 - k, r1 - k), colour, 1)


def measured_shown(tracks: Sequence[Track]) -> list[Track]:
    """The shown vehicle and pedestrian tracks of `tracks` (`Track.shown`: confirmed, or a
    vehicle's shown early) measured this frame: what the demo's `confirmed` layer draws and
    the presenter counts."""
    return [t for t in tracks if t.shown and t.misses == 0 and t.kind != "guard_rail"]


def _tag(
    out: RgbImage,
    text: str,
    u_px: float,
    v_bottom_px: float,
    colour: Rgb,
    text_colour: Rgb = (0, 0, 0),
) -> None:
    """In place: `app.draw.put_tag` moved left to stay inside the image on the right."""
    (w, _), _ = cv2.getTextSize(text, FONT, TAG_FONT_SCALE, 1)
    u = min(round(u_px), out.shape[1] - w - 3)
    put_tag(out, text, max(u, 0), round(v_bottom_px), colour, text_colour, TAG_FONT_SCALE)


# --- radar and vehicles (paper 000 fig. 5, paper 001) ----------------------------------------


def put_radar_targets(out: RgbImage, targets: Sequence[TargetResult], camera: CameraModel) -> None:
    """In place: a cross where each radar target's road point (x_m, y_m, 0) projects with
    `camera` (the frame's, its pitch included), coloured by `radar_colour` of its verdict,
    labelled with its distance ahead x_m (the vehicles' `distance_m`; `app.draw.draw_radar`
    shows the range).

    targets: `VehicleResult.targets`. Targets behind the camera are skipped; crosses off the
    image are clipped.
    """
    require_rgb_image("out", out)
    half = RADAR_CROSS_SIZE_PX // 2
    put_road_crosses(
        out,
        [(t.target.x_m, t.target.y_m) for t in targets],
        camera,
        [radar_colour(t.verdict) for t in targets],
        [f"{t.target.x_m:.0f}m" for t in targets],
        (half + 2, half),
        TAG_FONT_SCALE,
    )


def put_search_areas(
    out: RgbImage,
    areas: Sequence[SearchArea],
    searched: Sequence[tuple[SearchArea, int]] = (),
    looks: Sequence[AppearanceMatch] = (),
) -> None:
    """In place: the cropped search area of each radar target (`SearchArea.box_px`), one
    pixel thick, in `SEARCH_AREA_COLOUR`; in dashes, tagged "#id", each area searched for
    a track that no radar target returned (`core.track_search`); and in dashes, tagged
    "#id look", each box where a track's look was found (`core.appearance`).

    areas: `FrameResult.areas`; searched: (area, track id) pairs; looks:
    `FrameResult.appearance`.
    """
    require_rgb_image("out", out)
    for area in areas:
        c0, r0, c1, r1 = area.box_px
        _outline(out, exclusive_to_edges((c0, r0, c1, r1)), SEARCH_AREA_COLOUR, 1)
    for area, track_id in searched:
        c0, r0, c1, r1 = area.box_px
        _outline(out, exclusive_to_edges((c0, r0, c1, r1)), SEARCH_AREA_COLOUR, 1, dashed=True)
        _tag(out, f"#{track_id}", c0, r0 - 1, SEARCH_AREA_COLOUR)
    for look in looks:
        _outline(out, look.vehicle.box_px, SEARCH_AREA_COLOUR, 1, dashed=True)
        c0, r0, _, _ = box_pixels(look.vehicle.box_px)
        _tag(out, f"#{look.track_id} look", c0, r0 - 1, SEARCH_AREA_COLOUR)


def put_vehicle_boxes(
    out: RgbImage, vehicles: Sequence[Vehicle], targets: Sequence[TargetResult] = ()
) -> None:
    """In place: the final vehicles' boxes (their bodies', `Vehicle.outline_px`) in
    `VEHICLE_COLOUR` (in dashes those without a
    radar target, found where a track expected them: `core.track_search`), and the boxes the
    size filter dropped (targets with verdict "size_filter") in `VEHICLE_REJECTED_COLOUR`
    tagged "size"; a vehicle a nearer one hides on one side (`Vehicle.hidden_side`, its
    width assumed) is tagged "hidden left" or "hidden right".

    vehicles: `VehicleResult.vehicles`; targets: `VehicleResult.targets`.
    """
    require_rgb_image("out", out)
    for t in targets:
        box = t.box_px
        if t.verdict == "size_filter" and box is not None:
            _outline(out, box, VEHICLE_REJECTED_COLOUR, BOX_THICKNESS_PX)
            c0, r0, _, _ = box_pixels(box)
            _tag(out, "size", c0, r0 - 1, VEHICLE_REJECTED_COLOUR)
    for v in vehicles:
        _outline(out, v.outline_px, VEHICLE_COLOUR, BOX_THICKNESS_PX, dashed=not v.target_indices)
        if v.hidden_side is not None:
            c0, r0, _, _ = box_pixels(v.outline_px)
            _tag(out, f"hidden {v.hidden_side}", c0, r0 - 1, VEHICLE_COLOUR)


# --- guard rails (paper 002) ----------------------------------------------------------------


def line_image_px(check: GuardRailCheck, area: SearchArea) -> np.ndarray:
    """(N, 2) float64 (u, v) image pixels of the centres of a check's followed line pixels
    (patch (row, col), `GuardRailCheck.line_px`) in its search area."""
    rows = check.line_px[:, 0].astype(np.float64) + 0.5
    cols = check.line_px[:, 1].astype(np.float64) + 0.5
    u, v = area.to_image_px(cols, rows)
    return np.stack([u, v], axis=1)


def _hatch(out: RgbImage, box: tuple[int, int, int, int], colour: Rgb) -> None:
    """In place: diagonal lines every HATCH_STEP_PX across the pixels [r0:r1, c0:c1]."""
    c0, r0, c1, r1 = box
    sub = out[r0:r1, c0:c1].copy()
    h, w = sub.shape[:2]
    for k in range(-h, w, HATCH_STEP_PX):
        cv2.line(sub, (k, h - 1), (k + h - 1, 0), colour, 1)
    out[r0:r1, c0:c1] = sub


def put_guard_rails(
    out: RgbImage, checks: Sequence[GuardRailCheck], areas: Sequence[SearchArea]
) -> None:
    """In place: the lines the guard-rail filter followed, in image pixels: `GUARD_RAIL_LINE_COLOUR`
    (2 px) where they made a guard rail, `SHORT_LINE_COLOUR` (1 px) where too short or the
    label was taken back (verdict 'off_line', `core.rail_lines`); the
    areas labelled guard rail without a line of their own, by overlap management or along
    a rail line (`core.rail_lines`), hatched in `OVERLAP_COLOUR`.

    checks: `GuardRailResult.checks`; areas: the frame's search areas (matched by
    target_index; a check without its area is skipped).
    """
    require_rgb_image("out", out)
    by_target = {a.target_index: a for a in areas}
    for check in checks:
        area = by_target.get(check.target_index)
        if area is None:
            continue
        if check.verdict in ("overlap", "line"):
            _hatch(out, area.box_px, OVERLAP_COLOUR)
            continue
        if len(check.line_px) == 0:
            continue
        pts = np.round(line_image_px(check, area)).astype(np.int32).reshape(-1, 1, 2)
        rail = check.verdict == "guard_rail"
        colour = GUARD_RAIL_LINE_COLOUR if rail else SHORT_LINE_COLOUR
        cv2.polylines(out, [pts], False, colour, LINE_THICKNESS_PX if rail else 1)


# --- pedestrians (paper 000 II-D, fig. 6-7) -----------------------------------------------


def put_pedestrian_strip(out: RgbImage, strip_rows_px: tuple[int, int]) -> None:
    """In place: the search strip, rows first .. stop - 1 blended with `STRIP_GREY`
    (`STRIP_ALPHA`)."""
    require_rgb_image("out", out)
    first, stop = max(strip_rows_px[0], 0), min(strip_rows_px[1], out.shape[0])
    if stop > first:
        band = out[first:stop].astype(np.float32)
        grey = np.array(STRIP_GREY, dtype=np.float32)
        out[first:stop] = np.round((1 - STRIP_ALPHA) * band + STRIP_ALPHA * grey).astype(np.uint8)


def put_pedestrians(
    out: RgbImage,
    candidates: Sequence[PedestrianCandidate],
    verdicts: Collection[str] | None = None,
) -> None:
    """In place: each candidate's extended box: kept ones in `PEDESTRIAN_COLOUR`, rejected ones in
    `PEDESTRIAN_REJECTED_COLOUR` (1 px) with their `PEDESTRIAN_REASONS` word on a tag
    above.

    candidates: `PedestrianResult.candidates`; verdicts: draw only the candidates with
    these verdicts (all when None). Kept boxes are drawn last, on top.
    """
    require_rgb_image("out", out)
    shown = [c for c in candidates if verdicts is None or c.verdict in verdicts]
    ordered = sorted(shown, key=lambda c: c.verdict == "pedestrian")
    for c in ordered:
        box = exclusive_to_edges(c.extended_box_px)
        if c.verdict == "pedestrian":
            _outline(out, box, PEDESTRIAN_COLOUR, BOX_THICKNESS_PX)
            continue
        _outline(out, box, PEDESTRIAN_REJECTED_COLOUR, 1)
        c0, r0, _, _ = box_pixels(box)
        reason = PEDESTRIAN_REASONS.get(c.verdict, c.verdict)
        _tag(out, reason, c0, r0 - 1, PEDESTRIAN_REJECTED_COLOUR, TEXT_COLOUR)


# --- pitch (paper 000 II-A, fig. 2) ---------------------------------------------------------


def line_segments_px(lines: Lines, top_row_px: float | None = None) -> np.ndarray:
    """(N, 4) float64 (u0, v0, u1, v1) segments of image lines a u + b v + c = 0 over the
    rows of their pixels (`Lines.rows_px`), the top extended up to `top_row_px` when given.
    Lines within 1e-6 of horizontal are left out (NaN rows) as no row range fixes them."""
    a, b, c = lines.abc[:, 0], lines.abc[:, 1], lines.abc[:, 2]
    v_top = lines.rows_px[:, 0].copy()
    if top_row_px is not None:
        v_top = np.minimum(v_top, top_row_px)
    v_bottom = lines.rows_px[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        steep = np.abs(a) > 1e-6
        u_top = np.where(steep, -(b * v_top + c) / a, np.nan)
        u_bottom = np.where(steep, -(b * v_bottom + c) / a, np.nan)
    return np.stack([u_top, v_top, u_bottom, v_bottom], axis=1)


def put_pitch(out: RgbImage, pitch: PitchResult, camera: CameraModel) -> None:
    """In place: the pitch detector's work (paper 000 fig. 2): the chosen lines in
    `LINE_HINT_COLOUR` up to the vanishing point's row, their used intersections as red
    circles, the calibrated vanishing point (green cross), the detected one (red cross), and
    the horizon of `camera` (the frame's, with the detected pitch) in
    `app.draw.HORIZON_COLOUR`.
    """
    require_rgb_image("out", out)
    put_horizon(out, camera)
    vp = pitch.vanishing_point_px
    top = float(vp[1]) if vp is not None else pitch.horizon_row_px
    for u0, v0, u1, v1 in line_segments_px(pitch.chosen, top):
        if np.all(np.isfinite([u0, u1])):
            cv2.line(out, (round(u0), round(v0)), (round(u1), round(v1)), LINE_HINT_COLOUR, 1)
    used = pitch.intersections_px[pitch.intersection_used]
    for u, v in used:
        if np.isfinite(u) and np.isfinite(v) and abs(u) < 1e5 and abs(v) < 1e5:
            cv2.circle(out, (round(u), round(v)), INTERSECTION_RADIUS_PX, INTERSECTION_COLOUR, 1)
    cu, cv_ = pitch.calibrated_vp_px
    cv2.drawMarker(
        out, (round(cu), round(cv_)), CALIBRATED_VP_COLOUR, cv2.MARKER_CROSS, VP_CROSS_SIZE_PX, 1
    )
    if vp is not None:
        cv2.drawMarker(
            out,
            (round(vp[0]), round(vp[1])),
            VANISHING_POINT_COLOUR,
            cv2.MARKER_CROSS,
            VP_CROSS_SIZE_PX,
            LINE_THICKNESS_PX,
        )


# --- tracks (core.tracking) -----------------------------------------------------------------


def put_track_ids(out: RgbImage, tracks: Sequence[Track], coasting: bool = False) -> None:
    """In place: a "#id" tag under the bottom-left corner of the box of each track measured
    this frame, in the colour of its kind (vehicles `VEHICLE_COLOUR`, pedestrians
    `PEDESTRIAN_COLOUR`); with `coasting`, instead, a "#id ?" tag under the last box of each
    track missed this frame (the box is an older frame's and is not drawn). Guard-rail
    tracks are skipped.

    The tags of all `tracks` are placed together, those measured first, so a tag that would
    cover one placed before goes under it and a measured tag never moves for a missed one:
    the two calls draw tags that do not overlap.

    tracks: e.g. `FrameResult.tracked_vehicles + FrameResult.tracked_pedestrians`.
    """
    require_rgb_image("out", out)
    (_, text_h), baseline = cv2.getTextSize("#0", FONT, TAG_FONT_SCALE, 1)
    tag_h = text_h + baseline
    placed: list[tuple[int, int, int, int]] = []  # the tags placed: (u0, v0, u1, v1)
    tagged = [t for t in tracks if t.kind != "guard_rail"]
    for t in sorted(tagged, key=lambda t: t.misses > 0):  # stable: measured, then missed
        colour = VEHICLE_COLOUR if t.kind == "vehicle" else PEDESTRIAN_COLOUR
        u0, _, _, v1 = t.outline_px
        text = f"#{t.id}" if t.misses == 0 else f"#{t.id} ?"
        (w, _), _ = cv2.getTextSize(text, FONT, TAG_FONT_SCALE, 1)
        u = max(min(round(u0), out.shape[1] - w - 3), 0)
        bottom = round(v1) + TRACK_TAG_GAP_PX + tag_h
        while any(_overlap((u, bottom - tag_h, u + w + 2, bottom), p) for p in placed):
            bottom += tag_h + 1  # under the tag it would cover
        placed.append((u, bottom - tag_h, u + w + 2, bottom))
        if (t.misses > 0) == coasting:
            _tag(out, text, u, bottom, colour)


def put_confirmed_tracks(out: RgbImage, tracks: Sequence[Track]) -> None:
    """In place: the box of each shown vehicle or pedestrian track measured this frame
    (`VEHICLE_COLOUR`, `PEDESTRIAN_COLOUR`, as `put_vehicle_boxes` and `put_pedestrians`
    draw them), tagged with its id (`put_track_ids`); tracks missed this frame, those not
    shown (`Track.shown`) and guard-rail tracks are not drawn.

    tracks: e.g. `FrameResult.tracked_vehicles + FrameResult.tracked_pedestrians`.
    """
    require_rgb_image("out", out)
    shown = measured_shown(tracks)
    for t in shown:
        if t.kind == "vehicle":
            _outline(out, t.outline_px, VEHICLE_COLOUR, BOX_THICKNESS_PX)
        else:  # a pedestrian's box has exclusive ends, as its candidate's
            _outline(out, exclusive_to_edges(t.box_px), PEDESTRIAN_COLOUR, BOX_THICKNESS_PX)
    put_track_ids(out, shown)


def _overlap(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> bool:
    """Whether two (u0, v0, u1, v1) rectangles share a pixel."""
    return a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]


# --- all layers of a FrameResult ------------------------------------------------------------

Layer = Callable[[RgbImage, FrameResult], None]  # draws in place


def _radar_layer(out: RgbImage, r: FrameResult) -> None:
    put_radar_targets(out, r.vehicle.targets, r.camera)


def _areas_layer(out: RgbImage, r: FrameResult) -> None:
    search = r.track_search
    pairs = zip((t.area for t in search.search.targets), search.track_ids, strict=True)
    put_search_areas(out, r.areas, [(a, i) for a, i in pairs if a is not None], r.appearance)


def _vehicles_layer(out: RgbImage, r: FrameResult) -> None:
    put_vehicle_boxes(out, r.vehicle.vehicles)


def _rejected_layer(out: RgbImage, r: FrameResult) -> None:
    put_vehicle_boxes(out, (), r.vehicle.targets)
    put_pedestrians(out, r.pedestrian.candidates, REJECTED_BY_FUSION)


def _rails_layer(out: RgbImage, r: FrameResult) -> None:
    put_guard_rails(out, r.guardrail.checks, r.areas)


def _strip_layer(out: RgbImage, r: FrameResult) -> None:
    put_pedestrian_strip(out, r.pedestrian.strip_rows_px)


def _pedestrians_layer(out: RgbImage, r: FrameResult) -> None:
    put_pedestrians(out, r.pedestrian.candidates, ("pedestrian",))


def _pruned_layer(out: RgbImage, r: FrameResult) -> None:
    put_pedestrians(out, r.pedestrian.candidates, CONSTRAINT_VERDICTS)


def _pitch_layer(out: RgbImage, r: FrameResult) -> None:
    put_pitch(out, r.pitch, r.camera)


def _tracks_layer(out: RgbImage, r: FrameResult) -> None:
    put_track_ids(out, r.tracked_vehicles + r.tracked_pedestrians)


def _coasting_layer(out: RgbImage, r: FrameResult) -> None:
    put_track_ids(out, r.tracked_vehicles + r.tracked_pedestrians, coasting=True)


def _confirmed_layer(out: RgbImage, r: FrameResult) -> None:
    put_confirmed_tracks(out, r.tracked_vehicles + r.tracked_pedestrians)


# In drawing order, back to front: the strip first, text last.
LAYERS: Mapping[str, Layer] = {
    "pedestrian strip": _strip_layer,
    "search areas": _areas_layer,
    "pitch": _pitch_layer,
    "guard rails": _rails_layer,
    "pruned pedestrians": _pruned_layer,
    "rejected": _rejected_layer,
    "pedestrians": _pedestrians_layer,
    "vehicles": _vehicles_layer,
    "confirmed tracks": _confirmed_layer,
    "radar": _radar_layer,
    "tracks": _tracks_layer,
    "coasting tracks": _coasting_layer,
}


def put_layers(out: RgbImage, result: FrameResult, names: Sequence[str]) -> None:
    """In place: the layers `names` (keys of `LAYERS`) of `result`, in `LAYERS` order."""
    unknown = [n for n in names if n not in LAYERS]
    if unknown:
        raise ValueError(f"names: expected layers among {', '.join(LAYERS)}, got {unknown}")
    require_rgb_image("out", out)
    for name, layer in LAYERS.items():
        if name in names:
            layer(out, result)


def draw_layers(rgb: RgbImage, result: FrameResult, names: Sequence[str]) -> RgbImage:
    """The layers `names` of `result` (`put_layers`) on a copy of `rgb`."""
    require_rgb_image("rgb", rgb)
    out = rgb.copy()
    put_layers(out, result, names)
    return out
