"""Drive: random access to the frames of a recording folder, lazy and cached.

    with Drive("recordings/highway") as drive:
        frame = drive.frame(10)      # FrameInput: image, radar targets, speed, yaw rate, ego
        truth = drive.truth(10)      # FrameTruth or None

Opening reads the manifest and calibration and the recording's index (camera stamps, radar
scans, CAN signals; see core.io.index, cached on disk after the first open), and decodes the
first image to check it against the calibration. Images are decoded on demand and kept in an
LRU cache bounded in bytes.

Time alignment, per camera frame at stamp t:
    radar: the scan nearest t within the manifest's max_radar_skew_ms (default half the
        radar's median scan period), else none (FrameInput.radar_t_ns is None);
    speed, yaw rate: linear between CAN samples at t (held past the ends); without CAN, the
        manifest's assumptions, else NaN;
    ego: motion since the previous frame, paper 000 eq. 3-5 chained over every CAN sample in
        between (core.ego.integrate); None for the first frame and without speed.
"""

from __future__ import annotations

import functools
import math
import threading
import time
from collections import OrderedDict
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.ego import EgoMotion, integrate, step
from core.io.bag import CAMERA_TYPES, BagReader, decode_image
from core.io.calibration import Calibration, load_calibration
from core.io.canlog import VehicleSignals
from core.io.errors import RecordingError
from core.io.frame import FrameInput, RadarTarget
from core.io.groundtruth import FrameTruth
from core.io.index import DriveIndex, load_index
from core.io.manifest import Manifest, load_manifest
from core.io.radarscans import RadarScans

DEFAULT_CACHE_BYTES = 64 * 2**20
NS_PER_MS = 1_000_000


class Drive:
    """An open recording. Thread-safe: frame() may be called from any thread.

    times_ns: (N,) int64 camera stamps on the recording clock (camera offset applied), in
    time order. warnings: what was skipped or repaired on reading, in plain words.
    open_s: seconds the open took; index_cached: whether the index came from the cache.
    """

    def __init__(
        self, path: Path | str, cache_bytes: int = DEFAULT_CACHE_BYTES, use_cache: bool = True
    ) -> None:
        started = time.perf_counter()
        self.path = Path(path)
        self.manifest: Manifest = load_manifest(self.path)
        m = self.manifest
        self.name = m.name
        self.calibration: Calibration = load_calibration(m.resolve(m.calibration))
        self._lock = threading.Lock()
        self._cache: OrderedDict[int, FrameInput] = OrderedDict()
        self._cache_bytes = max(0, cache_bytes)
        self._cached_bytes = 0
        self.index: DriveIndex
        self.index, self.index_cached = load_index(m, use_cache)
        self.times_ns: npt.NDArray[np.int64] = self.index.camera_t_ns
        self.radar: RadarScans | None = self.index.radar
        self.vehicle_signals: VehicleSignals = self.index.vehicle
        self.warnings: tuple[str, ...] = self.index.warnings
        self._bag: BagReader | None = BagReader(m.resolve(m.camera.bag))
        try:
            self._conn = self._bag.connection(m.camera.topic, CAMERA_TYPES, "camera")
            # here: core.annotation reads its files with core.io, which imports this module
            from core.annotation.truth import recording_truth

            named = None if m.groundtruth is None else m.resolve(m.groundtruth)
            self._truth: dict[int, FrameTruth]
            self._truth, self.truth_problem = recording_truth(
                self.path, named, self.calibration.camera, self.times_ns
            )
            self.frame(0)  # fail on open, not later, when images do not match the calibration
        except BaseException:
            self.close()
            raise
        self.open_s = time.perf_counter() - started

    # --- lifetime -----------------------------------------------------------------------
    def close(self) -> None:
        with self._lock:
            if self._bag is not None:
                self._bag.close()
                self._bag = None
            self._cache.clear()
            self._cached_bytes = 0

    def __enter__(self) -> Drive:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # --- facts --------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.times_ns)

    @property
    def camera(self) -> CameraModel:
        return self.calibration.camera

    @property
    def has_truth(self) -> bool:
        """The recording has ground truth for some frame: the generator's exact truth, or
        annotations with frames marked annotated (`core.annotation.truth`)."""
        return bool(self._truth)

    @property
    def notes(self) -> tuple[str, ...]:
        """What a viewer should know: the manifest's assumptions, then the reading warnings."""
        return self.manifest.assumptions.describe() + self.warnings

    @property
    def frame_rate_hz(self) -> float:
        """Camera frames per second from the median frame interval; 0.0 with one frame."""
        if len(self.times_ns) < 2:
            return 0.0
        return float(1e9 / np.median(np.diff(self.times_ns)))

    # --- frames -------------------------------------------------------------------------
    def _check_index(self, i: int) -> int:
        n = len(self)
        if not isinstance(i, (int, np.integer)) or not 0 <= i < n:
            raise IndexError(f"frame index: expected 0 <= i <= {n - 1}, got {i!r}")
        return int(i)

    def truth(self, i: int) -> FrameTruth | None:
        """Ground truth of frame `i`, None when the recording has none for it."""
        return self._truth.get(self._check_index(i))

    @functools.cached_property
    def max_radar_skew_ns(self) -> float:
        """The largest camera-radar time difference accepted for a frame's radar scan (the
        median over the drive's scans, computed once)."""
        if self.manifest.max_radar_skew_ms is not None:
            return self.manifest.max_radar_skew_ms * NS_PER_MS
        return self.radar.median_period_ns / 2 if self.radar is not None else 0.0

    def radar_scan_near(self, t_ns: int) -> int | None:
        """Index of the radar scan nearest `t_ns` within max_radar_skew_ns, None if none."""
        scans = self.radar
        if scans is None or len(scans.t_ns) == 0:
            return None
        k = int(np.searchsorted(scans.t_ns, t_ns))
        near = [j for j in (k - 1, k) if 0 <= j < len(scans.t_ns)]
        j = min(near, key=lambda j: abs(int(scans.t_ns[j]) - t_ns))
        return j if abs(int(scans.t_ns[j]) - t_ns) <= self.max_radar_skew_ns else None

    def radar_at(self, t_ns: int) -> tuple[tuple[RadarTarget, ...], int | None]:
        """Targets of the scan nearest `t_ns` (see radar_scan_near) and its stamp.

        ((), None) when no scan is that near.
        """
        j = self.radar_scan_near(t_ns)
        if j is None or self.radar is None:
            return (), None
        scans = self.radar
        mount = self.calibration.radar_mount
        rows = range(int(scans.start[j]), int(scans.start[j + 1]))
        targets = tuple(
            RadarTarget.from_polar(
                float(scans.range_m[r]),
                float(scans.azimuth_rad[r]),
                float(scans.range_rate_mps[r]),
                float(scans.amplitude[r]),
                mount.x_m,
                mount.y_m,
                mount.yaw_rad,
                track_id=None if scans.track_id[r] < 0 else int(scans.track_id[r]),
            )
            for r in rows
        )
        return targets, int(scans.t_ns[j])

    def speed_at(self, t_ns: int) -> float:
        """Speed (m/s) at `t_ns`: from CAN, else the manifest's assumption, else NaN."""
        if len(self.vehicle_signals.speed_t_ns):
            return float(self.vehicle_signals.speed_at(t_ns))
        assumed = self.manifest.assumptions.speed_mps
        return math.nan if assumed is None else assumed

    def yaw_rate_at(self, t_ns: int) -> float:
        """Yaw rate (rad/s, positive left) at `t_ns`: from CAN, else assumed, else NaN."""
        if len(self.vehicle_signals.yaw_rate_t_ns):
            return float(self.vehicle_signals.yaw_rate_at(t_ns))
        assumed = self.manifest.assumptions.yaw_rate_radps
        return math.nan if assumed is None else assumed

    def ego_between(self, t0_ns: int, t1_ns: int) -> EgoMotion | None:
        """The car's motion from t0_ns to t1_ns (see core.ego), None without speed or yaw rate."""
        v = self.vehicle_signals
        if len(v.speed_t_ns) and len(v.yaw_rate_t_ns):
            return integrate(
                t0_ns, t1_ns, v.speed_t_ns, v.speed_mps, v.yaw_rate_t_ns, v.yaw_rate_radps
            )
        speed, yaw_rate = self.speed_at(t0_ns), self.yaw_rate_at(t0_ns)
        if math.isnan(speed) or math.isnan(yaw_rate):
            return None
        return step(speed, yaw_rate, (t1_ns - t0_ns) / 1e9)

    def _image(self, i: int) -> npt.NDArray[np.uint8]:
        """Decode frame `i`'s image (the caller holds the lock)."""
        if self._bag is None:
            raise RecordingError(f"{self.path}: the drive is closed")
        t = int(self.index.camera_log_ns[i])
        msg: Any = self._bag.read_at(self._conn, t, int(self.index.camera_occurrence[i]))
        where = f"{self._bag.path}: {self._conn.topic} at {t / 1e9:.9f} s (frame {i})"
        size = self.camera.intrinsics
        return decode_image(
            msg,
            self._conn.msgtype,
            where,
            self.manifest.camera.mono16_bits,
            (size.width_px, size.height_px),
        )

    def frame(self, i: int) -> FrameInput:
        """Frame `i`: image, the nearest radar scan, speed, yaw rate and ego motion."""
        i = self._check_index(i)
        with self._lock:
            if i in self._cache:
                self._cache.move_to_end(i)
                return self._cache[i]
            image = self._image(i)
        size = self.camera.intrinsics
        if image.shape != (size.height_px, size.width_px):
            raise RecordingError(
                f"{self.path}: frame {i}: image is {image.shape[1]}x{image.shape[0]}, "
                f"calibration says {size.width_px}x{size.height_px}"
            )
        t_ns = int(self.times_ns[i])
        radar, radar_t_ns = self.radar_at(t_ns)
        frame = FrameInput(
            index=i,
            t_ns=t_ns,
            image=image,
            radar=radar,
            radar_t_ns=radar_t_ns,
            speed_mps=self.speed_at(t_ns),
            yaw_rate_radps=self.yaw_rate_at(t_ns),
            ego=self.ego_between(int(self.times_ns[i - 1]), t_ns) if i > 0 else None,
        )
        with self._lock:
            if i not in self._cache:
                self._cache[i] = frame
                self._cached_bytes += image.nbytes
            while self._cached_bytes > self._cache_bytes and len(self._cache) > 1:
                _, old = self._cache.popitem(last=False)
                self._cached_bytes -= old.image.nbytes
        return frame
