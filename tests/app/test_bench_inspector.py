"""scripts/bench_inspector.py end to end with tiny counts: it prints finite figures and leaves
no server behind. No time is asserted: the script measures, the people reading it judge.

Needs Debian's chromium at /usr/bin/chromium; without it the test skips, except when CI or
REQUIRE_BROWSER is set, where it fails (as tests/app/test_browser.py).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest
from browser_page import CHROMIUM, load_script


def numbers(value: object) -> list[float]:
    """Every number in a JSON value, booleans aside."""
    if isinstance(value, bool):
        return []
    if isinstance(value, int | float):
        return [float(value)]
    if isinstance(value, dict):
        return [x for v in value.values() for x in numbers(v)]
    if isinstance(value, list):
        return [x for v in value for x in numbers(v)]
    return []


def test_tiny_run_prints_finite_figures_and_stops_its_server(
    capsys: pytest.CaptureFixture[str],
) -> None:
    if not CHROMIUM.exists():
        message = f"the inspector benchmark needs Debian chromium at {CHROMIUM}"
        if os.environ.get("CI") or os.environ.get("REQUIRE_BROWSER"):
            pytest.fail(message + " (CI / REQUIRE_BROWSER is set)")
        pytest.skip(message)
    bench = load_script("bench_inspector")
    args = ["--seeks", "3", "--moves", "3", "--play-s", "2", "--tabs", "2", "--warmup", "1"]
    code = bench.main([*args, "--json", "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0, out

    table, _, doc = out.partition("\n{")
    summary = json.loads("{" + doc)
    for name in ("seek to a random frame", "parameter change -> panels", "-> exact (replayed)"):
        assert name in table
    assert [lat["count"] for lat in summary["latency"]] == [3, 3, 3]
    # a miss would print as null (no latency): every action finished
    assert all(math.isfinite(x) for x in numbers(summary["latency"])), summary["latency"]
    # at 4x: one tab, two with one idle, both playing (+ mean); both playing at 1x (+ mean)
    assert len(summary["playback"]) == 6
    assert all(math.isfinite(p["fps"]) and p["fps"] >= 0 for p in summary["playback"])
    real_time = [p for p in summary["playback"] if "at 1x" in p["name"]]
    assert [p["target_fps"] for p in real_time] == [0.9 * summary["frame_rate_hz"], None]
    assert all(v > 0 for v in summary["memory"]["rss_kib"].values())
    assert math.isfinite(summary["memory"]["growth_pct"])

    assert not Path(f"/proc/{summary['server_pid']}").exists()
