"""What a recording holds and how well its streams line up: `fusionscope info RECORDING`.

Per stream (camera, radar, CAN speed, CAN yaw rate): count, time span, median rate, gaps
(intervals longer than GAP_FACTOR times the median), and what was skipped on reading. Per
camera frame: the time to the nearest radar scan (the skew), summarised as median, 95th
percentile and maximum, and how many frames have no scan within the allowed skew.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.io.drive import Drive

GAP_FACTOR = 2.0
NS_PER_S = 1_000_000_000
NS_PER_MS = 1_000_000


@dataclass(frozen=True)
class StreamReport:
    """One stream's stamps: count, first and last (s), median period (ms), gaps."""

    name: str
    count: int
    first_s: float
    last_s: float
    median_period_ms: float
    gaps: int
    max_gap_ms: float

    @property
    def rate_hz(self) -> float:
        return 1000.0 / self.median_period_ms if self.median_period_ms > 0 else 0.0


@dataclass(frozen=True)
class SkewReport:
    """Camera frame to nearest radar scan, |t_radar - t_camera| in ms."""

    median_ms: float
    p95_ms: float
    max_ms: float
    allowed_ms: float
    frames_without_radar: int


@dataclass(frozen=True)
class DriveReport:
    name: str
    path: str
    frames: int
    open_s: float
    index_cached: bool
    index_build_s: float
    streams: tuple[StreamReport, ...]
    skew: SkewReport | None
    camera_skipped: int
    speed_range_mps: tuple[float, float] | None
    yaw_rate_bias_radps: float
    assumptions: tuple[str, ...]
    warnings: tuple[str, ...]


def stream_report(name: str, t_ns: npt.NDArray[np.int64]) -> StreamReport:
    """Count, span, median period and gaps of ascending stamps `t_ns`."""
    if len(t_ns) == 0:
        return StreamReport(name, 0, math.nan, math.nan, math.nan, 0, math.nan)
    dt = np.diff(t_ns)
    median = float(np.median(dt)) if len(dt) else math.nan
    gaps = dt[dt > GAP_FACTOR * median] if len(dt) else dt
    return StreamReport(
        name=name,
        count=len(t_ns),
        first_s=int(t_ns[0]) / NS_PER_S,
        last_s=int(t_ns[-1]) / NS_PER_S,
        median_period_ms=median / NS_PER_MS,
        gaps=len(gaps),
        max_gap_ms=float(gaps.max()) / NS_PER_MS if len(gaps) else 0.0,
    )


def skew_report(drive: Drive) -> SkewReport | None:
    """Camera-to-radar skew over every frame; None without radar scans."""
    scans = drive.radar
    if scans is None or len(scans.t_ns) == 0:
        return None
    t = drive.times_ns
    k = np.clip(np.searchsorted(scans.t_ns, t), 1, len(scans.t_ns) - 1)
    if len(scans.t_ns) == 1:
        skew = np.abs(scans.t_ns[0] - t)
    else:
        skew = np.minimum(np.abs(scans.t_ns[k - 1] - t), np.abs(scans.t_ns[k] - t))
    allowed = drive.max_radar_skew_ns
    return SkewReport(
        median_ms=float(np.median(skew)) / NS_PER_MS,
        p95_ms=float(np.percentile(skew, 95)) / NS_PER_MS,
        max_ms=float(skew.max()) / NS_PER_MS,
        allowed_ms=allowed / NS_PER_MS,
        frames_without_radar=int(np.count_nonzero(skew > allowed)),
    )


def drive_report(drive: Drive) -> DriveReport:
    """Everything `fusionscope info` prints about an open drive."""
    v = drive.vehicle_signals
    streams = [stream_report("camera", drive.times_ns)]
    if drive.radar is not None:
        streams.append(stream_report("radar", drive.radar.t_ns))
    if drive.manifest.can is not None:
        streams.append(stream_report("CAN speed", v.speed_t_ns))
        streams.append(stream_report("CAN yaw rate", v.yaw_rate_t_ns))
    return DriveReport(
        name=drive.name,
        path=str(drive.path),
        frames=len(drive),
        open_s=drive.open_s,
        index_cached=drive.index_cached,
        index_build_s=drive.index.build_s,
        streams=tuple(streams),
        skew=skew_report(drive),
        camera_skipped=drive.index.camera_skipped,
        speed_range_mps=(
            (float(v.speed_mps.min()), float(v.speed_mps.max())) if len(v.speed_mps) else None
        ),
        yaw_rate_bias_radps=v.yaw_rate_bias_radps,
        assumptions=drive.manifest.assumptions.describe(),
        warnings=drive.warnings,
    )


def format_report(r: DriveReport) -> str:
    """The report as plain text, one fact per line."""
    cache = "index from cache" if r.index_cached else f"index built in {r.index_build_s:.2f} s"
    lines = [
        f"recording  {r.name}  ({r.path})",
        f"frames     {r.frames}",
        f"opened in  {r.open_s:.3f} s ({cache})",
        "",
        f"{'stream':<14}{'count':>9}{'first s':>16}{'last s':>16}{'rate Hz':>9}"
        f"{'gaps':>6}{'max gap ms':>12}",
    ]
    for s in r.streams:
        lines.append(
            f"{s.name:<14}{s.count:>9}{s.first_s:>16.3f}{s.last_s:>16.3f}{s.rate_hz:>9.2f}"
            f"{s.gaps:>6}{s.max_gap_ms:>12.1f}"
        )
    lines.append("")
    lines.append(f"camera     {r.camera_skipped} frame(s) with outlier stamps skipped")
    if r.skew is not None:
        k = r.skew
        lines.append(
            f"skew       camera->radar median {k.median_ms:.1f} ms, p95 {k.p95_ms:.1f} ms, "
            f"max {k.max_ms:.1f} ms; {k.frames_without_radar} frame(s) without a scan within "
            f"{k.allowed_ms:.1f} ms"
        )
    else:
        lines.append("skew       no radar")
    if r.speed_range_mps is not None:
        lo, hi = r.speed_range_mps
        lines.append(f"speed      {lo:.2f} .. {hi:.2f} m/s")
    if r.yaw_rate_bias_radps:
        lines.append(
            f"yaw rate   bias {r.yaw_rate_bias_radps:.5f} rad/s "
            f"({math.degrees(r.yaw_rate_bias_radps):.3f} deg/s) subtracted"
        )
    lines += [f"assumed    {a}" for a in r.assumptions]
    lines += ["", f"warnings   {len(r.warnings)}"] + [f"  - {w}" for w in r.warnings]
    return "\n".join(lines)
