"""Drive: random access to the frames of a recording folder, lazy and cached.

    with Drive("recordings/highway") as drive:
        frame = drive.frame(10)      # FrameInput: image, radar targets, speed, yaw rate
        truth = drive.truth(10)      # FrameTruth or None

Opening validates the whole recording (manifest, calibration, topics and their types, CAN
signals, the first image) and decodes radar and CAN completely (they are small); images are
decoded on demand and the last few are kept.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from pathlib import Path
from types import TracebackType

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.bag import RADAR_TYPES, BagReader, CameraStream
from core.io.calibration import Calibration, load_calibration
from core.io.canlog import VehicleSignals, read_vehicle_signals
from core.io.errors import RecordingError
from core.io.frame import FrameInput, RadarTarget
from core.io.groundtruth import FrameTruth, read_groundtruth
from core.io.manifest import Manifest, RadarCanSource, load_manifest
from core.io.radarscans import RadarScans

DEFAULT_CACHE_FRAMES = 16


class Drive:
    """An open recording. Thread-safe: frame() may be called from any thread.

    times_ns: (N,) int64 camera stamps on the recording clock (camera offset applied).
    Without a CAN section in the manifest, speed_mps and yaw_rate_radps of every frame are NaN.
    """

    def __init__(self, path: Path | str, cache_frames: int = DEFAULT_CACHE_FRAMES) -> None:
        self.path = Path(path)
        self.manifest: Manifest = load_manifest(self.path)
        m = self.manifest
        self.name = m.name
        self.calibration: Calibration = load_calibration(m.resolve(m.calibration))
        self._lock = threading.Lock()
        self._cache: OrderedDict[int, FrameInput] = OrderedDict()
        self._cache_frames = max(1, cache_frames)
        self._bags: dict[Path, BagReader] = {}
        try:
            self._camera = CameraStream(
                self._bag(m.camera.bag), m.camera.topic, m.time_offsets.camera_ns
            )
            self.times_ns: npt.NDArray[np.int64] = self._camera.times_ns
            self.radar: RadarScans | None = None
            if isinstance(m.radar, RadarCanSource):
                raise RecordingError(f"{self.path}: radar over CAN is not read yet")
            if m.radar is not None:
                bag = self._bag(m.radar.bag)
                conn = bag.connection(m.radar.topic, RADAR_TYPES, "radar")
                self.radar = bag.read_radar(conn, m.time_offsets.radar_ns)
            self.vehicle_signals = VehicleSignals.empty()
            if m.can is not None and m.can.bus.log is not None:
                self.vehicle_signals = read_vehicle_signals(
                    m.resolve(m.can.bus.log),
                    [m.resolve(d) for d in m.can.bus.dbc],
                    m.can.speed,
                    m.can.yaw_rate,
                    channel=m.can.bus.channel,
                    offset_ns=m.time_offsets.can_ns,
                )
            self._truth: dict[int, FrameTruth] = {}
            if m.groundtruth is not None:
                self._truth = {f.index: f for f in read_groundtruth(m.resolve(m.groundtruth))}
            self.frame(0)  # fail on open, not later, when images do not match the calibration
        except BaseException:
            self.close()
            raise

    def _bag(self, relative: str) -> BagReader:
        path = self.manifest.resolve(relative)
        if path not in self._bags:
            self._bags[path] = BagReader(path)
        return self._bags[path]

    # --- lifetime -----------------------------------------------------------------------
    def close(self) -> None:
        with self._lock:
            for bag in self._bags.values():
                bag.close()
            self._bags.clear()
            self._cache.clear()

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
        return self.manifest.groundtruth is not None

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

    def radar_at(self, t_ns: int) -> tuple[tuple[RadarTarget, ...], int | None]:
        """Targets of the scan nearest `t_ns` within half the median radar period, its stamp.

        ((), None) when no scan is that near.
        """
        scans = self.radar
        if scans is None or len(scans.t_ns) == 0:
            return (), None
        k = int(np.searchsorted(scans.t_ns, t_ns))
        near = [j for j in (k - 1, k) if 0 <= j < len(scans.t_ns)]
        j = min(near, key=lambda j: abs(int(scans.t_ns[j]) - t_ns))
        if abs(int(scans.t_ns[j]) - t_ns) > scans.median_period_ns / 2:
            return (), None
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

    def frame(self, i: int) -> FrameInput:
        """Frame `i`: image, the nearest radar scan, speed and yaw rate at the camera stamp."""
        i = self._check_index(i)
        with self._lock:
            if i in self._cache:
                self._cache.move_to_end(i)
                return self._cache[i]
            if not self._bags:
                raise RecordingError(f"{self.path}: the drive is closed")
            image = self._camera.image(i)
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
            speed_mps=float(self.vehicle_signals.speed_at(t_ns)),
            yaw_rate_radps=float(self.vehicle_signals.yaw_rate_at(t_ns)),
        )
        with self._lock:
            self._cache[i] = frame
            while len(self._cache) > self._cache_frames:
                self._cache.popitem(last=False)
        return frame
