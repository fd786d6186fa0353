"""`fusionscope bench`: the figures come out in both formats; bad input is a clear error.

Nothing here asserts on time (the machine is noisy): only that the figures are there and
consistent with each other.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from core.bench import BUDGET_MS, PAPER_MS, STAGES, bench_stages
from core.cli import DEFAULT_RECORDINGS, main

HIGHWAY = DEFAULT_RECORDINGS / "highway"


def test_json_has_every_stage_with_the_papers_figure(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--format", "json", "--frames", "2", "--repeat", "2"]) == 0
    stages = json.loads(capsys.readouterr().out)["stages"]
    assert set(stages) == set(STAGES)
    for name, t in stages.items():
        assert t["paper_ms"] == PAPER_MS[name]
        assert t["budget_ms"] == BUDGET_MS[name]
        assert t["runs"] == 2 * t["frames"] == 4
        assert 0 < t["median_ms"] <= t["p90_ms"]
        assert t["speedup"] == pytest.approx(t["paper_ms"] / t["median_ms"])
        assert t["image"] == "640x300"


def test_table_names_the_stage(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--stage", "pitch", "--frames", "2", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    assert "pitch" in out and "motion_stereo" not in out
    assert "4.0" in out  # the paper's 4 ms


def test_bad_input_is_a_clear_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--recording", str(tmp_path / "missing")]) == 2
    assert "missing" in capsys.readouterr().err
    with pytest.raises(ValueError, match="stage: expected one of pitch, motion_stereo"):
        bench_stages(["symmetry"], HIGHWAY)
    with pytest.raises(SystemExit):
        main(["bench", "--frames", "1"])
