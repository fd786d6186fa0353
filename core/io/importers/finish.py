"""The finishing step every `fusionscope import` shares: the folder, its calibration and
manifest, the options every import takes and what it returns; and the camera frames' common
handling (grey, resized, written to the recording's bag).

The result is a folder `core.io.Drive` and the inspector open (layout in core/io/manifest.py),
self-contained: the CAN log, the DBC files and the bag are copied into it. The folder is
written beside OUT_DIR under a temporary name and renamed at the end, so an error leaves
nothing behind; OUT_DIR must be new or empty.

Where nothing records the speed, `Assumptions` (a constant speed and yaw rate) go into the
manifest, or `--ego-from-radar` estimates the speed from the recording's own radar scans
(core.radar_ego) and writes it as CAN frames (`write_ego_from_radar`); without either,
speed is NaN and the engine's motion stereo cannot work.
"""

from __future__ import annotations

import math
import os
import shutil
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from core.io import radar_msgs
from core.io.calibration import Calibration, save_calibration
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.image_header import MAX_IMAGE_PIXELS, file_image_size_px
from core.io.importers.calibration_spec import BuiltCalibration
from core.io.importers.can_mapping import PreparedCan
from core.io.index import build_index
from core.io.manifest import (
    MANIFEST_NAME,
    Assumptions,
    BagStream,
    Manifest,
    RadarCanSource,
    save_manifest,
)
from core.io.split_bag import SplitBagWriter
from core.io.writer import (
    BAG_DIR,
    CALIBRATION_NAME,
    CAMERA_TOPIC,
    CAN_LOG,
    DBC_NAME,
    MAX_BAG_FILE_BYTES,
    VehicleState,
    write_vehicle_can,
)
from core.radar_ego import RadarEgoParams, speeds_from_scans

GreyImage = npt.NDArray[np.uint8]
Progress = Callable[[int, int], None]

DEFAULT_WIDTH_PX = 640  # paper 001: the engine works on 640-pixel-wide images
NS_PER_S = 1_000_000_000


@dataclass(frozen=True)
class ImportOptions:
    """What every import takes besides its source.

    name: the recording's name (None: the source file's stem); assumptions: constants where
    nothing records the speed or yaw rate; max_radar_skew_ms: how far (ms) a radar scan may
    lie from a camera frame and still be paired with it (None: the Drive's default);
    ego_from_radar: the speed estimated from the recording's radar (write_ego_from_radar),
    for recordings that record none.
    """

    name: str | None = None
    assumptions: Assumptions = field(default_factory=Assumptions)
    max_radar_skew_ms: float | None = None
    ego_from_radar: bool = False

    def __post_init__(self) -> None:
        a = self.assumptions
        if self.ego_from_radar and a != Assumptions():
            raise ValueError(
                "--ego-from-radar: not with --assume-speed-mps or --assume-yaw-rate-radps; it "
                "writes the speed it estimates and a yaw rate of 0 (give one or the other)"
            )
        for flag, value in (
            ("--assume-speed-mps", a.speed_mps),
            ("--assume-yaw-rate-radps", a.yaw_rate_radps),
        ):
            if value is not None and not math.isfinite(value):
                raise ValueError(f"{flag}: expected a finite number, got {value}")
        if a.speed_mps is not None and a.speed_mps < 0:
            raise ValueError(f"--assume-speed-mps: expected a speed >= 0 m/s, got {a.speed_mps}")
        skew = self.max_radar_skew_ms
        if skew is not None and not (math.isfinite(skew) and skew > 0):
            raise ValueError(f"--max-radar-skew-ms: expected a time > 0 ms, got {skew}")
        if self.name is not None and not self.name.strip():
            raise ValueError("--name: expected a non-empty name")


@dataclass(frozen=True)
class ImportResult:
    """What was written: the folder, its frames (count, size, first and last stamp, ns),
    the calibration and manifest as written, and notes for the person importing."""

    out_dir: Path
    frames: int
    width_px: int
    height_px: int
    first_t_ns: int
    last_t_ns: int
    calibration: Calibration
    manifest: Manifest
    notes: tuple[str, ...] = field(default_factory=tuple)


def check_out_dir(out_dir: Path) -> None:
    """RecordingError unless `out_dir` is new or an empty folder."""
    if out_dir.exists() and not out_dir.is_dir():
        raise RecordingError(
            f"{out_dir}: expected a new or empty folder for the recording, it is a file"
        )
    if out_dir.is_dir() and any(out_dir.iterdir()):
        raise RecordingError(
            f"{out_dir}: expected a new or empty folder for the recording, it is not empty"
        )


@contextmanager
def staging(out_dir: Path) -> Iterator[Path]:
    """A temporary folder beside `out_dir`, renamed to it on success, removed on error.

    The caller writes the recording into the folder yielded. Success: the recording opens with
    Drive (RecordingError otherwise), which also writes its index; then the folder is renamed.
    """
    check_out_dir(out_dir)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    # mkdir, not tempfile.mkdtemp: the folder gets the user's usual permissions, not 0700.
    tmp = out_dir.parent / f".{out_dir.name}.{uuid.uuid4().hex[:12]}.partial"
    tmp.mkdir()
    try:
        yield tmp
        Drive(tmp).close()  # it must open; this also caches its index (moves keep it)
        check_out_dir(out_dir)
        if out_dir.exists():
            out_dir.rmdir()
        os.replace(tmp, out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def assumption_notes(
    options: ImportOptions, prepared: PreparedCan | None
) -> tuple[Assumptions, str, list[str]]:
    """The assumptions to write (yaw rate 0 with an assumed speed), their text, notes."""
    a = options.assumptions
    if prepared is not None and prepared.can is not None and a != Assumptions():
        raise ValueError(
            "--assume-speed-mps/--assume-yaw-rate-radps: the mapping's `can:` section records "
            "speed and yaw rate; assumptions are for recordings without them"
        )
    if a.speed_mps is not None and a.yaw_rate_radps is None:
        a = Assumptions(a.speed_mps, 0.0)
    text, notes = "", []
    if a.speed_mps is not None:
        text = f"Speed not recorded: assumed {a.speed_mps:g} m/s"
    if a.yaw_rate_radps is not None:
        text += ("; yaw rate" if text else "Yaw rate not recorded: assumed") + (
            f" {a.yaw_rate_radps:g} rad/s"
        )
    if text:
        text += "."
    if (
        a.speed_mps is None
        and not options.ego_from_radar
        and (prepared is None or prepared.can is None)
    ):
        notes.append(
            "no speed: nothing records it and --assume-speed-mps is not given, so speed is NaN "
            "and the engine's motion stereo cannot work"
        )
    return a, text, notes


def write_manifest(
    tmp: Path,
    *,
    kind: str,
    source: Path,
    source_text: str,
    camera: BagStream,
    built: BuiltCalibration,
    radar: BagStream | RadarCanSource | None,
    prepared: PreparedCan | None,
    assumptions: Assumptions,
    assumption_text: str,
    options: ImportOptions,
    notes: list[str],
) -> Manifest:
    """Copy the CAN files, write calibration and manifest (checked by staging's open), and
    with `options.ego_from_radar` the speed from the radar (write_ego_from_radar, whose note
    is added to `notes`).

    The description: "Imported by `fusionscope import KIND` from NAME" + source_text, then
    the calibration's, the CAN mapping's and the assumptions' descriptions.
    """
    if prepared is not None:
        for rel, src in prepared.files.items():
            shutil.copyfile(src, tmp / rel)
    save_calibration(built.calibration, tmp / CALIBRATION_NAME)
    description = join_text(
        f"Imported by `fusionscope import {kind}` from {source.name}{source_text}",
        built.description,
        prepared.description if prepared is not None else "",
        assumption_text,
    )
    manifest = Manifest(
        folder=tmp,
        name=recording_name(options, source),
        description=description,
        generator={"importer": kind, "source": source.name},
        camera=camera,
        radar=radar,
        can=prepared.can if prepared is not None else None,
        calibration=CALIBRATION_NAME,
        assumptions=assumptions,
        max_radar_skew_ms=options.max_radar_skew_ms,
    )
    save_manifest(manifest, tmp / MANIFEST_NAME)
    if options.ego_from_radar:
        manifest, note = write_ego_from_radar(manifest, built.calibration, source)
        notes.append(note)
    return manifest


def check_ego_from_radar(
    options: ImportOptions, prepared: PreparedCan | None, has_radar: bool, source: Path
) -> None:
    """Before anything is written: ValueError naming --ego-from-radar when it is asked of a
    recording without radar, with CAN speed (the mapping's `can:` section), or with a CAN
    file that would take the name of a file it writes. (With assumptions: ImportOptions.)"""
    if not options.ego_from_radar:
        return
    if prepared is not None and prepared.can is not None:
        raise ValueError(
            "--ego-from-radar: the mapping's `can:` section records speed and yaw rate; "
            "--ego-from-radar is for recordings without them"
        )
    taken = sorted({CAN_LOG, DBC_NAME} & set(prepared.files if prepared is not None else ()))
    if prepared is not None and taken:
        raise ValueError(
            f"--ego-from-radar: writes {taken[0]}, and a CAN file of that name is copied into "
            f"the recording ({prepared.files[taken[0]]}); rename the file"
        )
    if not has_radar:
        raise ValueError(
            f"--ego-from-radar: {source} gives no radar to estimate the speed from (no radar "
            "topic, no `radar:` section in the mapping)"
        )


def write_ego_from_radar(
    manifest: Manifest,
    calibration: Calibration,
    source: Path,
) -> tuple[Manifest, str]:
    """The speed from the staged recording's radar scans, written into it as CAN.

    manifest: as write_manifest wrote it into the staging folder (radar, no CAN speed;
    check_ego_from_radar passed). Each scan's speed (core.radar_ego.speeds_from_scans with
    the default RadarEgoParams) becomes one CAN sample at the scan's stamp with a yaw rate of
    0 (the radar gives none usable: core/radar_ego.py Notes), written by
    core.io.writer.write_vehicle_can; scans without a fit are left out (the Drive
    interpolates between samples). The manifest is saved again with that `can:` section
    and its description extended. Returns it and a note for the person importing;
    RecordingError naming `source` when no scan gives a speed.
    """
    params = RadarEgoParams()
    scans = build_index(manifest).radar
    if scans is None or len(scans.t_ns) == 0:
        raise RecordingError(f"{source}: --ego-from-radar: the recording holds no radar scan")
    speeds = speeds_from_scans(
        scans.range_rate_mps,
        scans.azimuth_rad,
        scans.start,
        calibration.radar_mount.yaw_rad,
        params,
        range_m=scans.range_m,
    )
    fitted = np.flatnonzero(np.isfinite(speeds))
    if fitted.size == 0:
        raise RecordingError(
            f"{source}: --ego-from-radar: none of the radar's {len(speeds)} scans has "
            f"{params.min_stationary} stationary returns at distinct places agreeing on one "
            "speed (core/radar_ego.py); give the speed another way (CAN, --assume-speed-mps)"
        )
    samples = [VehicleState(int(scans.t_ns[k]), float(speeds[k]), 0.0) for k in fitted]
    can = write_vehicle_can(manifest.folder, samples)
    low, high = float(speeds[fitted].min()), float(speeds[fitted].max())
    text = (
        f"Speed estimated from the radar's stationary returns (core.radar_ego) on "
        f"{fitted.size} of {len(speeds)} scans, written as CAN ({CAN_LOG}, {DBC_NAME}); "
        "yaw rate not recorded: 0 (the radar gives no usable yaw rate)."
    )
    manifest = replace(manifest, can=can, description=join_text(manifest.description, text))
    save_manifest(manifest, manifest.folder / MANIFEST_NAME)
    note = (
        f"speed from the radar's stationary returns on {fitted.size} of {len(speeds)} scans "
        f"({low:.1f}-{high:.1f} m/s; between them the speed is interpolated); yaw rate not "
        "recorded: 0, the radar gives no usable yaw rate (core/radar_ego.py Notes)"
    )
    return manifest, note


def recording_name(options: ImportOptions, source: Path) -> str:
    """The recording's name: `options.name`, else the source file's stem (else its name)."""
    return options.name if options.name is not None else source.stem or source.name


def join_text(*parts: str) -> str:
    """The non-blank `parts`, stripped, joined by single spaces."""
    return " ".join(p.strip() for p in parts if p.strip())


def result(
    out_dir: Path,
    stamps: Sequence[int],
    size: tuple[int, int],
    calibration: Calibration,
    manifest: Manifest,
    notes: Sequence[str],
) -> ImportResult:
    """What an import wrote into `out_dir`: `stamps` of frames of `size` (width, height)."""
    return ImportResult(
        out_dir,
        len(stamps),
        size[0],
        size[1],
        stamps[0],
        stamps[-1],
        calibration,
        replace(manifest, folder=out_dir),
        tuple(notes),
    )


def check_image_file(path: Path, size: tuple[int, int] | None = None, whose: str = "") -> None:
    """RecordingError naming `path` when its PNG or JPEG header declares a size other than
    `size` (W, H), or over MAX_IMAGE_PIXELS: before any of it is decoded (a small file may
    declare a huge image). Other formats are left for the decoder to judge."""
    try:
        declared = file_image_size_px(path)
    except OSError as err:
        raise RecordingError(f"{path}: cannot read the image: {err.strerror or err}") from err
    if declared is None:
        return
    width, height = declared
    if size is not None and declared != size:
        raise RecordingError(
            f"{path}: the image declares {width}x{height} pixels, expected {size[0]}x{size[1]} "
            f"({whose}); not decoded"
        )
    if width * height > MAX_IMAGE_PIXELS:
        raise RecordingError(
            f"{path}: the image declares {width}x{height} pixels, more than the "
            f"{MAX_IMAGE_PIXELS:,} an import decodes; not decoded"
        )


def read_grey(path: Path, size: tuple[int, int] | None = None, whose: str = "") -> GreyImage:
    """(H, W) uint8 grey of the image file at `path`; RecordingError naming it when it cannot
    be decoded, or is not `size` (W, H) when that is given (`whose`: whose size it is, for
    the message)."""
    check_image_file(path, size, whose)
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise RecordingError(f"{path}: cannot decode the image (expected a JPEG or PNG)")
    if size is not None and (image.shape[1], image.shape[0]) != size:
        raise RecordingError(
            f"{path}: image is {image.shape[1]}x{image.shape[0]}, expected {size[0]}x{size[1]} "
            f"({whose})"
        )
    return np.asarray(image, dtype=np.uint8)


def output_size(width_px: int, source_size: tuple[int, int]) -> tuple[int, int]:
    """(width, height) of the resized image: `width_px` wide, the source's aspect ratio."""
    sw, sh = source_size
    return width_px, max(1, round(width_px * sh / sw))


def to_grey(frame: npt.NDArray[Any], size: tuple[int, int]) -> GreyImage:
    """(H, W) uint8 grey of a decoded 8-bit frame (grey, BGR or BGRA), resized to `size` (W, H).

    Shrinking averages pixel areas (cv2.INTER_AREA); enlarging interpolates linearly.
    """
    if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
        raise ValueError(f"frame: expected an 8-bit image, got {frame.dtype} {frame.shape}")
    grey: npt.NDArray[Any] = frame
    if frame.ndim == 3 and frame.shape[2] == 4:
        grey = cv2.cvtColor(frame, cv2.COLOR_BGRA2GRAY)
    elif frame.ndim == 3 and frame.shape[2] == 3:
        grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    elif frame.ndim == 3:
        grey = frame[:, :, 0]
    if (grey.shape[1], grey.shape[0]) != size:
        shrink = size[0] < grey.shape[1]
        grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
    return np.ascontiguousarray(grey, dtype=np.uint8)


def camera_bag(tmp: Path) -> SplitBagWriter:
    """A writer of the recording's camera bag (BAG_DIR in `tmp`), split at MAX_BAG_FILE_BYTES."""
    return SplitBagWriter(
        tmp / BAG_DIR,
        {CAMERA_TOPIC: radar_msgs.COMPRESSED_IMAGE},
        radar_msgs.typestore(),
        MAX_BAG_FILE_BYTES,
    )
