"""Parameter sweeps on Dask: every parameter set of a sweep file evaluated on every recording,
one task per (recording, parameter set), each result appended to a results file as it
finishes, and the sets ranked by one figure of their total (`fusionscope sweep`).

The sweep file (YAML) names the parameters to vary and how:

    base: tuned.yaml                        # optional: a parameter file, relative to this one
    metric: vehicles.events.refined_share   # optional: the figure ranked on (DEFAULT_METRIC)
    goal: max                               # optional: max or min (default max)
    grid:                                   # every combination, in the file's order
      vehicle.refined_error_m: [0.3, 0.4, 0.5]
      guardrail.manage_overlaps: [true, false]

or, instead of `grid`, a seeded random sample:

    random:
      samples: 20
      seed: 1
      parameters:
        vehicle.search_width_m: {low: 2.0, high: 4.0}   # a float parameter: uniform in [low, high)
        pitch.lines_kept: {low: 5, high: 9}             # an integer one: integers, both ends in
        guardrail.manage_overlaps: {choices: [true, false]}

A parameter set runs with the base (default: the papers' parameters) and its values. Its id
is a short hash of every parameter value it runs with, so the same set has the same id in
every run, and a set whose base changed does not take the old results for its own. Sets that
come out equal (a random sample may draw one twice) run once.

The results file holds JSON lines, one per finished task, appended, flushed and synced to
disk as each task finishes: {"format_version": 1, "set": id, "values": {name: value},
"recording": path as given, "seconds": the task's wall time, "figures":
`report.figures_json` of that recording (without the frame listings, which "report" holds),
"report": `codec.encode` of its RecordingReport}. A sweep first reads the file and runs only
the tasks not in it, so an interrupted sweep resumes where it stopped. A last line cut short
(the sweep was killed while writing it) is cut off the file with a warning, and its task
runs again; any other line that does not read is an error naming the file and the line, and
the file is left as it is. One sweep at a time appends to a results file (a lock).

Ranking: per parameter set, `evaluate.total` of its recordings' reports (shares are ratios of
sums, as the papers add up their sequences), and the metric, a dotted path into
`report.figures_json` of that total. Sets done on every recording come first, ordered by the
metric (undefined values last, ties in the sweep file's order); then the incomplete ones, the
same way, on the recordings they did finish. Each set also lists its worst frames: those with
the most errors of the kinds `fusionscope evaluate` lists (`errors_at`).

Notes:
- Tasks run `evaluate_recording` without paper 002's timing: times taken beside other busy
  workers are not its one-thread figures. So the timing figures are no metric.
- Recordings are read by the workers, at the path given made absolute on the machine that
  starts the sweep: on a cluster of several machines they must be at that path on every one.
"""

from __future__ import annotations

import contextlib
import dataclasses
import difflib
import fcntl
import itertools
import json
import logging
import math
import os
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, Literal, cast

import numpy as np
import yaml

from core.evaluation.codec import CodecError, decode, empty, encode
from core.evaluation.evaluate import (
    PEDESTRIAN_STAGES,
    RecordingReport,
    error_listings,
    evaluate_recording,
    total,
)
from core.evaluation.objects import BoxScore
from core.evaluation.report import Table, figures_json
from core.io.errors import RecordingError
from core.params import Params, ParamsError, load_params, params_hash

if TYPE_CHECKING:
    from distributed import Client

Goal = Literal["max", "min"]
Progress = Callable[[int, int], None]

DEFAULT_METRIC = "vehicles.events.refined_share"  # paper 001, table I: refined by vision
DEFAULT_GOAL: Goal = "max"
DEFAULT_WORKERS = 2  # of a LocalCluster
RESULTS_FORMAT_VERSION = 1
WORST_FRAMES = 5  # frames listed per set
CONNECT_TIMEOUT_S = 10.0  # to reach a scheduler given with --scheduler
# figures a sweep never has: it does not time (module docstring)
NOT_METRICS = ("guardrails.timing",)
SWEEP_KEYS = ("base", "metric", "goal", "grid", "random")
RANDOM_KEYS = ("samples", "seed", "parameters")


class SweepError(ValueError):
    """A sweep file, a results file or a cluster that cannot be used; the message names it."""


# --- the sweep file -------------------------------------------------------------------------


@dataclass(frozen=True)
class ParameterSet:
    """One combination of the sweep: (dotted name, value) in the sweep file's order, as the
    parameters hold them (an integer given for a float parameter reads as a float), and the
    whole parameters it runs with."""

    id: str
    values: tuple[tuple[str, Any], ...]
    params: Params


@dataclass(frozen=True)
class Sweep:
    """A sweep file read and checked: what is ranked, how, and the distinct parameter sets."""

    path: Path
    metric: str
    goal: Goal
    names: tuple[str, ...]  # the varied parameters, in the file's order
    sets: tuple[ParameterSet, ...]


def load_sweep(path: Path | str, metric: str | None = None, goal: str | None = None) -> Sweep:
    """Read and check a sweep file (module docstring); `metric` and `goal` override the
    file's. Every parameter set is built here, so a misspelt parameter or a value out of
    range fails before any task runs. SweepError names the file, the key and the problem."""
    p = Path(path)
    raw = _read_yaml(p)
    unknown = [k for k in raw if k not in SWEEP_KEYS]
    if unknown:
        raise SweepError(f"{p}: {unknown[0]}: unknown key; known: {', '.join(SWEEP_KEYS)}")
    base = Params()
    if raw.get("base") is not None:
        if not isinstance(raw["base"], str):
            raise SweepError(f"{p}: base: expected a parameter file's path, got {raw['base']!r}")
        try:
            base = load_params(p.parent / raw["base"])
        except ParamsError as err:
            raise SweepError(f"{p}: base: {err}") from None
    metric = metric if metric is not None else raw.get("metric", DEFAULT_METRIC)
    if not isinstance(metric, str):
        raise SweepError(f"{p}: metric: expected a figure's dotted name, got {metric!r}")
    try:
        check_metric(metric)
    except SweepError as err:
        raise SweepError(f"{p}: metric: {err}") from None
    goal = goal if goal is not None else raw.get("goal", DEFAULT_GOAL)
    if goal not in ("max", "min"):
        raise SweepError(f"{p}: goal: expected max or min, got {goal!r}")
    given = [k for k in ("grid", "random") if raw.get(k) is not None]
    if len(given) != 1:
        raise SweepError(
            f"{p}: expected exactly one of grid and random, got {' and '.join(given) or 'none'}"
        )
    if given == ["grid"]:
        names, combinations = _grid(p, raw["grid"], base)
        section = "grid"
    else:
        names, combinations = _random(p, raw["random"], base)
        section = "random"
    sets: dict[str, ParameterSet] = {}
    for combination in combinations:
        s = _parameter_set(p, section, base, names, combination)
        sets.setdefault(s.id, s)
    return Sweep(p, metric, cast(Goal, goal), names, tuple(sets.values()))


def _read_yaml(p: Path) -> dict[str, Any]:
    try:
        raw = yaml.safe_load(p.read_text(encoding="utf-8"))
    except OSError as err:
        raise SweepError(f"{p}: cannot read the sweep file: {err.strerror}") from err
    except UnicodeDecodeError as err:
        raise SweepError(f"{p}: not a UTF-8 text file: {err}") from err
    except yaml.YAMLError as err:
        raise SweepError(f"{p}: not valid YAML: {err}") from err
    if not isinstance(raw, dict):
        raise SweepError(
            f"{p}: expected a mapping with grid or random (and base, metric, goal), "
            f"got {type(raw).__name__}"
        )
    return raw


def _leaf(p: Path, section: str, base: Params, name: object) -> object:
    """The value of the dotted parameter `name` in `base`, or SweepError naming the file, the
    section and what `Params.value_of` says is known there."""
    if not isinstance(name, str):
        raise SweepError(f"{p}: {section}: expected a parameter's dotted name, got {name!r}")
    try:
        return base.value_of(name)
    except ParamsError as err:
        raise SweepError(f"{p}: {section}: {err}") from None


def _grid(p: Path, grid: object, base: Params) -> tuple[tuple[str, ...], list[tuple[Any, ...]]]:
    if not isinstance(grid, dict) or not grid:
        raise SweepError(f"{p}: grid: expected a mapping of parameter: [values], got {grid!r}")
    for name, values in grid.items():
        _leaf(p, "grid", base, name)
        if not isinstance(values, list) or not values:
            raise SweepError(
                f"{p}: grid: {name}: expected a non-empty list of values, got {values!r}"
            )
    return tuple(grid), list(itertools.product(*grid.values()))


def _random(p: Path, spec: object, base: Params) -> tuple[tuple[str, ...], list[tuple[Any, ...]]]:
    if not isinstance(spec, dict):
        raise SweepError(
            f"{p}: random: expected a mapping of samples, seed and parameters, got {spec!r}"
        )
    unknown = [k for k in spec if k not in RANDOM_KEYS]
    missing = [k for k in RANDOM_KEYS if k not in spec]
    if unknown or missing:
        raise SweepError(
            f"{p}: random: expected the keys {', '.join(RANDOM_KEYS)}; "
            + (f"unknown: {', '.join(map(str, unknown))}" if unknown else "")
            + ("; " if unknown and missing else "")
            + (f"missing: {', '.join(missing)}" if missing else "")
        )
    samples, seed, parameters = spec["samples"], spec["seed"], spec["parameters"]
    if not isinstance(samples, int) or isinstance(samples, bool) or samples < 1:
        raise SweepError(f"{p}: random: samples: expected an integer >= 1, got {samples!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise SweepError(f"{p}: random: seed: expected an integer >= 0, got {seed!r}")
    if not isinstance(parameters, dict) or not parameters:
        raise SweepError(
            f"{p}: random: parameters: expected a mapping of parameter: {{low, high}} or "
            f"{{choices}}, got {parameters!r}"
        )
    draws = [
        _sampler(p, name, how, _leaf(p, "random.parameters", base, name))
        for name, how in parameters.items()
    ]
    rng = np.random.default_rng(seed)
    combinations = [tuple(draw(rng) for draw in draws) for _ in range(samples)]
    return tuple(parameters), combinations


def _is_number(x: object) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _sampler(
    p: Path, name: str, how: object, current: object
) -> Callable[[np.random.Generator], object]:
    """How one parameter is drawn: uniformly from choices, or from [low, high], as integers
    (both ends included) for an integer parameter and uniformly in [low, high) otherwise."""
    where = f"{p}: random.parameters: {name}"
    if isinstance(how, dict) and set(how) == {"choices"}:
        choices = how["choices"]
        if not isinstance(choices, list) or not choices:
            raise SweepError(f"{where}: choices: expected a non-empty list, got {choices!r}")
        return lambda rng: choices[int(rng.integers(len(choices)))]
    if not (isinstance(how, dict) and set(how) == {"low", "high"}):
        raise SweepError(
            f"{where}: expected {{low: A, high: B}} or {{choices: [...]}}, got {how!r}"
        )
    low, high = how["low"], how["high"]
    if isinstance(current, bool) or not _is_number(current):
        raise SweepError(
            f"{where}: expected choices: [...] for a parameter that is no number "
            f"(it is {current!r}), got low and high"
        )
    if isinstance(current, int):
        if not all(isinstance(x, int) and not isinstance(x, bool) for x in (low, high)):
            raise SweepError(
                f"{where}: expected integer low and high for an integer parameter, "
                f"got low {low!r}, high {high!r}"
            )
        ilow, ihigh = cast(int, low), cast(int, high)
        if ilow > ihigh:
            raise SweepError(f"{where}: expected low <= high, got low {low!r}, high {high!r}")
        return lambda rng: int(rng.integers(ilow, ihigh, endpoint=True))
    if not (_is_number(low) and _is_number(high)):
        raise SweepError(f"{where}: expected numbers low and high, got low {low!r}, high {high!r}")
    flow, fhigh = float(cast(float, low)), float(cast(float, high))
    if flow > fhigh:
        raise SweepError(f"{where}: expected low <= high, got low {low!r}, high {high!r}")
    return lambda rng: float(rng.uniform(flow, fhigh))


def _parameter_set(
    p: Path, section: str, base: Params, names: Sequence[str], combination: Sequence[Any]
) -> ParameterSet:
    """The base with every value of one combination, applied at once (the parameters check
    some values against others, e.g. min_distance_m < max_distance_m)."""
    try:
        params = base.with_values(dict(zip(names, combination, strict=True)))
    except ParamsError as err:
        given = ", ".join(f"{n}={v!r}" for n, v in zip(names, combination, strict=True))
        raise SweepError(f"{p}: {section}: the set {given}: {err}") from None
    values = [(name, params.value_of(name)) for name in names]
    return ParameterSet(params_hash(params), tuple(values), params)


# --- the metric -----------------------------------------------------------------------------


def _flatten(prefix: str, value: object, out: dict[str, object]) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    elif not isinstance(value, list):
        out[prefix] = value


def _figure_names() -> dict[str, object]:
    """Every figure of `figures_json` of a total, by dotted name (of an empty report)."""
    zero = dataclasses.replace(
        empty(RecordingReport), pedestrians={k: empty(BoxScore) for k in PEDESTRIAN_STAGES}
    )
    flat: dict[str, object] = {}
    _flatten("", figures_json(zero, listings=False), flat)
    return {k: v for k, v in flat.items() if k not in NOT_METRICS}


def check_metric(metric: str) -> None:
    """SweepError when `metric` names no figure, listing the figures where its name goes
    wrong (groups of figures as `name.*`) and the nearest name."""
    names = list(_figure_names())
    if metric in names:
        return
    parts = metric.split(".")
    for depth in range(len(parts), -1, -1):
        prefix = ".".join(parts[:depth])
        under = [n for n in names if depth == 0 or n.startswith(prefix + ".")]
        if under:
            break
    shown = dict.fromkeys(
        ".".join(n.split(".")[: depth + 1]) + (".*" if n.count(".") > depth else "") for n in under
    )
    near = difflib.get_close_matches(metric, names, n=1)
    raise SweepError(
        f"{metric}: no such figure"
        + (f" (nearest: {near[0]})" if near else "")
        + f"; {'under ' + prefix if prefix else 'figures'}: {', '.join(shown)}"
    )


def metric_value(report: RecordingReport, metric: str) -> float | None:
    """The figure `metric` of `report` (None when undefined, e.g. a share of nothing)."""
    node: object = figures_json(report, listings=False)
    for part in metric.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return float(cast(float, node)) if _is_number(node) else None


# --- the results file -----------------------------------------------------------------------


@dataclass(frozen=True)
class TaskResult:
    """One line of the results file: one parameter set evaluated on one recording."""

    set_id: str
    values: dict[str, Any]
    recording: str  # as given to the sweep
    seconds: float  # the task's wall time on its worker
    report: RecordingReport


@dataclass(frozen=True)
class _Line:
    """A line of the results file as written (module docstring)."""

    format_version: int
    set: str
    values: dict[str, Any]
    recording: str
    seconds: float
    figures: dict[str, Any]
    report: RecordingReport


def recording_key(path: Path | str) -> str:
    """A recording as the results file names it: the path as given, without a trailing /."""
    return str(Path(path))


class ResultsFile:
    """The results file of a sweep, open for this process alone (a lock: two sweeps never
    append to one file). On entering, `results` holds what it has (module docstring: a last
    line cut short is dropped, with a note in `warnings`); `append` adds a line."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        self.results: list[TaskResult] = []
        self.warnings: list[str] = []
        self._file: IO[bytes] | None = None

    def __enter__(self) -> ResultsFile:
        if not self.path.parent.is_dir():
            raise SweepError(f"{self.path}: the folder {self.path.parent} does not exist")
        try:
            f = self.path.open("a+b")
        except OSError as err:
            raise SweepError(f"{self.path}: cannot open the results file: {err.strerror}") from err
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.close()
            raise SweepError(
                f"{self.path}: another sweep is writing this results file; wait for it to "
                "finish or give another --results"
            ) from None
        self._file = f
        try:
            self._read(f)
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()  # releases the lock
            self._file = None

    def _read(self, f: IO[bytes]) -> None:
        f.seek(0)
        lines = f.read().split(b"\n")
        tail = lines.pop()  # after the last end of line: b"" in a file written whole
        good_bytes = 0
        for number, line in enumerate(lines, start=1):
            if line.strip():
                self.results.append(self._parse(line, number))
            good_bytes += len(line) + 1
        if not tail.strip():
            return
        number = len(lines) + 1
        try:
            self.results.append(self._parse(tail, number))
        except SweepError:
            f.truncate(good_bytes)
            self.warnings.append(
                f"{self.path}: line {number} is cut short ({len(tail)} bytes without an end of "
                "line: a sweep stopped while writing it); dropped it, its task runs again"
            )
            return
        f.write(b"\n")  # a whole line that lacks its end of line: end it before appending

    def _parse(self, text: bytes, number: int) -> TaskResult:
        where = f"{self.path}: line {number}"
        try:
            raw = json.loads(text.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as err:
            raise SweepError(f"{where}: not a line of JSON: {err}; {_LEFT_AS_IT_IS}") from None
        keys = [f.name for f in dataclasses.fields(_Line)]
        if not isinstance(raw, dict) or set(raw) != set(keys):
            got = ", ".join(map(str, raw)) if isinstance(raw, dict) else type(raw).__name__
            raise SweepError(
                f"{where}: expected an object with the keys {', '.join(keys)}, got {got}; "
                f"{_LEFT_AS_IT_IS}"
            )
        try:
            line = decode(_Line, raw)
        except CodecError as err:
            raise SweepError(f"{where}: {err}; {_LEFT_AS_IT_IS}") from None
        if line.format_version != RESULTS_FORMAT_VERSION:
            raise SweepError(
                f"{where}: format_version: expected {RESULTS_FORMAT_VERSION}, got "
                f"{line.format_version}; {_LEFT_AS_IT_IS}"
            )
        return TaskResult(line.set, line.values, line.recording, line.seconds, line.report)

    def append(
        self, s: ParameterSet, recording: str, report: RecordingReport, seconds: float
    ) -> None:
        """Write one finished task's line and push it to disk before returning."""
        if self._file is None:
            raise RuntimeError("ResultsFile.append: the file is not open (use it in a with block)")
        values = dict(s.values)
        line = _Line(
            RESULTS_FORMAT_VERSION,
            s.id,
            values,
            recording,
            round(seconds, 3),
            figures_json(report, listings=False),
            report,
        )
        self._file.write((json.dumps(encode(line)) + "\n").encode("utf-8"))
        self._file.flush()
        os.fsync(self._file.fileno())
        self.results.append(TaskResult(s.id, values, recording, seconds, report))


_LEFT_AS_IT_IS = "the file is left as it is: mend or delete that line, or give another --results"


# --- the tasks ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Task:
    """One parameter set on one recording."""

    set: ParameterSet
    recording: str  # as the results file names it


def tasks(sweep: Sweep, recordings: Sequence[str]) -> list[Task]:
    """Every task of the sweep, one parameter set after the other."""
    return [Task(s, r) for s in sweep.sets for r in recordings]


def pending(all_tasks: Sequence[Task], results: Iterable[TaskResult]) -> list[Task]:
    """The tasks without a result."""
    done = {(r.set_id, r.recording) for r in results}
    return [t for t in all_tasks if (t.set.id, t.recording) not in done]


@dataclass(frozen=True)
class TaskOutcome:
    """What a task sends back: the report and the seconds it took, or why the recording
    could not be evaluated (it does not read, or has no ground truth)."""

    report: RecordingReport | None
    seconds: float
    error: str | None


def evaluate_task(recording: str, params: Params) -> TaskOutcome:
    """What a worker runs: one recording evaluated with one parameter set, untimed. At module
    level, so that Dask sends it by name. A fault of the recording comes back as an outcome
    (not an exception, which the worker would log with its traceback)."""
    started = time.perf_counter()
    try:
        report = evaluate_recording(recording, params, timing=False)
    except (RecordingError, ValueError, OSError) as err:
        return TaskOutcome(None, time.perf_counter() - started, str(err))
    return TaskOutcome(report, time.perf_counter() - started, None)


@contextlib.contextmanager
def connect(scheduler: str | None, workers: int) -> Iterator[Client]:
    """A Dask client: of a new LocalCluster of `workers` processes of one thread each (no
    dashboard), closed on leaving; or of the scheduler at the address `scheduler`
    (tcp://HOST:PORT), which is left running. SweepError when Dask is not installed or no
    scheduler answers there within CONNECT_TIMEOUT_S."""
    try:
        import distributed
    except ImportError as err:
        raise SweepError(
            "the sweep runs on Dask, which is not installed: pip install -e '.[cluster]' "
            "(or pip install 'dask[distributed]')"
        ) from err
    if scheduler is None:
        with (
            distributed.LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
                silence_logs=logging.ERROR,  # not the warnings of tasks cancelled on an error
            ) as cluster,
            distributed.Client(cluster) as client,
        ):
            yield client
        return
    client = _client(scheduler)
    try:
        yield client
    finally:
        client.close()


def _client(address: str) -> Client:
    """A client of the scheduler at `address`, connected in a thread of its own: a server
    that accepts the connection but speaks no Dask (say, a web server) would otherwise hold
    it for ever, past distributed's own timeout."""
    import distributed
    from distributed.comm.addressing import get_address_host_port

    try:  # the address's form, checked here: a loaded machine may not answer in time
        get_address_host_port(address)
    except ValueError as err:
        raise SweepError(
            f"--scheduler {address}: not a scheduler's address ({err}); expected tcp://HOST:PORT"
        ) from None
    box: dict[str, Any] = {}

    def attempt() -> None:
        try:
            box["client"] = distributed.Client(address, timeout=CONNECT_TIMEOUT_S)
        except Exception as err:  # shown to the user below, with the address
            box["error"] = err

    thread = threading.Thread(target=attempt, name="dask-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_TIMEOUT_S + 1.0)
    if "client" in box:
        return cast("Client", box["client"])
    why = f"{type(box['error']).__name__}: {box['error']}" if "error" in box else "no answer"
    raise SweepError(
        f"--scheduler {address}: no Dask scheduler answered within {CONNECT_TIMEOUT_S:g} s "
        f"({why}); expected tcp://HOST:PORT of a running `dask scheduler`"
    )


def run(
    client: Client,
    todo: Sequence[Task],
    results: ResultsFile,
    progress: Progress | None = None,
) -> None:
    """Run the tasks on the client's cluster and append each result to `results` as it
    finishes, whichever finishes first; tasks are started in the order given. A task that
    fails (a recording that does not read or has no ground truth) stops the sweep with a
    SweepError naming the recording and the set; what finished before stays in the file."""
    import distributed

    futures = {
        client.submit(
            evaluate_task,
            str(Path(t.recording).absolute()),
            t.set.params,
            pure=False,
            priority=len(todo) - k,
        ): t
        for k, t in enumerate(todo)
    }
    try:
        for done, future in enumerate(distributed.as_completed(list(futures)), start=1):
            task = futures.pop(future)
            where = f"{task.recording} with set {task.set.id}"
            try:
                outcome: TaskOutcome = future.result()
            except distributed.KilledWorker as err:  # e.g. out of memory, three times
                raise SweepError(f"{where}: {err}") from err
            if outcome.report is None:
                raise SweepError(f"{where}: {outcome.error}")
            results.append(task.set, task.recording, outcome.report, outcome.seconds)
            if progress is not None:
                progress(done, len(todo))
    finally:
        if futures:
            client.cancel(list(futures))


# --- ranking --------------------------------------------------------------------------------


@dataclass(frozen=True)
class FrameErrors:
    """A frame of one recording and how many errors it has."""

    recording: str  # the recording's name
    frame: int
    errors: int


@dataclass(frozen=True)
class RankedSet:
    """A parameter set's place: its total over the recordings it finished and its metric
    (None when undefined or none finished)."""

    rank: int
    set: ParameterSet
    recordings_done: int
    recordings: int
    metric: float | None
    total: RecordingReport | None
    worst_frames: tuple[FrameErrors, ...]

    @property
    def complete(self) -> bool:
        return self.recordings_done == self.recordings


def errors_at(r: RecordingReport) -> Iterator[int]:
    """The frame index of every error `fusionscope evaluate` lists under "Where the errors
    are" (`core.evaluation.evaluate.error_listings`), once per error."""
    for listing in error_listings(r):
        for frame, _ in listing.at:
            yield frame


def worst_frames(
    reports: Sequence[RecordingReport], n: int = WORST_FRAMES
) -> tuple[FrameErrors, ...]:
    """The `n` frames with the most errors (`errors_at`), most first, then in the recordings'
    and the frames' order."""
    counts: Counter[tuple[int, int]] = Counter()
    for k, r in enumerate(reports):
        counts.update((k, frame) for frame in errors_at(r))
    top = sorted(counts.items(), key=lambda item: (-item[1], item[0]))[:n]
    return tuple(FrameErrors(reports[k].name, frame, count) for (k, frame), count in top)


def rank(sweep: Sweep, recordings: Sequence[str], results: Iterable[TaskResult]) -> list[RankedSet]:
    """Every parameter set of the sweep ranked (module docstring) on the given recordings;
    results for other sets or recordings are left out, and of two for one task the first
    counts."""
    wanted = set(recordings)
    found: dict[tuple[str, str], RecordingReport] = {}
    for r in results:
        if r.recording in wanted:
            found.setdefault((r.set_id, r.recording), r.report)
    unranked = []
    for order, s in enumerate(sweep.sets):
        reports = [found[(s.id, rec)] for rec in recordings if (s.id, rec) in found]
        summed = total(reports) if reports else None
        value = metric_value(summed, sweep.metric) if summed is not None else None
        unranked.append((order, s, reports, summed, value))

    def key(
        item: tuple[int, ParameterSet, list[RecordingReport], Any, float | None],
    ) -> tuple[bool, bool, float, int]:
        order, _, reports, _, value = item
        incomplete = len(reports) < len(recordings)
        score = 0.0 if value is None else (-value if sweep.goal == "max" else value)
        return (incomplete, value is None, score, order)

    return [
        RankedSet(k, s, len(reports), len(recordings), value, summed, worst_frames(reports))
        for k, (_, s, reports, summed, value) in enumerate(sorted(unranked, key=key), start=1)
    ]


# --- output ---------------------------------------------------------------------------------


def _value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _metric(v: float | None) -> str:
    if v is None:
        return "-"
    return str(int(v)) if v.is_integer() else f"{v:.4f}"


def table(sweep: Sweep, ranked: Sequence[RankedSet], of: int) -> Table:
    """The ranked sets as a table for `report.format_text`; `of`: how many sets there are
    (more than shown when only the first are)."""
    goal = "highest" if sweep.goal == "max" else "lowest"
    recordings = ranked[0].recordings if ranked else 0
    shown = f"the first {len(ranked)} of {of} sets" if len(ranked) < of else f"{of} sets"
    notes = [
        "set: its id in the results file, a hash of every parameter value it runs with",
        "worst frames: recording:frame (errors: vehicle FN, RFN and FP, guard-rail FN and FP, "
        "pedestrians missed and false after the fusion filters)",
    ]
    if any(not r.complete for r in ranked):
        notes.append(
            "incomplete: not done on every recording; ranked after the complete sets, on the "
            "recordings done"
        )
    return Table(
        f"Parameter sets by {sweep.metric}, {goal} first, on the total of {recordings} "
        f"recordings ({shown})",
        ("rank", "set", *sweep.names, sweep.metric, "recordings", "worst frames"),
        tuple(
            (
                str(r.rank),
                r.set.id,
                *(_value(v) for _, v in r.set.values),
                _metric(r.metric),
                f"{r.recordings_done}/{r.recordings}" + ("" if r.complete else " incomplete"),
                ", ".join(f"{f.recording}:{f.frame} ({f.errors})" for f in r.worst_frames)
                or "none",
            )
            for r in ranked
        ),
        tuple(notes),
    )


def as_json(sweep: Sweep, ranked: Sequence[RankedSet], recordings: Sequence[str]) -> dict[str, Any]:
    """The ranked sets with their values, metric, worst frames and total figures."""
    return {
        "sweep": str(sweep.path),
        "metric": sweep.metric,
        "goal": sweep.goal,
        "recordings": list(recordings),
        "sets": [
            {
                "rank": r.rank,
                "set": r.set.id,
                "values": dict(r.set.values),
                "metric": r.metric,
                "complete": r.complete,
                "recordings_done": r.recordings_done,
                "worst_frames": [dataclasses.asdict(f) for f in r.worst_frames],
                "figures": None if r.total is None else figures_json(r.total, listings=False),
            }
            for r in ranked
        ],
    }
