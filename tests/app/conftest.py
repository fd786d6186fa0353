"""A recordings root with one small drive for the inspector tests.

The drive comes from `fusionscope synth` when the command is there, else from the bundled
`recordings/`, else it is `app_fakes.FakeDrive` written with the project's RecordingWriter.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from app_fakes import Recordings, write_fake_recording

from app.catalog import list_recordings

REPO_ROOT = Path(__file__).resolve().parents[2]
BUNDLED = REPO_ROOT / "recordings"
SYNTH_SECONDS = 2
FAKE_FRAMES = 50


def _synth(root: Path) -> bool:
    """Try `fusionscope synth` into root/highway; False when the command is not available."""
    cmd = [
        sys.executable,
        "-c",
        "import sys; from core.cli import main; sys.exit(main())",
        "synth",
        "--scenario",
        "highway",
        "--seconds",
        str(SYNTH_SECONDS),
        "--seed",
        "1",
        str(root / "highway"),
    ]
    done = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True, timeout=300)
    return done.returncode == 0 and "highway" in list_recordings(root)


@pytest.fixture(scope="session")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> Recordings:
    root = tmp_path_factory.mktemp("recordings")
    if _synth(root):
        return Recordings(root, "highway", "synth")
    if BUNDLED.is_dir() and list_recordings(BUNDLED):
        return Recordings(BUNDLED, list_recordings(BUNDLED)[0], "bundled")
    write_fake_recording(root / "fake", FAKE_FRAMES)
    return Recordings(root, "fake", "writer")
