"""`fusionscope import still`: a one-frame recording folder from one image at a given
time, made grey and resized as a video frame (core.io.importers.video).
"""

from __future__ import annotations

from pathlib import Path

import cv2

from core.io import radar_msgs
from core.io.errors import RecordingError
from core.io.importers.calibration_spec import CalibrationSpec, build_calibration
from core.io.importers.can_mapping import CanSpec, check_can_times, prepare_can
from core.io.importers.finish import (
    DEFAULT_WIDTH_PX,
    NS_PER_S,
    ImportOptions,
    ImportResult,
    assumption_notes,
    camera_bag,
    check_ego_from_radar,
    check_image_file,
    check_out_dir,
    output_size,
    result,
    staging,
    to_grey,
    write_manifest,
)
from core.io.manifest import BagStream
from core.io.writer import BAG_DIR, CAMERA_TOPIC, png_image_message


def import_still(
    image_path: Path,
    out_dir: Path,
    t_ns: int,
    calibration: CalibrationSpec,
    width_px: int = DEFAULT_WIDTH_PX,
    can_spec: CanSpec | None = None,
    options: ImportOptions = ImportOptions(),
) -> ImportResult:
    """Write a one-frame recording of `image_path` stamped `t_ns` (ns on the CAN log's clock
    when `can_spec` is given) into `out_dir` (new or empty).

    The image is made grey and resized as a video frame; RecordingError or ValueError naming
    the file or the option on bad input, and nothing is left behind then.
    """
    check_out_dir(out_dir)
    if width_px < 1:
        raise ValueError(f"--width: expected a width >= 1 px, got {width_px}")
    if t_ns < 0:
        raise ValueError(f"--time-s: expected a time >= 0 s, got {t_ns / NS_PER_S:g}")
    if not image_path.is_file():
        raise RecordingError(f"{image_path}: image not found")
    check_image_file(image_path)
    frame = cv2.imread(str(image_path), cv2.IMREAD_COLOR)
    if frame is None:
        raise RecordingError(
            f"{image_path}: cannot decode the image; expected a file OpenCV reads (png, jpg, ...)"
        )
    prepared = prepare_can(can_spec) if can_spec is not None else None
    assumptions, assumption_text, notes = assumption_notes(options, prepared)
    notes.extend(prepared.notes if prepared is not None else ())
    source_size = (frame.shape[1], frame.shape[0])
    out_size = output_size(width_px, source_size)
    has_radar = prepared is not None and prepared.radar is not None
    check_ego_from_radar(options, prepared, has_radar, image_path)
    built = build_calibration(calibration, source_size, out_size, has_radar, "the image is")
    notes.extend(built.notes)
    if prepared is not None:
        what = f"--time-s {t_ns / NS_PER_S:.3f}"
        notes.extend(check_can_times(prepared, [t_ns], what, options.max_radar_skew_ms))
    image = to_grey(frame, out_size)
    with staging(out_dir) as tmp:
        bag = camera_bag(tmp)
        bag.write(CAMERA_TOPIC, t_ns, png_image_message(radar_msgs.typestore(), t_ns, image))
        bag.close()
        manifest = write_manifest(
            tmp,
            kind="still",
            source=image_path,
            source_text=(
                f" ({source_size[0]}x{source_size[1]}): one frame at {t_ns / NS_PER_S:.3f} s, "
                f"grey, resized to {out_size[0]}x{out_size[1]}."
            ),
            camera=BagStream(BAG_DIR, CAMERA_TOPIC),
            built=built,
            radar=prepared.radar if prepared is not None else None,
            prepared=prepared,
            assumptions=assumptions,
            assumption_text=assumption_text,
            options=options,
            notes=notes,
        )
    return result(out_dir, [t_ns], out_size, built.calibration, manifest, notes)
