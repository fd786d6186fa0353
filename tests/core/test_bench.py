"""`fusionscope bench`: the figures come out in both formats; bad input is a clear error.

Nothing here asserts on time (the machine is noisy): only that the figures are there and
consistent with each other.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from core.bench import BUDGET_MS, PAPER_MS, STAGES, TOTAL, _tracking_cases, _tracking_runs, bench
from core.cli import DEFAULT_RECORDINGS, main
from core.engine import FusionEngine
from core.io.drive import Drive
from core.params import Params

HIGHWAY = DEFAULT_RECORDINGS / "highway"
TIMING_KEYS = {"median_ms", "p10_ms", "p90_ms", "paper_ms"}
MACHINE_TYPES = {
    "python": str,
    "numpy": str,
    "opencv": str,
    "numba": str,
    "cpu": str,
    "logical_cpus": int,
    "threads": int,
}


def _check_timing(name: str, t: dict[str, object], reference_ms: float) -> None:
    assert TIMING_KEYS <= set(t)
    assert isinstance(t["ref_multiple"], float)
    median, p10, p90 = t["median_ms"], t["p10_ms"], t["p90_ms"]
    assert isinstance(median, float) and isinstance(p10, float) and isinstance(p90, float)
    assert 0 < p10 <= median <= p90
    paper = PAPER_MS[name]
    assert t["paper_ms"] == paper
    assert t["budget_ms"] == BUDGET_MS[name]
    assert t["ref_multiple"] == pytest.approx(median / reference_ms)
    if paper is None:
        assert t["speedup"] is None
    else:
        assert t["speedup"] == pytest.approx(paper / median)
    assert t["image"] == "640x300"
    assert t["frames"] == 2


def test_json_has_every_stage_the_total_and_the_reference(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["bench", "--format", "json", "--frames", "2", "--repeat", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    stages = out["stages"]
    assert set(stages) == set(STAGES) - {TOTAL}
    assert list(stages) == [s for s in STAGES if s != TOTAL]  # the pipeline's order
    reference = out["reference_kernel_ms"]
    assert isinstance(reference, float) and reference > 0
    assert out["reference_kernel"]["median_ms"] == reference
    assert out["reference_kernel"]["image"] == "640x300"
    for name, t in stages.items():
        _check_timing(name, t, reference)
        # one run per frame, per slow target for the guard-rail filter
        assert t["runs"] == 4 if name != "guardrail" else t["runs"] % 2 == 0
    assert stages["tracking"]["paper_ms"] is None
    total = out["total"]
    _check_timing(TOTAL, total, reference)
    assert total["paper_ms"] == pytest.approx(1000 / 7) and total["budget_ms"] == 3.0
    assert isinstance(out["run_frames_per_s"], float) and out["run_frames_per_s"] > 0
    with Drive(HIGHWAY) as drive:
        assert out["run"]["frames"] == len(drive)
    assert out["guard_rail_savings"] is not None  # vehicle and guardrail both ran
    machine = out["machine"]
    for key, kind in MACHINE_TYPES.items():
        assert isinstance(machine[key], kind), key
    assert machine["threads"] == 1 and machine["cpu"]


def test_guard_rail_savings_reproduce_paper_002_table_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["bench", "--stage", "vehicle", "--stage", "guardrail", "--format", "json"]
    assert main([*args, "--frames", "3", "--repeat", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["stages"]) == {"vehicle", "guardrail"}
    assert out["total"] is None and out["run_frames_per_s"] is None  # total not chosen
    s = out["guard_rail_savings"]
    assert s["paper_ms"] == {"vd": 26.6, "grd": 23.2, "obm": 21.4}
    assert s["reduction"] == pytest.approx(1 - s["obm_ms"] / s["vd_ms"])
    assert s["frames"] == 3 and s["slow_targets"] <= s["targets"]
    # overlap management searches fewer areas, and never more than the slow targets
    assert s["searched_obm"] <= s["searched_grd"] <= s["slow_targets"]
    assert s["guard_rails"] > 0  # the highway's rails


def test_table_names_the_stage_and_the_reference(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--stage", "pitch", "--frames", "2", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    assert "pitch" in out and "motion_stereo" not in out and "total" not in out
    assert "4.0" in out  # the paper's 4 ms
    assert "x ref" in out and "cv2.warpPerspective 640x300" in out
    assert "fusionscope run" not in out  # measured with total only


def test_stage_total_times_the_whole_frame_and_run() -> None:
    report = bench([TOTAL], HIGHWAY, frames=2, warmup=0, repeat=1, run_passes=1)
    assert report.stages == {} and report.guard_rail_savings is None
    assert report.total is not None and report.total.runs == 2
    assert report.run is not None and report.run.frames == 150 and report.run.passes == 1


def test_stage_selects_and_total_comes_last(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["bench", "--stage", "tracking", "--stage", "pedestrian", "--frames", "2"]
    assert main([*args, "--repeat", "1", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert list(out["stages"]) == ["tracking", "pedestrian"]
    assert out["total"] is None and out["guard_rail_savings"] is None


def test_tracking_runs_on_the_engines_tracker() -> None:
    """The tracker the tracking stage updates is the engine's after the frame before: the
    update gives the engine's tracks of that frame, ids included, every run alike."""
    with Drive(HIGHWAY) as drive:
        pairs = [(drive.frame(k - 1), drive.frame(k)) for k in (6, 14)]
        cases = _tracking_cases(drive, pairs, Params())
        engine = FusionEngine(Params(), drive.camera)
        expected = {i: engine.process(drive.frame(i)).tracking for i in range(15)}
    assert [len(c.tracker._tracks) for c in cases] == [len(expected[k - 1].tracks) for k in (6, 14)]
    for (_, now), run in zip(pairs, _tracking_runs(cases, Params()), strict=True):
        first, second = run()(), run()()
        assert first == second == expected[now.index]
    assert expected[14].confirmed  # a test with tracks to compare


def test_bad_input_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--recording", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err
    assert "--recording" in err and "missing" in err and "Traceback" not in err
    params = tmp_path / "params.yaml"
    params.write_text("pitch: [")
    assert main(["bench", "--params", str(params)]) == 2
    err = capsys.readouterr().err
    assert "--params" in err and "not valid YAML" in err and "Traceback" not in err
    for args, named in (
        (["--stage", "symmetry"], "argument --stage: invalid choice: 'symmetry'"),
        (["--stage", "frame"], "argument --stage: invalid choice: 'frame'"),
        (["--frames", "1"], "argument --frames: expected a whole number >= 2"),
        (["--repeat", "0"], "argument --repeat: expected a whole number >= 1"),
    ):
        with pytest.raises(SystemExit) as exit_:
            main(["bench", *args])
        assert exit_.value.code == 2
        err = capsys.readouterr().err
        assert named in err and "Traceback" not in err
    with pytest.raises(ValueError, match="stage: expected one of pitch, motion_stereo, vehicle"):
        bench(["symmetry"], HIGHWAY)
    with pytest.raises(ValueError, match="repeat: expected a whole number >= 1, got 0"):
        bench(["pitch"], HIGHWAY, repeat=0)
