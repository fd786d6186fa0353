"""Shared fixtures: the real recordings beside the project, small synthetic drives, and the
bundled drives evaluated once for every test that reads their figures."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from core.evaluation.evaluate import RecordingReport

REPO_ROOT = Path(__file__).resolve().parents[1]
REALDATA_DIR = REPO_ROOT.parent / "shared" / "realdata"
REPORT = pytest.StashKey[list[str]]()


def pytest_configure(config: pytest.Config) -> None:
    config.stash[REPORT] = []


def pytest_terminal_summary(
    terminalreporter: pytest.TerminalReporter, config: pytest.Config
) -> None:
    """Figures the tests measured (accuracy on the bundled drives), after the results."""
    lines = config.stash.get(REPORT, [])
    if lines:
        terminalreporter.section("figures measured by the tests")
        for line in lines:
            terminalreporter.write_line(line)


@pytest.fixture
def report(request: pytest.FixtureRequest) -> Callable[[str], None]:
    """Adds a line to the figures printed at the end of the test run."""
    return request.config.stash[REPORT].append


@pytest.fixture(scope="session")
def realdata() -> Path:
    """The real recordings in ../shared/realdata (see its README).

    Skips when they are absent, except when REQUIRE_REAL_DATA=1 (as in CI), where it fails.
    """
    if REALDATA_DIR.is_dir():
        return REALDATA_DIR
    message = f"real data not found at {REALDATA_DIR}"
    if os.environ.get("REQUIRE_REAL_DATA") == "1":
        pytest.fail(message + " and REQUIRE_REAL_DATA=1 is set")
    pytest.skip(message)


@pytest.fixture(autouse=True, scope="session")
def _index_cache_in_a_temporary_folder(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Drive caches recording indexes; tests keep them out of the user's cache folder."""
    os.environ["FUSIONSCOPE_CACHE_DIR"] = str(tmp_path_factory.mktemp("fusionscope-cache"))


# The RAV4's camera pose is not in the data set. It was estimated from the image: the two
# dashed lane lines of the ego lane meet at (597, 390.5) px in the 1164x874 frame. The horizon
# lies 46.5 px above cy = 437 px, so with fx = 910 px the camera looks down by
# atan(46.5 / 910) = 0.051 rad; the straight-ahead point lies 15 px right of cx = 582 px, a
# yaw of atan(15 / 910) = 0.0165 rad to the left (core.camera's convention). At 1.2 m height
# the ego lane then measures 3.5 m wide 9.8 m ahead, as a lane should.
RAV4_PITCH_RAD = 0.051
RAV4_YAW_RAD = 0.0165


@pytest.fixture(scope="session")
def rav4(realdata: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The RAV4's first frame imported with its CAN log (speed, yaw rate, radar tracks)."""
    from core.cli import main
    from core.io.importers.can_mapping import MAPPING_EXAMPLE

    rav4 = realdata / "comma2k19-rav4"
    mapping = tmp_path_factory.mktemp("mapping") / "rav4.yaml"
    mapping.write_text(MAPPING_EXAMPLE)
    out = tmp_path_factory.mktemp("rav4") / "rav4"
    args = ["import", "still", str(rav4 / "first_frame.png"), str(out), "--time-s", "46408.547"]
    args += ["--can", str(rav4 / "rav4_seg40.log.gz"), "--mapping", str(mapping)]
    args += ["--dbc", str(rav4 / "toyota_rav4_powertrain.dbc")]
    args += ["--dbc", str(rav4 / "toyota_adas_radar.dbc")]
    args += ["--fx", "910", "--cx", "582", "--cy", "437", "--camera-height-m", "1.2"]
    args += ["--pitch-rad", str(RAV4_PITCH_RAD), "--yaw-rad", str(RAV4_YAW_RAD)]
    args += ["--radar-x-m", "2.7"]
    args += ["--max-radar-skew-ms", "50"]
    assert main(args) == 0
    return out


# The README's import commands for the real drives (section "Real drives with real truth"),
# by the name of the recording each makes.
REAL_IMPORTS = {
    "nuscenes-scene-0523": ("nuscenes", "nuscenes-mini-scene-0523", "--scene", "scene-0523"),
    "aimotive-night-motorway": ("aimotive", "aimotive-night-motorway"),
}


@pytest.fixture(scope="session")
def real_recordings(realdata: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding the nuScenes and aiMotive drives imported as the README says."""
    from core.cli import main

    root = tmp_path_factory.mktemp("recordings-real")
    for name, (kind, source, *rest) in REAL_IMPORTS.items():
        assert main(["import", kind, str(realdata / source), str(root / name), *rest]) == 0
    return root


BUNDLED = ("highway", "exurban", "stop_and_go")


@pytest.fixture(scope="session")
def bundled_reports() -> list[RecordingReport]:
    """The bundled drives evaluated with the paper's parameters and the baselines, as
    `fusionscope evaluate --baselines` does (core.evaluation.evaluate.RecordingReport)."""
    from core.cli import DEFAULT_RECORDINGS
    from core.evaluation.evaluate import evaluate_recording
    from core.params import Params

    return [
        evaluate_recording(DEFAULT_RECORDINGS / name, Params(), baselines=True) for name in BUNDLED
    ]
