"""scripts/bench_export.py: it reads export-video's own summary line, and end to end on a
small drive, against this same checkout, it prints a row per checkout with finite figures.
No time is asserted: the script measures, the people reading it judge."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from app_fakes import Recordings
from browser_page import load_script

from app.video_export import ExportSummary, summary_text

bench = load_script("bench_export")
CHECKOUT = Path(__file__).resolve().parents[2]


def test_the_figures_are_read_from_export_videos_own_summary() -> None:
    # 150 frames of 10 Hz in 1.5 s, the first 0.3 s: 10x, and 149 frames in 1.2 s after it
    summary = ExportSummary(Path("x.mp4"), 0, 149, (640, 570), 10.0, 1, 1.5, 1.5, 0.3)
    got = bench.parse_summary("progress ...\n" + summary_text(summary) + "\n")
    assert got == bench.Export(1.5, 10.0, round(14.9 / 1.2, 1), 0.3)


def test_output_without_a_summary_is_an_error_quoting_it() -> None:
    with pytest.raises(ValueError, match=r"expected export-video's summary line .* 'nothing'"):
        bench.parse_summary("nothing")


def test_one_run_against_this_checkout_prints_both_rows(
    recordings: Recordings, capsys: pytest.CaptureFixture[str]
) -> None:
    drive = recordings.root / recordings.name
    assert bench.main(["--runs", "1", "--against", str(CHECKOUT), str(drive)]) == 0
    table = capsys.readouterr().out
    rows = [line for line in table.splitlines() if line.startswith(f"| {drive.name} |")]
    assert [row.split(" | ")[1].split()[0] for row in rows] == ["this", "against"]
    for row in rows:
        figures = [float(x) for x in re.findall(r"[0-9]+\.[0-9]+", row)]
        assert len(figures) == 4 and all(math.isfinite(x) and x > 0 for x in figures), row
    assert re.search(r"reference kernel: [0-9.]+ ms over 1 runs", table)
    assert re.search(
        r"^against .*: [0-9.]+ s in all \([0-9.]+ x the time of this .*\)$", table, re.M
    )


@pytest.mark.parametrize(
    ("args", "error"),
    [
        (["--runs", "0"], r"--runs: expected at least 1, got 0"),
        (["--cpu", "4096"], r"--cpu: expected one of \[.*\], got 4096"),
        (["/no/such/drive"], r"recordings: expected recording folders, got /no/such/drive"),
        (["--against", "/tmp"], r"--against: expected a fusionscope checkout, got /tmp"),
    ],
)
def test_bad_arguments_are_named(
    args: list[str], error: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as stop:
        bench.main(args)
    assert stop.value.code == 2
    assert re.search(error, capsys.readouterr().err)


def test_a_failing_export_is_reported_with_its_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    not_a_drive = tmp_path / "empty"
    not_a_drive.mkdir()
    assert bench.main(["--runs", "1", str(not_a_drive)]) == 1
    err = capsys.readouterr().err
    assert re.search(r"bench_export: .*: fusionscope export-video .*empty.* failed \(\d+\): ", err)
    assert str(not_a_drive) in err.splitlines()[-1]
