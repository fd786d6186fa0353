"""The evaluation's figures as plain-text tables in the papers' layout, markdown, CSV or JSON.

`as_json` holds every figure: {"recordings": [{"name": ..., <figures>}], "total": {<figures>}}
with <figures> = {"frames", "vehicles": {"frames": {rd, fn, rfn, fp, nvo, framed, the
shares, supplied_refined_share_by_class (RD / (RD + FN) per car, van, truck),
supplied_refined_share_within_50_m (RD / (RD + FN) of those within 50 m), and where
each FN, RFN, FP, NVO happened as [frame, id] pairs}, "events": {events, radar_miss,
not_refined, refined, refined_share, refined_share_of_radar_supplied}}, "guardrails",
"pedestrians" (per filter: symmetry, motion_stereo, vehicles, radar), "motion_stereo", "pitch",
"tracking", and with --baselines "baselines": {"pedestrians", "pitch", "motion_stereo"},
each the baseline beside the engine's figure with their median ms per frame}; shares are
fractions 0-1 (null when undefined). The total carries counts only; frame listings stay
with their recordings. CSV is the same figures flattened, one
line per recording and figure (`recording,figure,value`), listings left out.
"""

from __future__ import annotations

import csv
import io
import math
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from core.bench import PAPER_002_MS

from .baselines import Timing
from .evaluate import (
    FINAL_PEDESTRIAN_STAGE,
    PEDESTRIAN_STAGES,
    RecordingReport,
    error_listings,
    total,
)
from .mot import MotScore
from .objects import BoxScore, MaskScore, PitchScore, RailScore
from .vehicles import SUPPLIED_NEAR_M, VEHICLE_CLASSES, EventStats, FrameStats

TIMING_TITLE = "Guard rails: execution time per frame, ms, one thread (paper 002, table I)"
BASELINE_TIMING_TITLE = "Baselines: ms per frame (median, one thread, the same frames)"
# tables whose figures change from run to run
TIMED_TITLES = (TIMING_TITLE, BASELINE_TIMING_TITLE)
PEDESTRIAN_TITLES = {
    "symmetry": "symmetry alone",
    "motion_stereo": "+ motion stereo",
    "vehicles": "+ vehicles",
    "radar": "+ radar (beyond)",
    "image_motion": "+ image motion (beyond)",
    "hog": "+ HOG (beyond)",
}


# a refined vehicle's box should overlap its true box by this much of their union (issue 32)
IOU_GOOD = 0.6


def _fixed(x: float) -> str:
    """Two places; "-" for none (NaN: no frame had the figure, e.g. a true pitch)."""
    return "-" if math.isnan(x) else f"{x:.2f}"


def _percent(x: float) -> str:
    return "-" if math.isnan(x) else f"{x:.0%}"


def _share(x: float) -> float | None:
    return None if math.isnan(x) else round(x, 4)


def _ratio(part: int, whole: int) -> float | None:
    return round(part / whole, 4) if whole else None


def _distance_errors(s: FrameStats) -> str:
    """The distance error's signed median and the 90th percentile of its size, metres."""
    if not s.distance_error_m:
        return "-"
    return f"{s.distance_error_median_m:+.2f} / {s.distance_error_p90_m:.2f}"


def _by_class(s: FrameStats) -> str:
    """RD / (RD + FN) of each vehicle class, in VEHICLE_CLASSES' order ("-": no vehicle of
    that class was RD or FN)."""
    return " / ".join(_fixed(s.supplied_refined_share(c)) for c in VEHICLE_CLASSES)


def _pairs(at: Sequence[tuple[int, int]]) -> list[list[int]]:
    return [[frame, what] for frame, what in at]


def _frames_json(s: FrameStats, listings: bool) -> dict[str, Any]:
    out: dict[str, Any] = {
        "rd": s.rd,
        "fn": s.fn,
        "rfn": s.rfn,
        "fp": s.fp,
        "nvo": s.nvo,
        "framed": s.framed,
        "rd_share": _ratio(s.rd, s.framed),
        "fn_share": _ratio(s.fn, s.framed),
        "rfn_share": _ratio(s.rfn, s.framed),
        "rd_iou_median": _share(s.rd_iou_median),
        "rd_iou_good_share": _share(s.rd_iou_share(IOU_GOOD)),
        "distance_error_median_m": _share(s.distance_error_median_m),
        "distance_error_p90_m": _share(s.distance_error_p90_m),
        "supplied_refined_share_by_class": {
            c: _share(s.supplied_refined_share(c)) for c in VEHICLE_CLASSES
        },
        f"supplied_refined_share_within_{SUPPLIED_NEAR_M:g}_m": _share(
            s.supplied_refined_share_near
        ),
    }
    if listings:
        out |= {
            "fn_at": _pairs(s.fn_at),
            "rfn_at": _pairs(s.rfn_at),
            "fp_at": _pairs(s.fp_at),
            "nvo_at": _pairs(s.nvo_at),
        }
    return out


def _events_json(e: EventStats) -> dict[str, Any]:
    return {
        "events": e.events,
        "radar_miss": e.radar_miss,
        "not_refined": e.not_refined,
        "refined": e.refined,
        "refined_share": _share(e.refined_share) if e.events else None,
        "refined_share_of_radar_supplied": _share(e.refined_share_of_radar_supplied)
        if e.events - e.radar_miss
        else None,
    }


def _if_rail_truth(r: RailScore, count: int) -> str:
    """A count that needs guard-rail truth, "-" where no frame had any."""
    return str(count) if r.rail_truth_frames else "-"


def _rails_json(r: RailScore, listings: bool) -> dict[str, Any]:
    truth = r.rail_truth_frames > 0  # without rail truth only vehicles labelled are scored
    out: dict[str, Any] = {
        "slow_targets": r.slow_targets,
        "rail_returns": r.rail_returns if truth else None,
        "labelled": r.labelled,
        "fn": r.fn if truth else None,
        "fp": r.fp if truth else None,
        "vehicles_labelled": r.vehicles_labelled,
    }
    if listings:
        out |= {
            "fn_at": _pairs(r.fn_at),
            "fp_at": _pairs(r.fp_at),
            "vehicles_labelled_at": _pairs(r.vehicles_labelled_at),
        }
    return out


def _boxes_json(b: BoxScore, listings: bool) -> dict[str, Any]:
    out: dict[str, Any] = {
        "visible": b.visible,
        "found": b.found,
        "boxes": b.boxes,
        "true_boxes": b.true_boxes,
        "recall": _ratio(b.found, b.visible),
        "precision": _ratio(b.true_boxes, b.boxes),
    }
    if listings:
        out |= {"missed_at": _pairs(b.missed_at), "false_at": _pairs(b.false_at)}
    return out


def _mot_json(m: MotScore, listings: bool) -> dict[str, Any]:
    out: dict[str, Any] = {
        "truth": m.truth,
        "tracks": m.hypotheses,
        "matches": m.matches,
        "misses": m.misses,
        "false_positives": m.false_positives,
        "id_switches": m.id_switches,
        "mota": round(m.mota, 4) if m.truth else None,
        "motp": round(m.motp, 4) if m.matches else None,
        "idf1": round(m.idf1, 4) if m.truth + m.hypotheses else None,
    }
    if listings:
        out["id_switches_at"] = _pairs(m.switches_at)
    return out


def _timing_json(r: RecordingReport) -> dict[str, Any] | None:
    """VD, GRD, OBM and the reduction; a total's per recording with their mean."""
    if not r.guardrail_timing:
        return None
    rows = {
        name: {
            "vd_ms": round(g.vd_ms, 4),
            "grd_ms": round(g.grd_ms, 4),
            "obm_ms": round(g.obm_ms, 4),
            "reduction": round(g.reduction, 4),
        }
        for name, g in r.guardrail_timing
    }
    if len(rows) == 1:
        return next(iter(rows.values()))
    return {"recordings": rows, "mean_reduction": round(mean_reduction(r), 4)}


def mean_reduction(r: RecordingReport) -> float:
    """Paper 002's "mean of reductions" over the recordings of a report."""
    return sum(g.reduction for _, g in r.guardrail_timing) / len(r.guardrail_timing)


def figures_json(r: RecordingReport, listings: bool = True) -> dict[str, Any]:
    """Every figure of one report (module docstring)."""
    ms, pitch, t = r.motion_stereo, r.pitch, r.tracking
    return {
        "frames": r.frames,
        "warnings": list(r.warnings),
        "vehicles": {
            "frames": _frames_json(r.vehicles, listings),
            "events": _events_json(r.events),
        },
        "guardrails": {**_rails_json(r.guardrails, listings), "timing": _timing_json(r)},
        "pedestrians": {k: _boxes_json(b, listings) for k, b in r.pedestrians.items()},
        "motion_stereo": _mask_json(ms, listings),
        "pitch": {
            **_pitch_json(pitch),
            "calibration_rms_deg": _share(pitch.calibration_rms_deg),
        },
        "tracking": {
            "vehicles": {
                "frames": _frames_json(t.vehicles, listings),
                "events": _events_json(t.events),
                "mot": _mot_json(t.vehicle_mot, listings),
            },
            "pedestrians": {
                **_boxes_json(t.pedestrians, listings),
                "mot": _mot_json(t.pedestrian_mot, listings),
            },
            "guardrails": _rails_json(t.guardrails, listings),
        },
        **({} if r.baselines is None else {"baselines": _baselines_json(r, listings)}),
    }


def _mask_json(m: MaskScore, listings: bool) -> dict[str, Any]:
    return {
        "obstacles": m.obstacles,
        "obstacles_hit": m.obstacles_hit,
        "object_recall": _ratio(m.obstacles_hit, m.obstacles),
        "pixel_recall": _ratio(m.truth_marked_px, m.truth_px),
        "pixel_precision": _ratio(m.marked_on_objects_px, m.marked_px),
        **({"missed_at": _pairs(m.missed_at)} if listings else {}),
    }


def _pitch_json(p: PitchScore) -> dict[str, Any]:
    return {
        "frames": len(p.errors_deg),
        "rms_deg": _share(p.rms_deg),
        "max_deg": _share(p.max_deg),
    }


def _ms(t: Timing) -> float | None:
    return None if math.isnan(t.median_ms) else round(t.median_ms, 4)


def _baselines_json(r: RecordingReport, listings: bool) -> dict[str, Any]:
    b = r.baselines
    assert b is not None
    return {
        "pedestrians": {
            "hog": _boxes_json(b.hog, listings),
            "hog_ms": _ms(b.hog_time),
            "symmetry_ms": _ms(b.symmetry_time),
        },
        "pitch": {
            "hough": {**_pitch_json(b.hough), "no_vanishing_point": b.hough_missing},
            "hough_ms": _ms(b.hough_time),
            "pitch_ms": _ms(b.pitch_time),
        },
        "motion_stereo": {
            state: {
                "motion_stereo": _mask_json(getattr(b.motion_stereo, state), listings),
                "mog2": _mask_json(getattr(b.mog2, state), listings),
            }
            for state in ("moving", "still")
        }
        | {"motion_stereo_ms": _ms(b.motion_stereo_time), "mog2_ms": _ms(b.mog2_time)},
    }


def as_json(reports: Sequence[RecordingReport], total: RecordingReport) -> dict[str, Any]:
    return {
        "recordings": [{"name": r.name, **figures_json(r)} for r in reports],
        "total": figures_json(total, listings=False),
    }


# --- tables ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Table:
    title: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    notes: tuple[str, ...] = ()


def _pct(part: int, whole: int) -> str:
    return f"{part} ({part / whole:.0%})" if whole else str(part)


def _rp(b: BoxScore) -> str:
    recall = f"{b.recall:.0%}" if b.visible else "-"
    precision = f"{b.precision:.0%}" if b.boxes else "-"
    return f"{recall} / {precision}"


def _runs(frames: Sequence[int]) -> str:
    """'10-14, 20' from frame indices."""
    runs: list[str] = []
    seq = sorted(set(frames))
    start = prev = seq[0]
    for f in [*seq[1:], None]:
        if f is not None and f == prev + 1:
            prev = f
            continue
        runs.append(str(start) if start == prev else f"{start}-{prev}")
        if f is not None:
            start = prev = f
    return ", ".join(runs)


def _ranges(at: Sequence[tuple[int, int]]) -> str:
    """'3: 10-14, 20; 5: 7' from (frame, id) pairs: the frames of each id."""
    frames: dict[int, list[int]] = defaultdict(list)
    for frame, what in at:
        frames[what].append(frame)
    return "; ".join(f"{w}: {_runs(frames[w])}" for w in sorted(frames)) or "none"


def _frames(at: Sequence[tuple[int, int]]) -> str:
    return _runs([frame for frame, _ in at]) if at else "none"


def tables(
    reports: Sequence[RecordingReport], total: RecordingReport, listings: bool = True
) -> list[Table]:
    """The papers' tables; listings: also where each recording's errors are."""
    rows = [*reports, total] if len(reports) > 1 else list(reports)
    out = [
        Table(
            "Vehicles, frame by frame (paper 001, section III)",
            (
                "recording",
                "frames",
                "framed",
                "RD",
                "FN",
                "RFN",
                "FP",
                "NVO",
                "RD box IoU median",
                f"RD box IoU >= {IOU_GOOD:g}",
                "distance error m: median / p90 of size",
                "RD / (RD + FN): " + " / ".join(VEHICLE_CLASSES),
                f"RD / (RD + FN) within {SUPPLIED_NEAR_M:g} m",
            ),
            tuple(
                (
                    r.name,
                    str(r.frames),
                    str(r.vehicles.framed),
                    _pct(r.vehicles.rd, r.vehicles.framed),
                    _pct(r.vehicles.fn, r.vehicles.framed),
                    _pct(r.vehicles.rfn, r.vehicles.framed),
                    str(r.vehicles.fp),
                    str(r.vehicles.nvo),
                    _fixed(r.vehicles.rd_iou_median),
                    _percent(r.vehicles.rd_iou_share(IOU_GOOD)),
                    _distance_errors(r.vehicles),
                    _by_class(r.vehicles),
                    _fixed(r.vehicles.supplied_refined_share_near),
                )
                for r in rows
            ),
        ),
        Table(
            "Events: vehicles framed in more than 10 frames (paper 001, table I)",
            ("SEQUENCE", "EVENTS", "RADAR MISS", "NOT REFINED", "REFINED BY VISION"),
            tuple(
                (
                    r.name,
                    str(r.events.events),
                    _pct(r.events.radar_miss, r.events.events),
                    _pct(r.events.not_refined, r.events.events),
                    _pct(r.events.refined, r.events.events),
                )
                for r in rows
            ),
            (
                f"refined of the events radar supplied to vision: "
                f"{_pct(total.events.refined, total.events.events - total.events.radar_miss)}",
            ),
        ),
        Table(
            "Guard rails (paper 002): slow radar targets (-: no guard-rail truth)",
            ("recording", "slow", "rail returns", "labelled", "FN", "FP", "vehicles labelled"),
            tuple(
                (
                    r.name,
                    str(r.guardrails.slow_targets),
                    _if_rail_truth(r.guardrails, r.guardrails.rail_returns),
                    str(r.guardrails.labelled),
                    _if_rail_truth(r.guardrails, r.guardrails.fn),
                    _if_rail_truth(r.guardrails, r.guardrails.fp),
                    str(r.guardrails.vehicles_labelled),
                )
                for r in rows
            ),
        ),
        *_timing_tables(total),
        Table(
            "Pedestrians (paper 000), recall / precision",
            ("recording", "visible", *(PEDESTRIAN_TITLES[k] for k in PEDESTRIAN_STAGES), "tracked"),
            tuple(
                (
                    r.name,
                    str(r.pedestrians["symmetry"].visible),
                    *(_rp(r.pedestrians[k]) for k in PEDESTRIAN_STAGES),
                    _rp(r.tracking.pedestrians),
                )
                for r in rows
            ),
        ),
        Table(
            "Motion stereo and pitch",
            (
                "recording",
                "obstacles found",
                "pixel recall",
                "pixel precision",
                "pitch RMS deg",
                "pitch max deg",
                "calibration RMS deg",
            ),
            tuple(
                (
                    r.name,
                    _pct(r.motion_stereo.obstacles_hit, r.motion_stereo.obstacles),
                    f"{r.motion_stereo.pixel_recall:.0%}",
                    f"{r.motion_stereo.pixel_precision:.0%}",
                    _fixed(r.pitch.rms_deg),
                    _fixed(r.pitch.max_deg),
                    _fixed(r.pitch.calibration_rms_deg),
                )
                for r in rows
            ),
        ),
        Table(
            "Tracking (beyond the papers)",
            (
                "recording",
                "vehicles RD / FN / RFN",
                "events refined",
                "radar-seen vehicles MOTA / MOTP / IDF1",
                "id switches",
                "pedestrians MOTA / MOTP / IDF1",
                "id switches",
            ),
            tuple(
                (
                    r.name,
                    _counts(r.tracking.vehicles),
                    _pct(r.tracking.events.refined, r.tracking.events.events),
                    _mot(r.tracking.vehicle_mot),
                    str(r.tracking.vehicle_mot.id_switches),
                    _mot(r.tracking.pedestrian_mot),
                    str(r.tracking.pedestrian_mot.id_switches),
                )
                for r in rows
            ),
        ),
    ]
    out += _baseline_tables(rows)
    for r in reports if listings else ():
        out.append(
            Table(
                f"Where the errors are in {r.name} (frame indices per truth id or radar target)",
                ("what", "where"),
                tuple(
                    (e.title, _ranges(e.at) if e.ids else _frames(e.at)) for e in error_listings(r)
                ),
            )
        )
    return out


def _timing_tables(total: RecordingReport) -> list[Table]:
    if not total.guardrail_timing:
        return []
    paper = PAPER_002_MS
    rows = [
        (name, f"{g.vd_ms:.3f}", f"{g.grd_ms:.3f}", f"{g.obm_ms:.3f}", f"{g.reduction:.0%}")
        for name, g in total.guardrail_timing
    ]
    rows.append(
        (
            "paper 002",
            f"{paper['vd']:.1f}",
            f"{paper['grd']:.1f}",
            f"{paper['obm']:.1f}",
            f"{1 - paper['obm'] / paper['vd']:.0%}",
        )
    )
    return [
        Table(
            TIMING_TITLE,
            ("recording", "VD", "GRD", "OBM", "reduction"),
            tuple(rows),
            (f"mean of reductions: {mean_reduction(total):.0%} (paper 002: 20 %)",),
        )
    ]


def _baseline_tables(rows: Sequence[RecordingReport]) -> list[Table]:
    pairs = [(r.name, r.baselines) for r in rows if r.baselines is not None]
    if not pairs:
        return []
    by_name = {r.name: r for r in rows}
    return [
        Table(
            "Baselines: pedestrians beside OpenCV's HOG people detector, recall / precision",
            ("recording", "visible", "symmetry + both filters (paper 000)", "HOG"),
            tuple(
                (
                    name,
                    str(b.hog.visible),
                    _rp(by_name[name].pedestrians["vehicles"]),
                    _rp(b.hog),
                )
                for name, b in pairs
            ),
        ),
        Table(
            "Baselines: pitch beside a Hough-line vanishing point, error RMS / max deg",
            ("recording", "edge clusters (paper 000)", "Hough", "frames without a Hough VP"),
            tuple(
                (
                    name,
                    _rms_max(by_name[name].pitch),
                    _rms_max(b.hough),
                    _pct(b.hough_missing, len(b.hough.errors_deg)),
                )
                for name, b in pairs
            ),
            ("without a vanishing point the Hough baseline keeps the calibrated pitch",),
        ),
        Table(
            "Baselines: obstacle mask beside OpenCV's MOG2, "
            "object recall / pixel recall / pixel precision",
            (
                "recording",
                "moving: motion stereo (paper 000)",
                "moving: MOG2",
                "still: background subtraction",
                "still: MOG2",
            ),
            tuple(
                (
                    name,
                    _mask(b.motion_stereo.moving),
                    _mask(b.mog2.moving),
                    _mask(b.motion_stereo.still),
                    _mask(b.mog2.still),
                )
                for name, b in pairs
            ),
            (
                "moving: the car drives and MOG2 cannot undo its motion; still: it stands "
                "and only moving objects count",
            ),
        ),
        Table(
            BASELINE_TIMING_TITLE,
            ("recording", "symmetry / HOG", "pitch / Hough", "motion stereo / MOG2"),
            tuple(
                (
                    name,
                    f"{b.symmetry_time.median_ms:.2f} / {b.hog_time.median_ms:.2f}",
                    f"{b.pitch_time.median_ms:.2f} / {b.hough_time.median_ms:.2f}",
                    f"{b.motion_stereo_time.median_ms:.2f} / {b.mog2_time.median_ms:.2f}",
                )
                for name, b in pairs
            ),
        ),
    ]


def _rms_max(p: PitchScore) -> str:
    return f"{p.rms_deg:.2f} / {p.max_deg:.2f}" if p.errors_deg else "-"


def _mask(m: MaskScore) -> str:
    if not m.obstacles and not m.marked_px:
        return "-"
    recall = f"{m.object_recall:.0%} / {m.pixel_recall:.0%}" if m.obstacles else "- / -"
    precision = f"{m.pixel_precision:.0%}" if m.marked_px else "-"
    return f"{recall} / {precision}"


def _counts(s: FrameStats) -> str:
    return f"{s.rd} / {s.fn} / {s.rfn}"


def _mot(m: MotScore) -> str:
    if not m.truth:
        return "-"
    return f"{m.mota:.2f} / {m.motp:.2f} / {m.idf1:.2f}"


def _refined_of_supplied(r: RecordingReport) -> str:
    v = r.vehicles
    return f"{v.rd / (v.rd + v.fn):.2f}" if v.rd + v.fn else "-"


def _rfn_of_framed(r: RecordingReport) -> str:
    v = r.vehicles
    framed = v.rd + v.fn + v.rfn
    return f"{v.rfn / framed:.2f}" if framed else "-"


def _fp_per_frame(r: RecordingReport) -> str:
    return f"{r.vehicles.fp / r.frames:.2f}" if r.frames else "-"


def _events_refined(r: RecordingReport) -> str:
    return f"{r.events.refined_share:.2f}" if r.events.events else "-"


def _rail_errors(r: RecordingReport) -> str:
    g = r.guardrails
    return f"{_if_rail_truth(g, g.fn)} / {_if_rail_truth(g, g.fp)}"


def _vehicle_mota(r: RecordingReport) -> str:
    m = r.tracking.vehicle_mot
    return f"{m.mota:.2f}" if m.truth else "-"


# The headline figures `evaluate --compare` sets side by side: (name, figure of a report).
HEADLINE_FIGURES: tuple[tuple[str, Callable[[RecordingReport], str]], ...] = (
    ("vehicles RD / (RD + FN)", _refined_of_supplied),
    (
        f"vehicles RD / (RD + FN) within {SUPPLIED_NEAR_M:g} m",
        lambda r: _fixed(r.vehicles.supplied_refined_share_near),
    ),
    ("vehicles RFN / framed", _rfn_of_framed),
    ("vehicle FP per frame", _fp_per_frame),
    ("vehicles RD box IoU median", lambda r: _fixed(r.vehicles.rd_iou_median)),
    ("events refined", _events_refined),
    ("vehicles labelled guard rail", lambda r: str(r.guardrails.vehicles_labelled)),
    ("guard-rail FN / FP", _rail_errors),
    ("pedestrians recall / precision", lambda r: _rp(r.pedestrians[FINAL_PEDESTRIAN_STAGE])),
    ("pitch RMS deg", lambda r: _fixed(r.pitch.rms_deg)),
    ("tracked radar-seen vehicles MOTA", _vehicle_mota),
)


def comparison(
    names: tuple[str, str],
    reports: tuple[Sequence[RecordingReport], Sequence[RecordingReport]],
) -> Table:
    """The headline figures of the same recordings under two parameter sets, one row per
    recording (and the total) and figure; `names` head the two columns."""
    a, b = ([*rs, total(rs)] for rs in reports)
    rows = tuple(
        (ra.name, figure, value(ra), value(rb))
        for ra, rb in zip(a, b, strict=True)
        for figure, value in HEADLINE_FIGURES
    )
    return Table(f"Compared: {names[0]} against {names[1]}", ("recording", "figure", *names), rows)


def format_text(items: Sequence[Table]) -> str:
    blocks = []
    for t in items:
        widths = [max(len(row[k]) for row in (t.header, *t.rows)) for k in range(len(t.header))]
        lines = [t.title]
        for row in (t.header, *t.rows):
            lines.append("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)))
        lines += list(t.notes)
        blocks.append("\n".join(line.rstrip() for line in lines))
    return "\n\n".join(blocks) + "\n"


def format_markdown(items: Sequence[Table]) -> str:
    blocks = []
    for t in items:
        lines = [f"**{t.title}**", "", "| " + " | ".join(t.header) + " |"]
        lines.append("| " + " | ".join("---" for _ in t.header) + " |")
        lines += ["| " + " | ".join(c.replace("|", "/") for c in row) + " |" for row in t.rows]
        lines += ["", *t.notes] if t.notes else []
        blocks.append("\n".join(lines))
    return "\n\n".join(blocks) + "\n"


def _flatten(prefix: str, value: Any, out: list[tuple[str, Any]]) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else k, v, out)
    elif not isinstance(value, list):
        out.append((prefix, value))


def format_csv(reports: Sequence[RecordingReport], total: RecordingReport) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(("recording", "figure", "value"))
    for r in [*reports, total]:
        flat: list[tuple[str, Any]] = []
        _flatten("", figures_json(r, listings=False), flat)
        for name, value in flat:
            writer.writerow((r.name, name, "" if value is None else value))
    return buffer.getvalue()
