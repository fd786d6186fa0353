"""`fusionscope bench`: the figures come out in both formats; bad input is a clear error.

Nothing here asserts on time (the machine is noisy): only that the figures are there and
consistent with each other.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from core.bench import BUDGET_MS, PAPER_MS, STAGES, bench
from core.cli import DEFAULT_RECORDINGS, main

HIGHWAY = DEFAULT_RECORDINGS / "highway"


def test_json_has_every_stage_with_the_papers_figure(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--format", "json", "--frames", "2", "--repeat", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    stages = out["stages"]
    assert set(stages) == set(STAGES)
    assert "guard_rail_savings" in out  # vehicle and guardrail both ran
    for name, t in stages.items():
        assert t["paper_ms"] == PAPER_MS[name]
        assert t["budget_ms"] == BUDGET_MS[name]
        assert t["frames"] == 2
        # one run per frame, per slow target for the guard-rail filter
        assert t["runs"] == 4 if name != "guardrail" else t["runs"] % 2 == 0
        assert 0 < t["median_ms"] <= t["p90_ms"]
        if t["paper_ms"] is None:
            assert t["speedup"] is None
        else:
            assert t["speedup"] == pytest.approx(t["paper_ms"] / t["median_ms"])
        assert t["image"] == "640x300"


def test_guard_rail_savings_reproduce_paper_002_table_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["bench", "--stage", "vehicle", "--stage", "guardrail", "--format", "json"]
    assert main([*args, "--frames", "3", "--repeat", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["stages"]) == {"vehicle", "guardrail"}
    s = out["guard_rail_savings"]
    assert s["paper_ms"] == {"vd": 26.6, "grd": 23.2, "obm": 21.4}
    assert s["reduction"] == pytest.approx(1 - s["obm_ms"] / s["vd_ms"])
    assert s["frames"] == 3 and s["slow_targets"] <= s["targets"]
    # overlap management searches fewer areas, and never more than the slow targets
    assert s["searched_obm"] <= s["searched_grd"] <= s["slow_targets"]
    assert s["guard_rails"] > 0  # the highway's rails


def test_table_names_the_stage(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--stage", "pitch", "--frames", "2", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    assert "pitch" in out and "motion_stereo" not in out
    assert "4.0" in out  # the paper's 4 ms


def test_bad_input_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--recording", str(tmp_path / "missing")]) == 2
    assert "missing" in capsys.readouterr().err
    with pytest.raises(ValueError, match="stage: expected one of pitch, motion_stereo, vehicle"):
        bench(["symmetry"], HIGHWAY)
    with pytest.raises(SystemExit):
        main(["bench", "--frames", "1"])
