"""RecordingWriter: writes a recording folder (the synthetic generator's output format).

    with RecordingWriter(out_dir, name="highway", calibration=cal) as w:
        w.add_image(t_ns, image)                 # (H, W) uint8 -> PNG CompressedImage
        w.add_radar_scan(t_ns, targets)          # -> radar_msgs/RadarScan
        w.add_vehicle_state(t_ns, speed_mps, yaw_rate_radps)   # -> BLF frames via vehicle.dbc
        w.set_groundtruth(frames)

The same calls give byte-identical files: no wall-clock time is written anywhere.
`write_vehicle_can` writes speed and yaw rate the same way for importers that have them
from elsewhere (the radar, core.radar_ego).

Notes:
    python-can's BLFWriter puts the first frame's time in the file header and stores frame
    times relative to it, but writes (and reads back) a zero header date for times before
    1990; a recording clock starting near 0 would then come back shifted. The writer fixes
    the BLF start time to 0, so frame times are stored as absolute recording-clock times.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from types import TracebackType
from typing import Any, Literal

import can
import cv2
import numpy as np
import numpy.typing as npt
from rosbags.typesys.store import Typestore

from core.io import radar_msgs
from core.io.calibration import Calibration, save_calibration
from core.io.canlog import SPEED_UNITS_TO_MPS, YAW_RATE_UNITS_TO_RADPS, SignalMapping, load_dbc
from core.io.errors import RecordingError
from core.io.frame import RadarTarget
from core.io.groundtruth import FrameTruth, write_groundtruth
from core.io.index import load_index
from core.io.manifest import (
    MANIFEST_NAME,
    BagStream,
    CanBus,
    CanSource,
    Manifest,
    load_manifest,
    save_manifest,
)
from core.io.split_bag import SplitBagWriter

CAMERA_TOPIC = "/camera/image/compressed"
RADAR_TOPIC = "/radar/scan"
CAMERA_FRAME_ID = "camera"
RADAR_FRAME_ID = "radar"
PNG_FORMAT = "mono8; png compressed mono8"
# Chosen for decoding, which every reader of a drive pays on every frame: no row filter
# and zlib level 6. On the bundled drives' frames libpng decodes these in 1.0 ms against
# 1.9 ms for its adaptive filters (mostly Paeth) with Huffman-only coding, the choice until
# 2026-11, for 14 % more bytes; a real 960x540 dashcam frame decodes in 1.9 ms against
# 3.6 ms, for 26 % more. Encoding takes about 14 ms a synthetic frame. Without filters the
# frames also take core.io.png's fast path (libdeflate), which is faster still.
PNG_PARAMS = [
    cv2.IMWRITE_PNG_COMPRESSION,
    6,
    cv2.IMWRITE_PNG_FILTER,
    cv2.IMWRITE_PNG_FILTER_NONE,
]
BAG_DIR = "bag"
CAN_LOG = "vehicle.blf"
DBC_NAME = "vehicle.dbc"
CALIBRATION_NAME = "calibration.yaml"
GROUNDTRUTH_NAME = "groundtruth.json"
BAG_VERSION: Literal[9] = 9
# Bag files are split past this size (rosbag2's max_bagfile_size), keeping each file small.
MAX_BAG_FILE_BYTES = 6 * 2**20

SPEED_SIGNAL = SignalMapping("SPEED", "SPEED", "km/h", SPEED_UNITS_TO_MPS["km/h"])
YAW_RATE_SIGNAL = SignalMapping("KINEMATICS", "YAW_RATE", "deg/s", YAW_RATE_UNITS_TO_RADPS["deg/s"])
SPEED_COUNTER = "ENCODER"
COUNTER_MODULO = 256


def ros_header(store: Typestore, t_ns: int, frame_id: str) -> Any:
    """A std_msgs/Header stamped `t_ns` (ns, >= 0)."""
    sec, nanosec = divmod(int(t_ns), 1_000_000_000)
    stamp = store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
    return store.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)


def png_image_message(store: Typestore, t_ns: int, image: npt.NDArray[np.uint8]) -> bytes:
    """A serialised (CDR) sensor_msgs/CompressedImage holding `image` as PNG, stamped `t_ns`.

    image: (H, W) uint8 grey. Header stamp = `t_ns`, which the bag also takes as log time.
    """
    if image.dtype != np.uint8 or image.ndim != 2:
        raise ValueError(f"image: expected (H, W) uint8 grey, got {image.dtype} {image.shape}")
    ok, png = cv2.imencode(".png", image, PNG_PARAMS)
    if not ok:
        raise RecordingError(f"image at t={t_ns} ns: cannot be encoded as PNG")
    msg = store.types[radar_msgs.COMPRESSED_IMAGE](
        header=ros_header(store, t_ns, CAMERA_FRAME_ID),
        format=PNG_FORMAT,
        data=np.asarray(png, dtype=np.uint8).ravel(),
    )
    return bytes(store.serialize_cdr(msg, radar_msgs.COMPRESSED_IMAGE))


def vehicle_dbc_path() -> Path:
    """The synthetic car's DBC shipped with the package."""
    return Path(str(resources.files("core.io") / "data" / DBC_NAME))


@dataclass(frozen=True)
class VehicleState:
    """One CAN sample: t_ns on the recording clock, speed_mps forward, yaw_rate_radps
    positive turning left; ValueError unless speed and yaw rate are finite."""

    t_ns: int
    speed_mps: float
    yaw_rate_radps: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.speed_mps) and math.isfinite(self.yaw_rate_radps)):
            raise ValueError(
                "speed_mps, yaw_rate_radps: expected finite numbers, "
                f"got {self.speed_mps}, {self.yaw_rate_radps}"
            )


def write_vehicle_can(
    folder: Path, samples: Sequence[VehicleState], yaw_rate_bias: str = "none"
) -> CanSource:
    """Write `samples` as the synthetic car's CAN bus into `folder`; the manifest's section.

    Writes DBC_NAME (a copy of vehicle_dbc_path()) and CAN_LOG, a BLF log with one SPEED
    frame (its ENCODER counting the samples in the order given) and one KINEMATICS frame per
    sample, in time order, quantised as the DBC says; values beyond the DBC's range are
    clipped to it. Returns the CanSource that reads them back (SPEED_SIGNAL,
    YAW_RATE_SIGNAL, `yaw_rate_bias`).
    """
    shutil.copyfile(vehicle_dbc_path(), folder / DBC_NAME)
    db = load_dbc([folder / DBC_NAME])
    speed_msg = db.get_message_by_name(SPEED_SIGNAL.message)
    yaw_msg = db.get_message_by_name(YAW_RATE_SIGNAL.message)
    speed_sig = speed_msg.get_signal_by_name(SPEED_SIGNAL.signal)
    yaw_sig = yaw_msg.get_signal_by_name(YAW_RATE_SIGNAL.signal)
    frames: list[tuple[int, int, bytes]] = []
    for k, s in enumerate(samples):
        kmh = float(np.clip(s.speed_mps / SPEED_SIGNAL.to_si, speed_sig.minimum, speed_sig.maximum))
        degs = float(
            np.clip(s.yaw_rate_radps / YAW_RATE_SIGNAL.to_si, yaw_sig.minimum, yaw_sig.maximum)
        )
        counter = k % COUNTER_MODULO
        speed_data = speed_msg.encode({SPEED_SIGNAL.signal: kmh, SPEED_COUNTER: counter})
        yaw_data = yaw_msg.encode({YAW_RATE_SIGNAL.signal: degs})
        frames.append((int(s.t_ns), speed_msg.frame_id, bytes(speed_data)))
        frames.append((int(s.t_ns), yaw_msg.frame_id, bytes(yaw_data)))
    writer = can.BLFWriter(folder / CAN_LOG)
    writer.start_timestamp = 0.0  # see the module Notes
    for t_ns, frame_id, data in sorted(frames, key=lambda f: f[0]):
        writer.on_message_received(
            can.Message(
                timestamp=t_ns / 1e9,
                arbitration_id=frame_id,
                data=data,
                is_extended_id=False,
                channel=0,
            )
        )
    writer.stop()
    return CanSource(
        CanBus(dbc=(DBC_NAME,), log=CAN_LOG),
        SPEED_SIGNAL,
        YAW_RATE_SIGNAL,
        yaw_rate_bias=yaw_rate_bias,
    )


class RecordingWriter:
    """Writes one recording folder; a context manager (the files are complete after close)."""

    def __init__(
        self,
        out_dir: Path | str,
        *,
        name: str,
        calibration: Calibration,
        description: str = "",
        generator: Mapping[str, Any] | None = None,
        yaw_rate_bias: str = "none",
    ) -> None:
        self.out_dir = Path(out_dir)
        self.yaw_rate_bias = yaw_rate_bias
        if self.out_dir.exists() and (not self.out_dir.is_dir() or any(self.out_dir.iterdir())):
            raise RecordingError(
                f"{self.out_dir}: expected a new or empty folder for the recording, it is not empty"
            )
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self.name = name
        self.description = description
        self.generator = dict(generator or {})
        self.calibration = calibration
        self._truth: list[FrameTruth] | None = None
        self._vehicle: list[VehicleState] = []
        self._closed = False

        store = radar_msgs.typestore()
        self._store = store
        self._bag = SplitBagWriter(
            self.out_dir / BAG_DIR,
            {CAMERA_TOPIC: radar_msgs.COMPRESSED_IMAGE, RADAR_TOPIC: radar_msgs.RADAR_SCAN},
            store,
            MAX_BAG_FILE_BYTES,
            version=BAG_VERSION,
        )

    # --- context manager ----------------------------------------------------------------
    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    # --- messages -----------------------------------------------------------------------
    def add_image(self, t_ns: int, image: npt.NDArray[np.uint8]) -> None:
        """Add a camera frame: (H, W) uint8 grey, the calibration's size; stored as PNG."""
        i = self.calibration.camera.intrinsics
        if image.dtype != np.uint8 or image.shape != (i.height_px, i.width_px):
            raise ValueError(
                f"image: expected ({i.height_px}, {i.width_px}) uint8 grey as the calibration "
                f"says, got {image.dtype} {image.shape}"
            )
        self._bag.write(CAMERA_TOPIC, int(t_ns), png_image_message(self._store, t_ns, image))

    def add_radar_scan(self, t_ns: int, targets: Sequence[RadarTarget]) -> None:
        """Add a radar scan: range, azimuth, range rate and amplitude of each target (float32).

        x_m, y_m and track_id are not stored: the reader derives x/y from the radar mount.
        """
        ret_cls = self._store.types[radar_msgs.RADAR_RETURN]
        f32 = np.float32
        returns = [
            ret_cls(
                range=f32(t.range_m),
                azimuth=f32(t.azimuth_rad),
                elevation=f32(0.0),
                doppler_velocity=f32(t.range_rate_mps),
                amplitude=f32(t.amplitude),
            )
            for t in targets
        ]
        msg = self._store.types[radar_msgs.RADAR_SCAN](
            header=ros_header(self._store, t_ns, RADAR_FRAME_ID), returns=returns
        )
        self._bag.write(
            RADAR_TOPIC, int(t_ns), self._store.serialize_cdr(msg, radar_msgs.RADAR_SCAN)
        )

    def add_vehicle_state(self, t_ns: int, speed_mps: float, yaw_rate_radps: float) -> None:
        """Add one SPEED and one KINEMATICS CAN frame at `t_ns` (see write_vehicle_can)."""
        self._vehicle.append(VehicleState(int(t_ns), speed_mps, yaw_rate_radps))

    def set_groundtruth(self, frames: Sequence[FrameTruth]) -> None:
        """Ground truth per camera frame (written to groundtruth.json on close)."""
        self._truth = list(frames)

    # --- finish -------------------------------------------------------------------------
    def close(self) -> None:
        """Finish the bag and write the CAN log, calibration, ground truth and manifest."""
        if self._closed:
            return
        self._closed = True
        self._bag.close()
        can_source = write_vehicle_can(self.out_dir, self._vehicle, self.yaw_rate_bias)
        save_calibration(self.calibration, self.out_dir / CALIBRATION_NAME)
        if self._truth is not None:
            write_groundtruth(self._truth, self.out_dir / GROUNDTRUTH_NAME)
        manifest = Manifest(
            folder=self.out_dir,
            name=self.name,
            description=self.description,
            generator=self.generator,
            camera=BagStream(BAG_DIR, CAMERA_TOPIC),
            radar=BagStream(BAG_DIR, RADAR_TOPIC),
            can=can_source,
            calibration=CALIBRATION_NAME,
            groundtruth=GROUNDTRUTH_NAME if self._truth is not None else None,
        )
        save_manifest(manifest, self.out_dir / MANIFEST_NAME)
        try:  # index it now, so the first open is as quick as any (core/io/index.py)
            load_index(load_manifest(self.out_dir))
        except RecordingError:
            pass  # a recording that cannot be indexed says why when it is opened
