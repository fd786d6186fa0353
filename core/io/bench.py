"""Benchmark of opening and scrubbing a long drive: open time, seek time, resident memory.

    python -m core.io.bench [--seconds 3600] [--keep DIR]

Writes a drive of the given length (10 fps camera at 160x120, a 20 Hz radar with 8 returns,
50 Hz CAN speed and yaw rate) unless DIR already holds one, then prints the open time with
the index built from the files and with it cached (as after writing or importing, which
index the recording), and the median seek time and memory while reading 1,000
random frames. Every frame carries its own index in its first pixels, so each seek is also
checked to return the frame asked for.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import Intrinsics
from core.io.drive import Drive
from core.io.frame import RadarTarget
from core.io.manifest import MANIFEST_NAME
from core.io.writer import RecordingWriter
from core.synth.generate import synthetic_calibration

WIDTH_PX, HEIGHT_PX = 160, 120
CAMERA_PERIOD_NS = 100_000_000
RADAR_PERIOD_NS = 50_000_000
CAN_PERIOD_NS = 20_000_000
START_NS = 1_767_225_600 * 1_000_000_000  # 2026-01-01
SEEKS = 1000


def frame_image(i: int) -> npt.NDArray[np.uint8]:
    """A road-like gradient with the frame number written on it and coded in row 0."""
    rows = np.linspace(60, 180, HEIGHT_PX, dtype=np.float64)[:, None]
    img = np.repeat(rows, WIDTH_PX, axis=1).astype(np.uint8)
    cv2.putText(img, str(i), (8, 70), cv2.FONT_HERSHEY_SIMPLEX, 0.9, 255, 2)
    img[0, :4] = [(i >> s) & 0xFF for s in (24, 16, 8, 0)]
    return img


def frame_number(image: npt.NDArray[np.uint8]) -> int:
    b = [int(v) for v in image[0, :4]]
    return (b[0] << 24) | (b[1] << 16) | (b[2] << 8) | b[3]


def write_long_drive(out: Path, seconds: float) -> None:
    cal = synthetic_calibration()
    intrinsics = Intrinsics.from_fov(WIDTH_PX, HEIGHT_PX, math.radians(45.0))
    cal = replace(cal, camera=replace(cal.camera, intrinsics=intrinsics, rows_used_px=None))
    end_ns = START_NS + int(seconds * 1e9)
    with RecordingWriter(out, name=out.name, calibration=cal, description="benchmark") as w:
        for i, t in enumerate(range(START_NS, end_ns, CAMERA_PERIOD_NS)):
            w.add_image(t, frame_image(i))
        for k, t in enumerate(range(START_NS, end_ns, RADAR_PERIOD_NS)):
            targets = [
                RadarTarget.from_polar(
                    20.0 + j + (k % 50) * 0.1, 0.02 * (j - 4), -1.0, 10.0, 3.6, 0
                )
                for j in range(8)
            ]
            w.add_radar_scan(t, targets)
        for t in range(START_NS, end_ns, CAN_PERIOD_NS):
            w.add_vehicle_state(t, 25.0, 0.01 * math.sin((t - START_NS) / 1e10))


def rss_mb() -> float:
    """Resident memory of this process now (MB)."""
    with open(f"/proc/{os.getpid()}/statm", encoding="ascii") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3600.0)
    parser.add_argument("--keep", type=Path, help="folder for the drive (kept; reused if there)")
    args = parser.parse_args(argv)
    tmp = tempfile.TemporaryDirectory(prefix="fusionscope-bench-")
    os.environ.setdefault("FUSIONSCOPE_CACHE_DIR", str(Path(tmp.name) / "cache"))
    folder = args.keep or Path(tmp.name) / "long"
    if not (folder / MANIFEST_NAME).is_file():
        started = time.perf_counter()
        write_long_drive(folder, args.seconds)
        print(f"wrote {folder} in {time.perf_counter() - started:.1f} s")
    print(f"rss before opening          {rss_mb():8.1f} MB")
    with Drive(folder, use_cache=False) as drive:
        built_s = drive.open_s
    with Drive(folder) as drive:
        print(f"frames                      {len(drive):8d}")
        print(f"open, index built           {built_s:8.3f} s")
        print(f"open, index cached          {drive.open_s:8.3f} s")
        print(f"rss after opening           {rss_mb():8.1f} MB")
        rng = np.random.default_rng(0)
        seeks_ms = []
        peak = 0.0
        for i in rng.integers(0, len(drive), SEEKS):
            started = time.perf_counter()
            frame = drive.frame(int(i))
            seeks_ms.append(1000 * (time.perf_counter() - started))
            if frame_number(frame.image) != i:
                print(f"frame {i}: got the image of frame {frame_number(frame.image)}")
                return 1
            peak = max(peak, rss_mb())
        print(f"seek median ({SEEKS} random)    {np.median(seeks_ms):8.2f} ms")
        print(f"seek 95th percentile        {np.percentile(seeks_ms, 95):8.2f} ms")
        print(f"rss while seeking, max      {peak:8.1f} MB")
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak rss of the process     {peak_mb:8.1f} MB")
    tmp.cleanup()
    return 0


if __name__ == "__main__":
    sys.exit(main())
