"""How fast `fusionscope export-video` is on one core, by turns with another checkout; prints
the figures.

    python scripts/bench_export.py                                  # the bundled drives
    python scripts/bench_export.py --against ../old recordings/highway --runs 5

Each run times the reference kernel of `fusionscope bench` (its median: the machine's speed
at that moment, less is faster), then exports each recording with this checkout and, with
`--against`, with the other one just after it: each export a new process pinned to one CPU
(`--cpu`, default the last this process may use), so the figure includes the first frame's
set-up (numba's registries and its cached compiled functions), as a user's command pays it.
The figures are the ones the command prints: the export's time, its multiple of real time,
and that multiple after the first frame. This machine's speed moves two- to threefold from
hour to hour: compare checkouts in one sitting, and quote the kernel with the figures.

Prints, per recording and checkout, the range over the runs, then the range of the kernel
and the sum of each checkout's export times with their ratio.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
BUNDLED = ("recordings/highway", "recordings/exurban", "recordings/stop_and_go")
KERNEL_FRAMES, KERNEL_REPEAT = "5", "20"
# The last line export-video prints (app.video_export.format_summary).
SUMMARY = re.compile(
    r"in (?P<time_s>[0-9.]+) s: .*?(?P<real_time>[0-9.]+)x real time "
    r"\(.*the first frame (?P<first_s>[0-9.]+) s, after it (?P<steady>[0-9.]+)x real time\)"
)


@dataclass(frozen=True)
class Export:
    """One export's printed figures: seconds, multiple of real time, the same after the
    first frame, the first frame's seconds."""

    time_s: float
    real_time: float
    steady_real_time: float
    first_frame_s: float


def parse_summary(text: str) -> Export:
    """The figures of export-video's output `text`; ValueError quoting it when its summary
    line is missing."""
    found = SUMMARY.search(text)
    if found is None:
        raise ValueError(f"expected export-video's summary line (... in T s: ...), got {text!r}")
    return Export(
        float(found["time_s"]),
        float(found["real_time"]),
        float(found["steady"]),
        float(found["first_s"]),
    )


def _run(checkout: Path, args: Sequence[str], cpu: int) -> str:
    """`python -m core.cli ARGS` of `checkout`, pinned to `cpu`; its standard output.
    RuntimeError with its error output when it fails."""
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    done = subprocess.run(
        [sys.executable, "-m", "core.cli", *args],
        cwd=checkout,
        env=env,
        capture_output=True,
        text=True,
        preexec_fn=lambda: os.sched_setaffinity(0, {cpu}),
        check=False,
    )
    if done.returncode != 0:
        raise RuntimeError(
            f"{checkout}: fusionscope {' '.join(args)} failed ({done.returncode}): "
            f"{done.stderr.strip()[-2000:]}"
        )
    return done.stdout


def kernel_ms(cpu: int) -> float:
    """The reference kernel's median (ms) of `fusionscope bench`, this checkout, on `cpu`."""
    args = ["bench", "--stage", "pitch", "--frames", KERNEL_FRAMES, "--repeat", KERNEL_REPEAT]
    out = _run(HERE, [*args, "--format", "json"], cpu)
    return float(json.loads(out)["reference_kernel_ms"])


def export(checkout: Path, recording: Path, out_dir: Path, cpu: int) -> Export:
    """`recording` exported whole to an MP4 by `checkout` on `cpu`: its printed figures."""
    out = out_dir / f"{recording.name}.mp4"
    return parse_summary(_run(checkout, ["export-video", str(recording), str(out)], cpu))


def label(name: str, checkout: Path) -> str:
    """`name` and the checkout's commit ("this 1a2b3c4", "+" when it has changes), or `name`
    alone outside git."""
    git = ["git", "-C", str(checkout)]
    try:
        head = subprocess.run(
            [*git, "rev-parse", "--short", "HEAD"], capture_output=True, text=True
        )
        changes = subprocess.run(
            [*git, "status", "--porcelain", "--untracked-files=no"], capture_output=True, text=True
        )
    except FileNotFoundError:  # no git on this machine
        return name
    if head.returncode != 0:
        return name
    return f"{name} {head.stdout.strip()}{'+' if changes.stdout.strip() else ''}"


def _span(values: Sequence[float], fmt: str) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}}–{hi:{fmt}}"


def format_table(results: dict[tuple[str, str], list[Export]], kernels_ms: Sequence[float]) -> str:
    """Markdown: per (recording, checkout) the range of each figure over the runs; then the
    kernel's range and each checkout's total time, as a multiple of the first checkout's."""
    lines = [
        "| recording | checkout | time | x real time | after the first frame | first frame |",
        "| --- | --- | ---: | ---: | ---: | ---: |",
    ]
    for (recording, checkout), runs in results.items():
        lines.append(
            f"| {recording} | {checkout} | {_span([r.time_s for r in runs], '.2f')} s "
            f"| {_span([r.real_time for r in runs], '.1f')}x "
            f"| {_span([r.steady_real_time for r in runs], '.1f')}x "
            f"| {_span([r.first_frame_s for r in runs], '.2f')} s |"
        )
    totals: dict[str, float] = {}
    for (_, checkout), runs in results.items():
        totals[checkout] = totals.get(checkout, 0.0) + sum(r.time_s for r in runs)
    lines.append("")
    lines.append(f"reference kernel: {_span(kernels_ms, '.3f')} ms over {len(kernels_ms)} runs")
    first_checkout, first = next(iter(totals.items()))
    for checkout, total in totals.items():
        lines.append(
            f"{checkout}: {total:.2f} s in all ({total / first:.2f} x the time of {first_checkout})"
        )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0] if __doc__ else None,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "recordings", nargs="*", type=Path, help="recordings to export (default: the bundled)"
    )
    parser.add_argument("--runs", type=int, default=3, help="runs (default: 3)")
    parser.add_argument(
        "--against", type=Path, help="another checkout, exported just after this one each time"
    )
    parser.add_argument(
        "--cpu",
        type=int,
        default=max(os.sched_getaffinity(0)),
        help="the CPU every process is pinned to (default: the last this one may use)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    options = parser.parse_args(argv)
    if options.runs < 1:
        parser.error(f"--runs: expected at least 1, got {options.runs}")
    if options.cpu not in os.sched_getaffinity(0):
        parser.error(f"--cpu: expected one of {sorted(os.sched_getaffinity(0))}, got {options.cpu}")
    recordings = [p.resolve() for p in options.recordings] or [HERE / r for r in BUNDLED]
    missing = [str(p) for p in recordings if not p.is_dir()]
    if missing:
        parser.error(f"recordings: expected recording folders, got {', '.join(missing)}")
    checkouts = {label("this", HERE): HERE}
    if options.against is not None:
        against = options.against.resolve()
        if not (against / "core" / "cli.py").is_file():
            parser.error(f"--against: expected a fusionscope checkout, got {against}")
        checkouts[label("against", against)] = against
    try:
        results, kernels = _measure(recordings, checkouts, options.runs, options.cpu)
    except (RuntimeError, ValueError) as err:
        print(f"bench_export: {err}", file=sys.stderr)
        return 1
    print(format_table(results, kernels))
    return 0


def _measure(
    recordings: Sequence[Path], checkouts: dict[str, Path], runs: int, cpu: int
) -> tuple[dict[tuple[str, str], list[Export]], list[float]]:
    """`runs` times: the kernel, then each recording exported by each checkout in turn."""
    results: dict[tuple[str, str], list[Export]] = {
        (r.name, c): [] for r in recordings for c in checkouts
    }
    kernels: list[float] = []
    with tempfile.TemporaryDirectory(prefix="bench-export-") as out_dir:
        for run in range(1, runs + 1):
            kernels.append(kernel_ms(cpu))
            for recording in recordings:
                for name, checkout in checkouts.items():
                    figures = export(checkout, recording, Path(out_dir), cpu)
                    results[(recording.name, name)].append(figures)
                    print(
                        f"run {run}: {recording.name} {name} {figures.time_s:.2f} s, "
                        f"{figures.real_time:.1f}x (kernel {kernels[-1]:.3f} ms)",
                        file=sys.stderr,
                    )
    return results, kernels


if __name__ == "__main__":
    raise SystemExit(main())
