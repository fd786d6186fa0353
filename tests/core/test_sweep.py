"""`fusionscope sweep`: the sweep file, the results file, the ranking, and a sweep on a
LocalCluster of two workers that is killed after its first result and resumed."""

from __future__ import annotations

import dataclasses
import json
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from core import sweep
from core.cli import main
from core.evaluation.codec import CodecError, decode, empty, encode
from core.evaluation.evaluate import (
    PEDESTRIAN_STAGES,
    RecordingReport,
    evaluate_recording,
    total,
)
from core.evaluation.objects import BoxScore, RailScore
from core.evaluation.vehicles import EventStats, FrameStats
from core.params import HASH_HEX_DIGITS, Params, save_params
from core.sweep import ResultsFile, SweepError, load_sweep
from core.synth.generate import generate

REPO_ROOT = Path(__file__).resolve().parents[2]
DRIVE_SECONDS = 2.0
GRID = {"vehicle.refined_error_m": [0.2, 0.4, 0.8]}  # the RD count grows with the tolerance
METRIC = "vehicles.frames.rd"
RUN_TIMEOUT_S = 240.0


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _message(path: Path, text: str) -> str:
    with pytest.raises(SweepError) as err:
        load_sweep(_write(path, text))
    return str(err.value)


@pytest.fixture(scope="module")
def drives(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    root = tmp_path_factory.mktemp("drives")
    return [generate(s, DRIVE_SECONDS, 1, root / s) for s in ("highway", "stop_and_go")]


@pytest.fixture(scope="module")
def report(drives: list[Path]) -> RecordingReport:
    """A real evaluated drive, timed and with the baselines (every kind of field filled)."""
    return evaluate_recording(drives[0], Params(), timing=True, baselines=True)


# --- the sweep file ---------------------------------------------------------------------------


def test_a_grid_is_every_combination_in_the_files_order(tmp_path: Path) -> None:
    text = "grid:\n  vehicle.refined_error_m: [0.2, 1]\n  pitch.lines_kept: [5, 6, 7]\n"
    s = load_sweep(_write(tmp_path / "s.yaml", text))
    assert s.names == ("vehicle.refined_error_m", "pitch.lines_kept")
    assert [dict(p.values) for p in s.sets] == [
        {"vehicle.refined_error_m": e, "pitch.lines_kept": n} for e in (0.2, 1.0) for n in (5, 6, 7)
    ]
    # an integer given for a float parameter is the float the parameters hold
    assert isinstance(s.sets[3].values[0][1], float)
    assert [p.params.pitch.lines_kept for p in s.sets] == [5, 6, 7] * 2
    assert [p.params.vehicle.refined_error_m for p in s.sets] == [0.2] * 3 + [1.0] * 3
    assert len({p.id for p in s.sets}) == 6
    assert (s.metric, s.goal) == (sweep.DEFAULT_METRIC, "max")


def test_a_sets_id_is_stable_and_follows_the_base(tmp_path: Path) -> None:
    grid = "grid:\n  vehicle.refined_error_m: [0.3]\n"
    first = load_sweep(_write(tmp_path / "a.yaml", grid)).sets[0]
    again = load_sweep(_write(tmp_path / "b.yaml", grid + "goal: min\n")).sets[0]
    assert first.id == again.id and len(first.id) == HASH_HEX_DIGITS
    save_params(Params().with_value("pitch.lines_kept", 9), tmp_path / "base.yaml")
    based = load_sweep(_write(tmp_path / "c.yaml", "base: base.yaml\n" + grid)).sets[0]
    assert based.params.pitch.lines_kept == 9 and based.values == first.values
    assert based.id != first.id


def test_values_of_a_set_are_applied_together(tmp_path: Path) -> None:
    # min_distance_m 45 alone is above the default max_distance_m (40): only together valid
    text = "grid:\n  pedestrian.min_distance_m: [45]\n  pedestrian.max_distance_m: [60]\n"
    (s,) = load_sweep(_write(tmp_path / "s.yaml", text)).sets
    assert (s.params.pedestrian.min_distance_m, s.params.pedestrian.max_distance_m) == (45, 60)


RANDOM = """
random:
  samples: 40
  seed: {seed}
  parameters:
    vehicle.search_width_m: {{low: 2.0, high: 3.5}}
    pitch.lines_kept: {{low: 4, high: 6}}
    guardrail.manage_overlaps: {{choices: [true, false]}}
"""


def test_a_random_sample_is_reproducible_and_within_its_bounds(tmp_path: Path) -> None:
    a = load_sweep(_write(tmp_path / "a.yaml", RANDOM.format(seed=3)))
    b = load_sweep(_write(tmp_path / "b.yaml", RANDOM.format(seed=3)))
    c = load_sweep(_write(tmp_path / "c.yaml", RANDOM.format(seed=4)))
    assert [p.values for p in a.sets] == [p.values for p in b.sets]
    assert [p.values for p in a.sets] != [p.values for p in c.sets]
    widths = [p.params.vehicle.search_width_m for p in a.sets]
    kept = [p.params.pitch.lines_kept for p in a.sets]
    overlaps = {p.params.guardrail.manage_overlaps for p in a.sets}
    assert all(2.0 <= w < 3.5 for w in widths) and len(set(widths)) == len(widths)
    assert all(type(k) is int for k in kept) and set(kept) == {4, 5, 6}  # both ends drawn
    assert overlaps == {True, False}
    assert len(a.sets) == 40  # widths are continuous: no two sets alike


def test_equal_sets_run_once(tmp_path: Path) -> None:
    text = "random: {samples: 30, seed: 0, parameters: {pitch.lines_kept: {low: 4, high: 5}}}"
    s = load_sweep(_write(tmp_path / "s.yaml", text))
    assert sorted(dict(p.values)["pitch.lines_kept"] for p in s.sets) == [4, 5]


def test_a_misspelt_parameter_fails_naming_the_file_and_the_key(tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    message = _message(path, "grid:\n  vehicle.serch_width_m: [2.0, 3.0]\n")
    assert message.startswith(f"{path}: grid: vehicle.serch_width_m: no such parameter")
    assert "search_width_m" in message  # what is known there
    message = _message(path, RANDOM.format(seed=1).replace("pitch.lines_kept", "pich.lines_kept"))
    assert f"{path}: random.parameters: pich.lines_kept: no such parameter" in message
    assert "pitch" in message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("- 1\n- 2\n", "expected a mapping with grid or random"),
        ("grid: [\n", "not valid YAML"),
        ("colour: red\ngrid: {pitch.lines_kept: [5]}\n", "colour: unknown key; known: base"),
        ("goal: up\ngrid: {pitch.lines_kept: [5]}\n", "goal: expected max or min, got 'up'"),
        ("metric: 3\ngrid: {pitch.lines_kept: [5]}\n", "metric: expected a figure's dotted name"),
        ("base: nowhere.yaml\ngrid: {pitch.lines_kept: [5]}\n", "base: "),
        ("goal: max\n", "expected exactly one of grid and random, got none"),
        (
            "grid: {pitch.lines_kept: [5]}\nrandom: {samples: 1}\n",
            "expected exactly one of grid and random, got grid and random",
        ),
        ("grid: 3\n", "grid: expected a mapping of parameter: [values], got 3"),
        ("grid: {pitch.lines_kept: 5}\n", "grid: pitch.lines_kept: expected a non-empty list"),
        ("grid: {pitch.lines_kept: []}\n", "grid: pitch.lines_kept: expected a non-empty list"),
        ("grid: {pitch: [5]}\n", "grid: pitch: no such parameter; known here: pitch, "),
        ("grid: {pitch: [5]}\n", "(pitch is a group of parameters, not one; in it: "),
        (
            "grid: {pitch.lines_kept: [1]}\n",
            "grid: the set pitch.lines_kept=1: pitch.lines_kept: expected an integer >= 2, got 1",
        ),
        ("grid: {pitch.lines_kept: [five]}\n", "pitch.lines_kept: expected an integer, got 'five'"),
        ("random: {samples: 2, parameters: {}}\n", "random: expected the keys samples, seed"),
        (
            "random: {samples: 0, seed: 1, parameters: {pitch.lines_kept: {low: 4, high: 5}}}\n",
            "random: samples: expected an integer >= 1, got 0",
        ),
        (
            "random: {samples: 2, seed: 1, parameters: {pitch.lines_kept: {low: 4.0, high: 5}}}\n",
            "random.parameters: pitch.lines_kept: expected integer low and high",
        ),
        (
            "random: {samples: 2, seed: 1, parameters: {pitch.lines_kept: {low: 6, high: 5}}}\n",
            "pitch.lines_kept: expected low <= high, got low 6, high 5",
        ),
        (
            "random: {samples: 2, seed: 1, parameters: {vehicle.search_width_m: {low: 1}}}\n",
            "vehicle.search_width_m: expected {low: A, high: B} or {choices: [...]}",
        ),
        (
            "random: {samples: 2, seed: 1, parameters: "
            "{guardrail.manage_overlaps: {low: 0, high: 1}}}\n",
            "guardrail.manage_overlaps: expected choices: [...] for a parameter that is no number",
        ),
        (
            "random: {samples: 2, seed: 1, parameters: {vehicle.search_width_m: {choices: []}}}\n",
            "vehicle.search_width_m: choices: expected a non-empty list",
        ),
    ],
)
def test_a_bad_sweep_file_fails_naming_the_file_and_the_key(
    tmp_path: Path, text: str, expected: str
) -> None:
    path = tmp_path / "s.yaml"
    message = _message(path, text)
    assert message.startswith(f"{path}: ") and expected in message


def test_an_unknown_metric_fails_listing_the_figures_near_it(tmp_path: Path) -> None:
    path = _write(tmp_path / "s.yaml", "grid: {pitch.lines_kept: [5]}\n")
    with pytest.raises(SweepError) as err:
        load_sweep(path, metric="vehicles.events.refined_shar")
    message = str(err.value)
    assert message.startswith(f"{path}: metric: vehicles.events.refined_shar: no such figure")
    assert "nearest: vehicles.events.refined_share" in message
    assert "under vehicles.events: vehicles.events.events" in message
    with pytest.raises(SweepError, match=r"figures: frames, vehicles\.\*"):
        load_sweep(path, metric="vehicle")
    # every figure `evaluate` gives for a total is a metric, and its value is read
    for name in ("pedestrians.vehicles.precision", "tracking.vehicles.mot.mota", "pitch.rms_deg"):
        sweep.check_metric(name)


def test_an_unknown_metric_on_the_command_line_fails_before_anything_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path / "s.yaml", "grid: {pitch.lines_kept: [5]}\n")
    results = tmp_path / "results.jsonl"
    args = ["sweep", str(path), "nowhere", "--results", str(results), "--metric", "mota"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("fusionscope sweep: --metric: mota: no such figure")
    assert "Traceback" not in err and not results.exists()


# --- the codec --------------------------------------------------------------------------------


def test_a_report_survives_encode_json_and_decode(report: RecordingReport) -> None:
    # the fields worth a round trip
    assert report.guardrail_timing and report.vehicles.fn_at and report.baselines is not None
    text = json.dumps(encode(report))
    assert decode(RecordingReport, json.loads(text)) == report


def test_decoding_names_the_field_that_does_not_fit(report: RecordingReport) -> None:
    def encoded() -> Any:
        return json.loads(json.dumps(encode(report)))

    data = encoded()
    data["vehicles"]["fn_at"][0][1] = "x"
    with pytest.raises(CodecError, match=r"^report\.vehicles\.fn_at\[0\]\[1\]: expected an int"):
        decode(RecordingReport, data, "report")
    data = encoded()
    data["vehicles"]["fn_at"][0].append(3)
    with pytest.raises(CodecError, match=r"^vehicles\.fn_at\[0\]: expected a list of 2 items"):
        decode(RecordingReport, data)
    data = encoded()
    del data["events"]
    with pytest.raises(CodecError, match=r"^events: missing"):
        decode(RecordingReport, data)
    data = encoded()
    data["pitch"]["colour"] = 1
    with pytest.raises(CodecError, match=r"^pitch\.colour: not a field of PitchScore"):
        decode(RecordingReport, data)


# --- the results file -------------------------------------------------------------------------


def _results(path: Path, report: RecordingReport, n: int) -> list[sweep.ParameterSet]:
    """A results file of `report` under the first n of three parameter sets."""
    grid = _write(path.with_suffix(".yaml"), "grid: {pitch.lines_kept: [5, 6, 7]}\n")
    sets = list(load_sweep(grid).sets[:n])
    with ResultsFile(path) as f:
        for s in sets:
            f.append(s, "drive", report, 1.0)
    return sets


def _edit(line: bytes, change: Any) -> bytes:
    data = json.loads(line)
    change(data)
    return json.dumps(data).encode("utf-8")


def test_results_are_read_back_as_written(tmp_path: Path, report: RecordingReport) -> None:
    path = tmp_path / "results.jsonl"
    sets = _results(path, report, 3)
    with ResultsFile(path) as f:
        assert not f.warnings
        assert [(r.set_id, r.recording) for r in f.results] == [(s.id, "drive") for s in sets]
        assert all(r.report == report for r in f.results)
    line = json.loads(path.read_text().splitlines()[0])
    assert line["values"] == {"pitch.lines_kept": 5}
    # the listings are in the report, not repeated in the figures
    assert line["report"]["vehicles"]["fn_at"]
    assert "fn_at" not in line["figures"]["vehicles"]["frames"]


def test_a_cut_short_last_line_is_dropped_with_a_warning(
    tmp_path: Path, report: RecordingReport
) -> None:
    path = tmp_path / "results.jsonl"
    sets = _results(path, report, 3)
    whole = path.read_bytes()
    two = whole[: whole.index(b"\n", whole.index(b"\n") + 1) + 1]
    path.write_bytes(two + whole[len(two) : len(two) + 200])  # killed while writing line 3
    with ResultsFile(path) as f:
        assert [r.set_id for r in f.results] == [s.id for s in sets[:2]]
        (warning,) = f.warnings
        assert f"{path}: line 3 is cut short" in warning
        f.append(sets[2], "drive", report, 1.0)
    with ResultsFile(path) as f:
        assert [r.set_id for r in f.results] == [s.id for s in sets] and not f.warnings
    assert path.read_bytes().startswith(two)


def test_a_whole_last_line_without_its_end_of_line_is_kept(
    tmp_path: Path, report: RecordingReport
) -> None:
    path = tmp_path / "results.jsonl"
    sets = _results(path, report, 2)
    path.write_bytes(path.read_bytes()[:-1])
    with ResultsFile(path) as f:
        assert len(f.results) == 2 and not f.warnings
        f.append(sets[0], "other", report, 1.0)
    with ResultsFile(path) as f:
        assert [r.recording for r in f.results] == ["drive", "drive", "other"]


@pytest.mark.parametrize(
    ("mend", "expected"),
    [
        (lambda line: line[:100], "not a line of JSON"),
        (lambda line: b'{"set": "x"}', "expected an object with the keys format_version, set"),
        (
            lambda line: _edit(line, lambda d: d["report"].update(frames="many")),
            "report.frames: expected an integer, got 'many'",
        ),
        (
            lambda line: _edit(line, lambda d: d.update(format_version=9)),
            "format_version: expected 1, got 9",
        ),
    ],
)
def test_a_malformed_line_before_the_last_is_refused_and_the_file_left_as_it_is(
    tmp_path: Path, report: RecordingReport, mend: Any, expected: str
) -> None:
    path = tmp_path / "results.jsonl"
    _results(path, report, 3)
    lines = path.read_bytes().split(b"\n")
    lines[1] = mend(lines[1])
    path.write_bytes(b"\n".join(lines))
    before = path.read_bytes()
    with pytest.raises(SweepError) as err, ResultsFile(path):
        pass
    assert str(err.value).startswith(f"{path}: line 2: ") and expected in str(err.value)
    assert "the file is left as it is" in str(err.value)
    assert path.read_bytes() == before


def test_one_results_file_takes_one_sweep_at_a_time(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    with ResultsFile(path), pytest.raises(SweepError, match="another sweep is writing"):
        with ResultsFile(path):
            pass
    with ResultsFile(path) as f:  # free again
        assert f.results == []


# --- ranking ----------------------------------------------------------------------------------


def _report(name: str, events: int, refined: int) -> RecordingReport:
    pedestrians = {k: empty(BoxScore) for k in PEDESTRIAN_STAGES}
    return dataclasses.replace(
        empty(RecordingReport),
        name=name,
        events=EventStats(events, 0, events - refined, refined),
        pedestrians=pedestrians,
    )


def test_ranking_takes_the_share_of_the_total_and_puts_incomplete_and_undefined_last(
    tmp_path: Path,
) -> None:
    text = "grid: {pitch.lines_kept: [3, 4, 5, 6]}\n"
    spec = load_sweep(_write(tmp_path / "s.yaml", text), metric="vehicles.events.refined_share")
    a, b, c, d = spec.sets
    rows = [
        # a: 1/1 and 0/9: mean of shares 0.5, share of the total 0.1
        (a, "r1", _report("r1", 1, 1)),
        (a, "r2", _report("r2", 9, 0)),
        # b: 2/4 and 2/4: 0.5 either way
        (b, "r1", _report("r1", 4, 2)),
        (b, "r2", _report("r2", 4, 2)),
        # c: no events: undefined
        (c, "r1", _report("r1", 0, 0)),
        (c, "r2", _report("r2", 0, 0)),
        # d: 1.0, on one recording only
        (d, "r1", _report("r1", 3, 3)),
        (d, "elsewhere", _report("elsewhere", 1, 0)),  # not among this sweep's recordings
    ]
    results = [sweep.TaskResult(s.id, dict(s.values), r, 1.0, rep) for s, r, rep in rows]
    ranked = sweep.rank(spec, ["r1", "r2"], results)
    assert [(r.rank, r.set.id) for r in ranked] == [(1, b.id), (2, a.id), (3, c.id), (4, d.id)]
    assert [r.metric for r in ranked] == [0.5, 0.1, None, 1.0]
    assert [r.complete for r in ranked] == [True, True, True, False]
    lowest = sweep.rank(dataclasses.replace(spec, goal="min"), ["r1", "r2"], results)
    assert [r.set.id for r in lowest] == [a.id, b.id, c.id, d.id]


def test_the_worst_frames_count_the_errors_evaluate_lists() -> None:
    r = _report("r", 0, 0)
    r = dataclasses.replace(
        r,
        vehicles=dataclasses.replace(
            empty(FrameStats),
            fn_at=((3, 1), (3, 2)),
            rfn_at=((8, 1),),
            nvo_at=((8, 5), (8, 6), (8, 7)),  # right answers
        ),
        guardrails=dataclasses.replace(empty(RailScore), fp_at=((5, 0),)),
        pedestrians={
            **r.pedestrians,
            "symmetry": BoxScore(missed_at=((8, 4),) * 5),  # before the filters: not counted
            "vehicles": BoxScore(missed_at=((8, 4),) * 5),  # paper 000's output: not counted
            "radar": BoxScore(missed_at=((8, 4),) * 5),  # before the HOG verification
            "hog": BoxScore(missed_at=((5, 9),), false_at=((1, 0),)),  # the engine's
        },
    )
    other = dataclasses.replace(
        _report("s", 0, 0), vehicles=dataclasses.replace(empty(FrameStats), fp_at=((2, 0),) * 3)
    )
    worst = sweep.worst_frames([r, other], n=3)
    assert [(f.recording, f.frame, f.errors) for f in worst] == [
        ("s", 2, 3),
        ("r", 3, 2),
        ("r", 5, 2),
    ]


# --- on Dask ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("sweep") / "sweep.yaml"
    return _write(path, f"metric: {METRIC}\ngrid: {json.dumps(GRID)}\n")


def _command(sweep_file: Path, drives: list[Path], results: Path, *more: str) -> list[str]:
    return [
        sys.executable,
        "-m",
        "core.cli",
        "sweep",
        str(sweep_file),
        *map(str, drives),
        "--results",
        str(results),
        "--workers",
        "2",
        *more,
    ]


@dataclasses.dataclass(frozen=True)
class Resumed:
    first_lines: bytes  # the file when the first run was killed, whole lines
    second: subprocess.CompletedProcess[str]
    final: bytes


@pytest.fixture(scope="module")
def resumed(sweep_file: Path, drives: list[Path]) -> Resumed:
    """A sweep killed (SIGKILL) as soon as its first result is in the file, then run again."""
    results = sweep_file.with_name("results.jsonl")
    first = subprocess.Popen(
        _command(sweep_file, drives, results),
        cwd=REPO_ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + RUN_TIMEOUT_S
        while not (results.exists() and b"\n" in results.read_bytes()):
            assert first.poll() is None, "the sweep ended before its first result"
            assert time.monotonic() < deadline, "no result within the time allowed"
            time.sleep(0.02)
    finally:
        first.kill()  # SIGKILL: no clean-up of any kind
        first.wait()
    killed = results.read_bytes()
    first_lines = killed[: killed.rindex(b"\n") + 1]
    second = subprocess.run(
        _command(sweep_file, drives, results, "--format", "json"),
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )
    return Resumed(first_lines, second, results.read_bytes())


def test_a_killed_sweep_resumes_with_the_remaining_tasks_only(resumed: Resumed) -> None:
    done = resumed.first_lines.count(b"\n")
    assert 1 <= done < 6
    assert resumed.second.returncode == 0, resumed.second.stderr
    assert f"= 6 tasks; {done} already in" in resumed.second.stderr
    assert f"{6 - done} to run on a local cluster of 2 workers" in resumed.second.stderr
    assert "6/6" in resumed.second.stderr  # the progress bar, counting the resumed ones
    # the lines of the first run stay, and only the missing tasks were added
    assert resumed.final.startswith(resumed.first_lines)
    lines = [json.loads(line) for line in resumed.final.splitlines()]
    assert len(lines) == 6
    assert len({(line["set"], line["recording"]) for line in lines}) == 6


def test_the_ranking_agrees_with_evaluating_each_set_directly(
    resumed: Resumed, sweep_file: Path, drives: list[Path]
) -> None:
    spec = load_sweep(sweep_file)
    direct = []
    for order, s in enumerate(spec.sets):
        summed = total([evaluate_recording(d, s.params, timing=False) for d in drives])
        direct.append((sweep.metric_value(summed, METRIC), order, s.id))
    values = [v for v, _, _ in direct]
    assert None not in values and len(set(values)) == len(values)  # an order to get wrong
    expected = [(s, v) for v, _, s in sorted(direct, key=lambda x: (-x[0], x[1]))]  # type: ignore[operator]
    shown = json.loads(resumed.second.stdout)
    assert [(row["set"], row["metric"]) for row in shown["sets"]] == expected
    assert all(row["complete"] for row in shown["sets"])
    with ResultsFile(sweep_file.with_name("results.jsonl")) as f:
        ranked = sweep.rank(spec, [sweep.recording_key(d) for d in drives], f.results)
    assert [(r.set.id, r.metric) for r in ranked] == expected
    assert all(r.worst_frames for r in ranked)


def test_a_finished_sweep_ranks_without_a_cluster(
    resumed: Resumed, sweep_file: Path, drives: list[Path], capsys: pytest.CaptureFixture[str]
) -> None:
    results = sweep_file.with_name("results.jsonl")
    args = ["sweep", str(sweep_file), *map(str, drives), "--results", str(results), "--top", "2"]
    assert main([*args, "--scheduler", "tcp://127.0.0.1:1"]) == 0  # never reached
    out, err = capsys.readouterr()
    assert "6 already in" in err and "0 to run" in err
    assert f"Parameter sets by {METRIC}, highest first" in out and "(the first 2 of 3 sets)" in out
    # on one of the recordings: the other's results are left out of the ranking
    assert main(["sweep", str(sweep_file), str(drives[0]), "--results", str(results)]) == 0
    out, err = capsys.readouterr()
    assert "3 already in" in err and "(and 3 of other sets or recordings, left out)" in err
    assert "on the total of 1 recordings" in out and "stop_and_go:" not in out
    assert results.read_bytes() == resumed.final


def test_a_recording_that_does_not_read_stops_the_sweep_naming_it(
    tmp_path: Path, drives: list[Path]
) -> None:
    (s,) = load_sweep(_write(tmp_path / "s.yaml", "grid: {pitch.lines_kept: [5]}\n")).sets
    todo = [sweep.Task(s, str(drives[0])), sweep.Task(s, str(tmp_path / "nowhere"))]
    results = tmp_path / "results.jsonl"
    with ResultsFile(results) as f, sweep.connect(None, 2) as client:
        with pytest.raises(SweepError) as err:
            sweep.run(client, todo, f)
    assert str(err.value).startswith(f"{tmp_path / 'nowhere'} with set {s.id}: ")
    assert "expected a recording folder" in str(err.value)
    with ResultsFile(results) as f:  # what finished before the error stays
        assert all(r.recording == str(drives[0]) for r in f.results)


# --- without Dask, without a scheduler ----------------------------------------------------------


def test_without_dask_the_command_says_how_to_install_it(
    tmp_path: Path,
    drives: list[Path],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed: ImportError
    path = _write(tmp_path / "s.yaml", "grid: {pitch.lines_kept: [5]}\n")
    assert main(["sweep", str(path), str(drives[0]), "--results", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "Dask, which is not installed: pip install -e '.[cluster]'" in err
    assert "Traceback" not in err


@pytest.fixture
def silent_server() -> Iterator[str]:
    """A port that takes connections and never says a word (no Dask scheduler)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        yield f"tcp://127.0.0.1:{s.getsockname()[1]}"


def test_a_bad_or_unreachable_scheduler_is_an_error_not_a_hang(
    silent_server: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sweep, "CONNECT_TIMEOUT_S", 1.0)
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        closed = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    for address, expected in (
        ("127.0.0.1", "not a scheduler's address (missing port number"),
        ("http://127.0.0.1:8786", "not a scheduler's address (unknown address scheme"),
        (closed, "no Dask scheduler answered within 1 s"),
        (silent_server, "no Dask scheduler answered within 1 s"),
    ):
        started = time.monotonic()
        with pytest.raises(SweepError) as err, sweep.connect(address, 2):
            pass
        assert str(err.value).startswith(f"--scheduler {address}: {expected}")
        assert "expected tcp://HOST:PORT" in str(err.value)
        assert time.monotonic() - started < 5.0
