"""The `fusionscope` command: one entry point, one subcommand per job."""

from __future__ import annotations

import argparse
import gc
import math
import os
import sys
import textwrap
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from core.annotation.model import Track
    from core.io.drive import Drive
    from core.io.importers.calibration_spec import CalibrationSpec, IntrinsicsSpec
    from core.io.importers.can_mapping import CanSpec
    from core.io.importers.finish import ImportOptions, ImportResult
    from core.params import Params

DEFAULT_RECORDINGS = Path(__file__).resolve().parents[1] / "recordings"
DEFAULT_RECORDING = "highway"
PARAMS_HELP = "parameter file, or `papers` for the papers' pipeline (default: the defaults)"


class ProgressBar:
    """A one-line progress bar on stderr."""

    def __init__(self, label: str, width: int = 40) -> None:
        self.label = label
        self.width = width
        self._drawn = -1
        self.line_open = False  # drawn and not yet ended by its last step

    def __call__(self, done: int, total: int) -> None:
        filled = self.width * done // max(total, 1)
        if filled == self._drawn and done < total:
            return  # redrawn when the bar grows: a log of it stays short
        self._drawn = filled
        self.line_open = done < total
        bar = "#" * filled + "." * (self.width - filled)
        end = "\n" if done >= total else ""
        sys.stderr.write(f"\r{self.label} [{bar}] {done}/{total}{end}")
        sys.stderr.flush()


def _finite(text: str) -> float:
    """argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _positive(text: str) -> float:
    """argparse type: a finite number > 0."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def _non_negative(text: str) -> float:
    """argparse type: a finite number >= 0."""
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def _int_at_least(minimum: int) -> Callable[[str], int]:
    """argparse type: a whole number >= minimum."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {minimum}, got {text!r}")
        return value

    return parse


def _s_to_ns(seconds: float) -> int:
    return round(seconds * 1_000_000_000)


def _paragraph(text: str) -> str:
    """Help text wrapped for a parser whose epilog keeps its own line breaks."""
    return textwrap.fill(text, width=79, break_on_hyphens=False)


class _UsageError(Exception):
    """A combination of flags that does not go together; the message names them."""


def _check_out_folder(out: Path) -> None:
    """ValueError naming --out when the folder it would be written into does not exist."""
    if not out.parent.is_dir():
        raise ValueError(f"--out {out}: the folder {out.parent} does not exist")


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from core.calibrate import Chessboard, calibrate_chessboard, read_views
    from core.io.calibration import save_camera_info
    from core.io.errors import RecordingError

    out = Path(args.out)
    try:
        _check_out_folder(out)
        board = Chessboard.from_text(args.board, args.square_m)
        result = calibrate_chessboard(read_views(Path(args.folder)), board)
        save_camera_info(result.intrinsics, out, camera_name=Path(args.folder).resolve().name)
    except (ValueError, RecordingError, OSError) as err:
        print(f"fusionscope calibrate: {err}", file=sys.stderr)
        return 2
    i = result.intrinsics
    names = ("k1", "k2", "p1", "p2", "k3")
    print(
        f"views used: {len(result.used)} of {len(result.views)} "
        f"({board.cols}x{board.rows} inner corners, {board.square_m:g} m squares)"
    )
    for v in result.skipped:
        print(f"skipped: {v.name}: {v.skipped}")
    print(f"image size: {i.width_px}x{i.height_px} px")
    print(f"fx, fy: {i.fx_px:.2f}, {i.fy_px:.2f} px")
    print(f"cx, cy: {i.cx_px:.2f}, {i.cy_px:.2f} px")
    print(
        "distortion (plumb_bob): "
        + "  ".join(f"{n} {d:.5g}" for n, d in zip(names, i.distortion, strict=True))
    )
    print(f"RMS reprojection error: {result.rms_reprojection_px:.3f} px")
    print(f"wrote {out}")
    return 0


def _calibration_spec(args: argparse.Namespace) -> CalibrationSpec:
    from core.io.calibration import RadarMount
    from core.io.importers.calibration_spec import (
        CalibrationSpec,
        CameraInfoFile,
        FieldOfView,
        Pinhole,
    )

    given = [
        flag
        for flag, value in (
            ("--camera-info", args.camera_info),
            ("--hfov-deg", args.hfov_deg),
            ("--fx", args.fx),
        )
        if value is not None
    ]
    if len(given) != 1:
        raise _UsageError(
            "calibration: expected exactly one of --camera-info FILE, --hfov-deg D and "
            f"--fx FX [--fy --cx --cy], got {', '.join(given) or 'none'}"
        )
    extra = [
        f for f, v in (("--fy", args.fy), ("--cx", args.cx), ("--cy", args.cy)) if v is not None
    ]
    if extra and args.fx is None:
        raise _UsageError(f"{', '.join(extra)}: only with --fx")
    intrinsics: IntrinsicsSpec
    if args.camera_info is not None:
        intrinsics = CameraInfoFile(Path(args.camera_info))
    elif args.hfov_deg is not None:
        intrinsics = FieldOfView(args.hfov_deg)
    else:
        intrinsics = Pinhole(args.fx, args.fy, args.cx, args.cy)
    radar = [
        f
        for f, v in (
            ("--radar-y-m", args.radar_y_m),
            ("--radar-z-m", args.radar_z_m),
            ("--radar-yaw-rad", args.radar_yaw_rad),
        )
        if v is not None
    ]
    if radar and args.radar_x_m is None:
        raise _UsageError(f"{', '.join(radar)}: only with --radar-x-m")
    mount = None
    if args.radar_x_m is not None:
        mount = RadarMount(
            args.radar_x_m, args.radar_y_m or 0.0, args.radar_z_m or 0.0, args.radar_yaw_rad or 0.0
        )
    return CalibrationSpec(
        intrinsics,
        camera_height_m=args.camera_height_m,
        camera_x_m=args.camera_x_m,
        pitch_rad=args.pitch_rad,
        yaw_rad=args.yaw_rad,
        radar_mount=mount,
    )


def _can_spec(args: argparse.Namespace, from_bag: bool) -> CanSpec | None:
    from core.io.importers.can_mapping import CanSpec

    log = getattr(args, "can", None)
    topic = getattr(args, "can_topic", None)
    given = {"--can": log, "--can-topic": topic, "--dbc": args.dbc, "--mapping": args.mapping}
    named = [flag for flag, value in given.items() if value]
    if not named:
        return None
    missing = [f for f in ("--dbc", "--mapping") if not given[f]]
    if not from_bag and log is None:
        missing.insert(0, "--can")
    if missing:
        raise _UsageError(
            f"{', '.join(named)}: CAN input also needs {', '.join(missing)} "
            "(the log, its DBC files and the mapping of signals)"
        )
    if log is not None and topic is not None:
        raise _UsageError(f"--can {log}, --can-topic {topic}: expected one CAN source")
    return CanSpec(
        dbc=tuple(Path(d) for d in args.dbc),
        mapping=Path(args.mapping),
        log=Path(log) if log is not None else None,
        bag_topic=topic,
    )


def _options(args: argparse.Namespace) -> ImportOptions:
    from core.io.importers.finish import ImportOptions
    from core.io.manifest import Assumptions

    return ImportOptions(
        name=args.name,
        assumptions=Assumptions(args.assume_speed_mps, args.assume_yaw_rate_radps),
        max_radar_skew_ms=args.max_radar_skew_ms,
        ego_from_radar=args.ego_from_radar,
    )


def _report(result: ImportResult, seconds: float) -> None:
    span_s = (result.last_t_ns - result.first_t_ns) / 1e9
    print(
        f"{result.out_dir}: {result.frames} frames, {result.width_px}x{result.height_px}, "
        f"stamps {result.first_t_ns / 1e9:.3f} to {result.last_t_ns / 1e9:.3f} s "
        f"({span_s:.1f} s), in {seconds:.1f} s"
    )
    for note in result.notes:
        print(f"note: {note}")


def _cmd_import(args: argparse.Namespace) -> int:
    from core.io.errors import RecordingError
    from core.io.importers.bag import import_bag
    from core.io.importers.still import import_still
    from core.io.importers.video import VideoSampling, import_video

    command = f"fusionscope import {args.kind}"
    started = time.monotonic()
    try:
        calibration = _calibration_spec(args)
        can_spec = _can_spec(args, from_bag=args.kind == "bag")
        options = _options(args)
        out = Path(args.out_dir)
        if args.kind == "video":
            if can_spec is not None and args.video_start_s is None:
                raise _UsageError(
                    "--video-start-s: required with --can: the CAN-clock time (s) of the "
                    "video's first frame"
                )
            if can_spec is None and args.video_start_s is not None:
                raise _UsageError("--video-start-s: only with --can; without CAN use --start-ns")
            if can_spec is not None and args.start_ns is not None:
                raise _UsageError("--start-ns: with --can give --video-start-s instead")
            if args.to_s is not None and args.to_s <= args.from_s:
                raise _UsageError(
                    f"--to-s {args.to_s:g}: expected a time after --from-s {args.from_s:g}"
                )
            start_ns = (
                _s_to_ns(args.video_start_s)
                if args.video_start_s is not None
                else args.start_ns or 0
            )
            sampling = VideoSampling(args.width, args.fps, start_ns, args.from_s, args.to_s)
            result = import_video(
                Path(args.source),
                out,
                calibration,
                sampling,
                can_spec,
                options,
                progress=ProgressBar("import video"),
            )
        elif args.kind == "still":
            if can_spec is not None and args.time_s is None:
                raise _UsageError(
                    "--time-s: required with --can: the CAN-clock time (s) of the image"
                )
            t_ns = _s_to_ns(args.time_s) if args.time_s is not None else 0
            result = import_still(
                Path(args.source), out, t_ns, calibration, args.width, can_spec, options
            )
        else:
            result = import_bag(
                Path(args.source),
                out,
                calibration,
                args.camera_topic,
                args.radar_topic,
                can_spec,
                options,
                progress=ProgressBar("copy bag"),
            )
    except (_UsageError, ValueError, RecordingError, OSError) as err:
        print(f"{command}: {err}", file=sys.stderr)
        return 2
    _report(result, time.monotonic() - started)
    return 0


def _cmd_import_dataset(args: argparse.Namespace) -> int:
    """`import nuscenes` and `import aimotive`: a data set's scene or sequence."""
    from core.io.errors import RecordingError
    from core.io.importers.finish import ImportOptions

    command = f"fusionscope import {args.kind}"
    started = time.monotonic()
    try:
        options = ImportOptions(name=args.name)
        if args.kind == "nuscenes":
            from core.io.importers.nuscenes import import_nuscenes

            radars = tuple(r.strip() for r in args.radars.split(",") if r.strip())
            result = import_nuscenes(
                Path(args.source),
                Path(args.out_dir),
                args.scene,
                args.version,
                args.camera,
                radars,
                args.width,
                options,
                progress=ProgressBar("import nuscenes"),
            )
        else:
            from core.io.importers.aimotive import import_aimotive

            result = import_aimotive(
                Path(args.source),
                Path(args.out_dir),
                args.camera,
                args.radar,
                args.width,
                options,
                progress=ProgressBar("import aimotive"),
            )
    except (ValueError, RecordingError, OSError) as err:
        print(f"{command}: {err}", file=sys.stderr)
        return 2
    _report(result, time.monotonic() - started)
    return 0


def _frames_text(ranges: Sequence[tuple[int, int]]) -> str:
    """'20 (0-19)' for the frames of inclusive (first, last) ranges; 'none' without any."""
    if not ranges:
        return "none"
    count = sum(b - a + 1 for a, b in ranges)
    return f"{count} ({', '.join(f'{a}-{b}' if b > a else str(a) for a, b in ranges)})"


def _export_annotations(args: argparse.Namespace, frame_count: int, size: tuple[int, int]) -> str:
    """`annotations export`: the store's annotations (journal replayed, nothing written
    into the recording) to OUT; the lines to print."""
    from core.annotation.formats import export_command
    from core.annotation.store import AnnotationStore, read_annotations
    from core.io.errors import RecordingError

    out: Path = args.out
    if out.is_dir():
        raise ValueError(f"OUT {out}: expected a file to write, got a folder")
    if not out.parent.is_dir():
        raise ValueError(f"OUT {out}: the folder {out.parent} does not exist")
    with AnnotationStore(args.recording, writable=False) as store:
        if store.path.exists():
            # a store opened read-only shows no annotations when its file holds none it can
            # read, and says only "opened for reading only": the file's own error is wanted
            try:
                read_annotations(store.path)
            except RecordingError as err:
                raise RecordingError(f"{err}; nothing was exported") from err
        annotations, revision = store.snapshot()
    text = export_command(
        annotations,
        out,
        args.format,
        frame_count=frame_count,
        image_size_px=size,
        keyframes_only=args.keyframes_only,
    )
    return f"{text}\nfrom {store.path} (revision {revision})"


def _import_annotations(args: argparse.Namespace, frame_count: int) -> tuple[str, str | None]:
    """`annotations import`: FILE into the store as one edit; the lines to print and a
    warning (None: none)."""
    from core.annotation.formats import import_command
    from core.annotation.store import AnnotationStore, Edit, ReadOnlyError

    imported, read = import_command(args.file, args.format, frame_count=frame_count)
    with AnnotationStore(args.recording) as store:
        if store.read_only_reason is not None:
            raise ReadOnlyError(f"{store.read_only_reason}; nothing was imported")
        before, revision = store.snapshot()
        if (before.tracks or before.annotated) and not args.replace:
            raise _UsageError(
                f"--replace: {store.path} already holds {len(before.tracks)} tracks and "
                f"{_frames_text(before.annotated)} frames marked annotated: expected none, or "
                f"--replace to replace them all with {args.file}'s; nothing was imported"
            )
        tracks: dict[int, Track | None] = {t.id: None for t in before.tracks}
        tracks.update({t.id: t for t in imported.tracks})
        ranges = [(a, b, False) for a, b in before.annotated]
        ranges += [(a, b, True) for a, b in imported.annotated]
        if not tracks and not ranges:
            return f"{read}\nnothing to save: {store.path} is unchanged", None
        edit = Edit(revision, tracks, tuple(ranges), f"import {args.file}")
        saved = store.apply(edit)
        warning = store.save_error
    keyframes = sum(len(t.keyframes) for t in imported.tracks)
    replaced = (
        f"; replaced {len(before.tracks)} tracks and {_frames_text(before.annotated)} "
        "frames marked annotated"
        if before.tracks or before.annotated
        else ""
    )
    return (
        f"{read}\n{store.path}: revision {saved}: {len(imported.tracks)} tracks, {keyframes} "
        f"keyframes, {_frames_text(imported.annotated)} frames marked annotated{replaced}",
        warning,
    )


def _cmd_annotations(args: argparse.Namespace) -> int:
    from core.annotation.store import EditError
    from core.io.drive import Drive
    from core.io.errors import RecordingError

    command = f"fusionscope annotations {args.action}"
    warning = None
    try:
        with Drive(args.recording) as drive:
            frame_count = len(drive)
            i = drive.camera.intrinsics
            size = (i.width_px, i.height_px)
        if args.action == "export":
            text = _export_annotations(args, frame_count, size)
        else:
            text, warning = _import_annotations(args, frame_count)
    except (_UsageError, ValueError, RecordingError, EditError, OSError) as err:
        print(f"{command}: {err}", file=sys.stderr)
        return 2
    print(text)
    if warning is not None:
        print(f"{command}: warning: {warning}", file=sys.stderr)
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    from core.io.diagnostics import drive_report, format_report
    from core.io.drive import Drive
    from core.io.errors import RecordingError

    try:
        with Drive(args.recording, use_cache=not args.no_cache) as drive:
            print(format_report(drive_report(drive)))
    except RecordingError as err:
        print(f"fusionscope info: {err}", file=sys.stderr)
        return 2
    return 0


def _say_warnings(command: str, name: str, warnings: tuple[str, ...], strict: bool) -> None:
    """Print what was skipped or repaired on reading recording `name` to stderr; with
    `strict`, refuse it instead (RecordingError)."""
    from core.io.errors import RecordingError

    if strict and warnings:
        raise RecordingError(
            f"{name}: --strict: refused, reading it gave {len(warnings)} warning(s): "
            + "; ".join(warnings)
        )
    for warning in warnings:
        print(f"{command}: warning: {name}: {warning}", file=sys.stderr)


def _say_skipped(
    command: str, name: str, skipped: tuple[tuple[int, str], ...], frame_count: int
) -> None:
    """Print, at the end, the frames of recording `name` that could not be read and were
    skipped (each with why) to stderr."""
    if not skipped:
        return
    print(
        f"{command}: warning: {name}: skipped {len(skipped)} of {frame_count} frame(s) that "
        "could not be read (--strict stops at the first):",
        file=sys.stderr,
    )
    for index, why in skipped:
        print(f"  frame {index}: {why}", file=sys.stderr)


def _cmd_run(args: argparse.Namespace) -> int:
    from core.io.drive import Drive
    from core.io.errors import RecordingError
    from core.params import params_from
    from core.results import write_results

    out_path: Path | None = args.out
    try:
        params = params_from(args.params)
        if out_path is not None:
            _check_out_folder(out_path)
        with Drive(args.recording) as drive:
            _say_warnings("fusionscope run", drive.path.name, drive.warnings, args.strict)
            progress = ProgressBar(f"run {drive.path.name}")
            partial = None if out_path is None else out_path.with_name(out_path.name + ".partial")
            sink = sys.stdout if partial is None else partial.open("w", encoding="utf-8")
            try:
                skipped = write_results(drive, drive.camera, params, sink, progress, args.strict)
            except BaseException:
                if partial is not None:  # a complete file or none: never half a drive
                    partial.unlink(missing_ok=True)
                raise
            finally:
                if sink is not sys.stdout:
                    sink.close()
            if partial is not None and out_path is not None:
                partial.replace(out_path)
    except (RecordingError, ValueError, OSError) as err:
        written = f"; nothing written to {out_path}" if out_path is not None else ""
        print(f"fusionscope run: {err}{written}", file=sys.stderr)
        return 2
    _say_skipped("fusionscope run", drive.path.name, skipped, len(drive))
    return 0


def _cmd_evaluate(args: argparse.Namespace) -> int:
    import json

    from core.evaluation import report
    from core.evaluation.evaluate import evaluate_recording, total
    from core.io.drive import Drive
    from core.io.errors import RecordingError
    from core.params import ParamsError, params_from

    try:
        if args.compare is not None and args.format not in ("table", "markdown"):
            raise ValueError(f"--compare: prints a table or markdown, not {args.format}")
        params = params_from(args.params)
        other = params_from(args.compare) if args.compare is not None else None
        reports, others = [], []
        for path in args.recordings:
            if args.strict:
                with Drive(path) as drive:
                    _say_warnings("fusionscope evaluate", path.name, drive.warnings, strict=True)
            bar = ProgressBar(f"evaluate {path.name}")
            reports.append(
                evaluate_recording(path, params, bar, baselines=args.baselines, strict=args.strict)
            )
            _say_warnings("fusionscope evaluate", path.name, reports[-1].warnings, strict=False)
            if other is not None:
                bar = ProgressBar(f"evaluate {path.name} ({args.compare})")
                others.append(evaluate_recording(path, other, bar, timing=False))
    except (RecordingError, ParamsError, ValueError, OSError) as err:
        print(f"fusionscope evaluate: {err}", file=sys.stderr)
        return 2
    if other is not None:
        names = (args.params or "defaults", args.compare)
        table = report.comparison(names, (reports, others))
        if args.format == "markdown":
            sys.stdout.write(report.format_markdown([table]))
        else:
            sys.stdout.write(report.format_text([table]))
        return 0
    summed = total(reports)
    if args.format == "json":
        print(json.dumps(report.as_json(reports, summed), indent=1))
    elif args.format == "csv":
        sys.stdout.write(report.format_csv(reports, summed))
    elif args.format == "markdown":
        # the summary tables only: the error listings are for the table format and JSON
        sys.stdout.write(report.format_markdown(report.tables(reports, summed, listings=False)))
    else:
        sys.stdout.write(report.format_text(report.tables(reports, summed)))
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from core.bench import STAGES, bench, format_json, format_table
    from core.io.errors import RecordingError
    from core.params import ParamsError, params_from

    stages = args.stage or STAGES
    try:
        params = params_from(args.params)
    except (ParamsError, OSError) as err:
        print(f"fusionscope bench: --params: {err}", file=sys.stderr)
        return 2
    try:
        report = bench(stages, args.recording, params, frames=args.frames, repeat=args.repeat)
    except RecordingError as err:
        print(f"fusionscope bench: --recording: {err}", file=sys.stderr)
        return 2
    except ValueError as err:
        print(f"fusionscope bench: {err}", file=sys.stderr)
        return 2
    out = format_json if args.format == "json" else format_table
    print(out(report))
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    import json

    from core import sweep
    from core.evaluation.report import format_text
    from core.io.errors import RecordingError

    command = "fusionscope sweep"
    if args.scheduler is not None and args.workers is not None:
        print(
            f"{command}: --workers: only without --scheduler (a running cluster has its own)",
            file=sys.stderr,
        )
        return 2
    workers = args.workers or sweep.DEFAULT_WORKERS
    bar = ProgressBar("sweep")
    running = False  # the bar's line is open
    try:
        if args.metric is not None:
            try:
                sweep.check_metric(args.metric)
            except sweep.SweepError as err:
                raise sweep.SweepError(f"--metric: {err}") from None
        spec = sweep.load_sweep(args.sweep, args.metric, args.goal)
        recordings = list(dict.fromkeys(sweep.recording_key(r) for r in args.recordings))
        every = sweep.tasks(spec, recordings)
        with sweep.ResultsFile(args.results) as results:
            for warning in results.warnings:
                print(f"{command}: warning: {warning}", file=sys.stderr)
            todo = sweep.pending(every, results.results)
            done = len(every) - len(todo)
            wanted = {(t.set.id, t.recording) for t in every}
            others = sum((r.set_id, r.recording) not in wanted for r in results.results)
            on = args.scheduler or f"a local cluster of {workers} workers"
            print(
                f"{command}: {len(spec.sets)} parameter sets x {len(recordings)} recording(s) = "
                f"{len(every)} tasks; {done} already in {results.path}"
                + (f" (and {others} of other sets or recordings, left out)" if others else "")
                + f", {len(todo)} to run"
                + (f" on {on}" if todo else ""),
                file=sys.stderr,
            )
            if todo:
                with sweep.connect(args.scheduler, workers) as client:
                    running = True
                    bar(done, len(every))
                    sweep.run(client, todo, results, lambda k, n: bar(done + k, done + n))
                running = False
            ranked = sweep.rank(spec, recordings, results.results)
    except KeyboardInterrupt:
        print(
            f"\n{command}: interrupted; the finished tasks are in {args.results}: the same "
            "command resumes",
            file=sys.stderr,
        )
        return 130
    except (ValueError, RecordingError, OSError) as err:
        print(("\n" if running else "") + f"{command}: {err}", file=sys.stderr)
        return 2
    shown = ranked[: args.top]
    if args.format == "json":
        print(json.dumps(sweep.as_json(spec, shown, recordings), indent=1))
    else:
        sys.stdout.write(format_text([sweep.table(spec, shown, len(ranked))]))
    return 0


def _cmd_synth(args: argparse.Namespace) -> int:
    from core.io.errors import RecordingError
    from core.synth.generate import generate

    try:
        out = generate(
            args.scenario,
            args.seconds,
            args.seed,
            args.out_dir,
            progress=ProgressBar(f"synth {args.scenario}"),
        )
    except (ValueError, RecordingError) as err:
        print(f"fusionscope synth: {err}", file=sys.stderr)
        return 2
    print(out)
    return 0


# --- export-video, export-scene: a clip of a drive, exported (app.video_export, app.snapshot)

SCENE_SUFFIX = ".html"
# (drive, its clip's frames, set A, set B or None, progress) -> the summary line printed
ClipWriter = Callable[["Drive", range, "Params", "Params | None", ProgressBar], str]


def _clip_frames(args: argparse.Namespace, times_ns: Sequence[int], where: Path) -> range:
    """The frames of a drive (camera stamps `times_ns`, read from `where`) from --from to
    --to, seconds from its first frame, both included (default: the whole drive)."""
    offsets_ns = [int(t) - int(times_ns[0]) for t in times_ns]
    end_s = offsets_ns[-1] / 1e9
    from_s = 0.0 if args.from_s is None else args.from_s
    to_s = end_s if args.to_s is None else args.to_s
    for flag, value in (("--from", from_s), ("--to", to_s)):
        if _s_to_ns(value) > offsets_ns[-1]:
            raise _UsageError(
                f"{flag} {value:g}: expected seconds from the first frame of {where}, from 0 "
                f"to {end_s:g} (its last frame)"
            )
    if from_s > to_s:
        raise _UsageError(f"--from {from_s:g}, --to {to_s:g}: expected --from before --to")
    frames = [i for i, t in enumerate(offsets_ns) if _s_to_ns(from_s) <= t <= _s_to_ns(to_s)]
    if not frames:
        raise _UsageError(
            f"--from {from_s:g}, --to {to_s:g}: no frame of {where} between them; widen the clip"
        )
    return range(frames[0], frames[-1] + 1)


def _export_clip(
    args: argparse.Namespace, verb: str, write: ClipWriter, errors: tuple[type[Exception], ...] = ()
) -> int:
    """Export the clip --from/--to of RECORDING under --params (and --ab) with `write`, a
    progress bar on stderr; what fails is said as `fusionscope {verb}: ...` (exit 2), Ctrl-C
    exits 130."""
    from core.io.drive import Drive
    from core.io.errors import RecordingError
    from core.params import Params, params_from

    command = f"fusionscope {verb}"
    failures: tuple[type[Exception], ...] = (_UsageError, ValueError, RecordingError, OSError)
    failures += errors
    bar = ProgressBar(f"{verb} {Path(args.recording).name}")
    try:
        sets = []
        for flag, path in (("--params", args.params), ("--ab", args.ab)):
            try:
                sets.append(params_from(path) if path else None)
            except ValueError as err:
                raise _UsageError(f"{flag}: {err}") from err
        with Drive(args.recording) as drive:
            clip = _clip_frames(args, drive.times_ns.tolist(), drive.path)
            summary = write(drive, clip, sets[0] or Params(), sets[1], bar)
    except failures as err:
        print(("\n" if bar.line_open else "") + f"{command}: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(
            ("\n" if bar.line_open else "") + f"{command}: interrupted; nothing written to "
            f"{args.out}",
            file=sys.stderr,
        )
        return 130
    print(summary)
    return 0


def _cmd_export_scene(args: argparse.Namespace) -> int:
    import contextlib
    import io

    from app.snapshot import bird_eye_snapshot_html
    from core.checks import output_suffix

    out: Path = args.out

    def write(
        drive: Drive, clip: range, params: Params, params_b: Params | None, bar: ProgressBar
    ) -> str:
        output_suffix("OUT", out, (SCENE_SUFFIX,))
        # viser prints a banner for its private recording server; it is nobody's business
        with contextlib.redirect_stdout(io.StringIO()):
            html = bird_eye_snapshot_html(drive, clip[0], clip[-1], params, params_b, bar)
        partial = out.with_name(out.name + ".partial")
        try:
            partial.write_text(html, encoding="utf-8", newline="")
            partial.replace(out)  # a complete page or none
        finally:
            partial.unlink(missing_ok=True)
        start_ns = int(drive.times_ns[0])
        first_s, last_s = ((int(drive.times_ns[k]) - start_ns) / 1e9 for k in (clip[0], clip[-1]))
        return (
            f"{out}: {len(clip)} frames, {first_s:.2f} to {last_s:.2f} s of {args.recording}"
            + (" (A and B beside it)" if params_b is not None else "")
            + f", {out.stat().st_size / 1e6:.1f} MB"
        )

    return _export_clip(args, "export-scene", write)


def _cmd_export_video(args: argparse.Namespace) -> int:
    from app.video_export import ExportError, export_video, layers_named, summary_text, video_format
    from core.bench import one_thread
    from core.malloc import keep_freed_memory

    def write(
        drive: Drive, clip: range, params: Params, params_b: Params | None, bar: ProgressBar
    ) -> str:
        keep_freed_memory()  # a process of its own: its frames reuse the memory they free
        # and what it has made so far (modules, the drive's index) lives to its end: the
        # garbage collector stops walking it (on highway, 20 ms of collection instead of 100)
        gc.freeze()
        fmt = video_format(args.out, "OUT")
        if args.gif_width is not None and fmt != "gif":
            raise _UsageError(f"--gif-width: only for a .gif OUT, got {args.out}")
        try:
            layers = None if args.layers is None else layers_named(args.layers)
        except ValueError as err:
            raise _UsageError(f"--layers {args.layers}: {err}") from err
        with one_thread():  # and the encoder on one: the speed printed is one core's
            summary = export_video(
                drive, args.out, clip[0], clip[-1], layers, params, params_b, bar, args.gif_width
            )
        return summary_text(summary)

    return _export_clip(args, "export-video", write, (ExportError,))


def _clip_args(p: argparse.ArgumentParser) -> None:
    """RECORDING, OUT and the clip's and parameter sets' options of an export."""
    p.add_argument("recording", type=Path, metavar="RECORDING", help="a recording folder")
    p.add_argument(
        "--from",
        dest="from_s",
        metavar="T",
        type=_non_negative,
        help="start of the clip, seconds from the drive's first frame (default: 0)",
    )
    p.add_argument(
        "--to",
        dest="to_s",
        metavar="T",
        type=_non_negative,
        help="end of the clip, seconds from the drive's first frame, included (default: the "
        "last frame)",
    )
    p.add_argument("--params", metavar="FILE", help=PARAMS_HELP)
    p.add_argument(
        "--ab",
        type=Path,
        metavar="FILE",
        help="parameter file of a set B drawn beside the first (A/B compare)",
    )


def _add_export_scene(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    scene = sub.add_parser(
        "export-scene",
        help="save a clip's 3D bird's-eye scene as one HTML page that plays without a server",
        description=_paragraph(
            "Run the fusion engine over the clip (as the inspector plays it: the drive "
            "is played from its start up to --from first) and record its 3D bird's-eye "
            "view (the road texture, radar targets, vehicles, tracks, the ego car) frame "
            "after frame, at the "
            "drive's own pace, in one self-contained HTML page: open it in a browser, no "
            "server and no network needed; it loops over the clip. With --ab, a second "
            "parameter set's view beside it, as the inspector compares them. The page is "
            "about 0.8 MB plus 13 KB a frame (a bundled 15 s drive: 2.8 MB)."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _clip_args(scene)
    scene.add_argument(
        "out", type=Path, metavar="OUT.html", help="the page to write (replaced whole)"
    )
    scene.set_defaults(func=_cmd_export_scene)


def _add_export_video(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    video = sub.add_parser(
        "export-video",
        help="render a clip with its overlays to an .mp4 video or an animated .gif",
        description=_paragraph(
            "Run the fusion engine over the clip (as the inspector shows it: the drive "
            "is played from its start up to --from first) and write every frame's camera "
            "picture with the overlay layers chosen, over a banner: the recording, the "
            "time from the "
            "drive's first frame, the frame's index, the parameter set's hash, and what the "
            "colours mean. .mp4: H.264 at the drive's frame rate, plays in browsers while it "
            "loads; .gif: an animated GIF for slides, scaled down. With --ab, a second "
            "parameter set's picture beside the first, as the inspector compares them. OUT "
            "is written whole at the end (OUT.partial until then)."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _clip_args(video)
    video.add_argument(
        "out", type=Path, metavar="OUT", help="the .mp4 or .gif to write (replaced whole)"
    )
    video.add_argument(
        "--layers",
        metavar="NAMES",
        help="comma-separated overlays to draw, the others off, e.g. radar,vehicles,guardrails "
        "(a name not known lists them all; default: what was found and confirmed over "
        "frames: confirmed, the confirmed tracks measured in each frame, with their ids)",
    )
    video.add_argument(
        "--gif-width",
        type=_int_at_least(16),
        metavar="PX",
        help="width of a .gif (default: 480 px per camera picture)",
    )
    video.set_defaults(func=_cmd_export_video)


LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
# where the inspector keeps parameter presets: the user's data folder, not the project
DEFAULT_PRESETS = (
    Path(os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share")
    / "fusionscope"
    / "presets"
)


def _cmd_serve(args: argparse.Namespace) -> int:
    from app.access import Access, new_token
    from app.server import serve
    from core.io.manifest import MANIFEST_NAME
    from core.malloc import keep_freed_memory

    # its render workers draw frame after frame: the motion stereo picture took 5 ms and
    # 1,900 page faults a frame without, 0.45 ms and none with (core.malloc)
    keep_freed_memory()

    root = Path(args.recordings)
    if not root.is_dir():
        print(
            f"fusionscope serve: --recordings {root}: expected a folder of recordings, "
            "it does not exist",
            file=sys.stderr,
        )
        return 2
    if args.host not in LOOPBACK_HOSTS:
        who = (
            "anyone who can reach this port"
            if args.no_token
            else "anyone who has the printed URL (its token travels unencrypted over http)"
        )
        print(
            f"fusionscope serve: warning: --host {args.host} lets other machines reach the "
            f"inspector: {who} can see the recordings and change the parameters",
            file=sys.stderr,
        )
    access = Access(
        token=None if args.no_token else new_token(),
        allowed_hosts=frozenset(name.lower() for name in [args.host, *args.allow_host]),
    )
    try:
        recording = args.recording
        if recording is None and (root / DEFAULT_RECORDING / MANIFEST_NAME).is_file():
            recording = DEFAULT_RECORDING
        max_upload_bytes = round(args.max_upload_mb * 2**20)
        if max_upload_bytes <= 0:
            raise ValueError(f"--max-upload-mb: expected a positive size, got {args.max_upload_mb}")
        serve(
            root,
            recording,
            args.host,
            args.port,
            Path(args.presets),
            args.present,
            access,
            max_upload_bytes,
        )
    except ValueError as err:
        print(f"fusionscope serve: {err}", file=sys.stderr)
        return 2
    return 0


def _image_size_args(p: argparse.ArgumentParser) -> None:
    from core.io.importers.finish import DEFAULT_WIDTH_PX

    p.add_argument(
        "--width",
        metavar="PX",
        type=_int_at_least(1),
        default=DEFAULT_WIDTH_PX,
        help="output width in px; the height follows the aspect ratio (default: %(default)s, "
        "paper 001)",
    )


def _can_args(p: argparse.ArgumentParser, from_bag: bool) -> None:
    g = p.add_argument_group("CAN (speed, yaw rate, radar tracks)")
    g.add_argument(
        "--can",
        metavar="LOG",
        help="CAN log (.blf .asc .log .trc .csv, also .gz), copied into the recording"
        + ("; without it, the bag's can_msgs/Frame topic" if from_bag else ""),
    )
    if from_bag:
        g.add_argument(
            "--can-topic", metavar="TOPIC", help="the bag's CAN topic (default: the only one)"
        )
    g.add_argument(
        "--dbc", action="append", help="DBC file decoding the CAN frames; repeat for several"
    )
    g.add_argument(
        "--mapping",
        metavar="MAPPING.yaml",
        help="which DBC signals are speed, yaw rate and radar fields: `can:` and/or `radar:` "
        "sections as in recording.yaml, without log/dbc (example below)",
    )


def _common_import_args(p: argparse.ArgumentParser) -> None:
    from core.io.importers.calibration_spec import DEFAULT_CAMERA_HEIGHT_M, DEFAULT_CAMERA_X_M

    g = p.add_argument_group("camera intrinsics (exactly one way)")
    g.add_argument(
        "--camera-info", metavar="FILE", help="ROS camera_info YAML (as calibrate writes)"
    )
    g.add_argument(
        "--hfov-deg",
        metavar="DEG",
        type=_positive,
        help="horizontal field of view: centred pinhole",
    )
    g.add_argument(
        "--fx", metavar="PX", type=_positive, help="focal length (px) at the source's size"
    )
    g.add_argument("--fy", metavar="PX", type=_positive, help="with --fx (default: --fx)")
    g.add_argument("--cx", metavar="PX", type=_finite, help="with --fx (default: the image centre)")
    g.add_argument("--cy", metavar="PX", type=_finite, help="with --fx (default: the image centre)")
    m = p.add_argument_group("mounting (vehicle frame: x forward, y left, z up)")
    m.add_argument(
        "--camera-height-m",
        metavar="M",
        type=_positive,
        default=DEFAULT_CAMERA_HEIGHT_M,
        help="camera above the road (default: %(default)s)",
    )
    m.add_argument(
        "--camera-x-m",
        metavar="M",
        type=_finite,
        default=DEFAULT_CAMERA_X_M,
        help="camera ahead of the reference point (default: %(default)s)",
    )
    m.add_argument(
        "--pitch-rad", metavar="RAD", type=_finite, default=0.0, help="camera pitch, down positive"
    )
    m.add_argument(
        "--yaw-rad",
        metavar="RAD",
        type=_finite,
        default=0.0,
        help="camera yaw, left positive: the straight-ahead point moves right (default: 0)",
    )
    m.add_argument(
        "--radar-x-m", metavar="M", type=_finite, help="radar ahead of the reference point"
    )
    m.add_argument("--radar-y-m", metavar="M", type=_finite, help="radar to the left (default: 0)")
    m.add_argument(
        "--radar-z-m", metavar="M", type=_finite, help="radar above the road (default: 0)"
    )
    m.add_argument(
        "--radar-yaw-rad", metavar="RAD", type=_finite, help="radar yaw, left positive (default: 0)"
    )
    a = p.add_argument_group("where nothing is recorded")
    a.add_argument(
        "--assume-speed-mps",
        metavar="MPS",
        type=_non_negative,
        help="constant speed written to the manifest (without it and without CAN speed, "
        "speed is NaN and motion stereo cannot work)",
    )
    a.add_argument(
        "--ego-from-radar",
        action="store_true",
        help="without CAN speed: estimate the speed from the radar's stationary returns and "
        "write it into the recording as CAN frames, yaw rate 0 (the radar gives none usable); "
        "needs a radar that reports the roadside (detections), not only tracked vehicles",
    )
    a.add_argument(
        "--assume-yaw-rate-radps",
        metavar="RADPS",
        type=_finite,
        help="constant yaw rate, left positive (default: 0 when a speed is assumed)",
    )
    p.add_argument(
        "--max-radar-skew-ms",
        metavar="MS",
        type=_positive,
        help="pair a radar scan with a camera frame up to this far apart (default: half the "
        "radar's period)",
    )
    p.add_argument("--name", help="recording name (default: the source file's stem)")


def build_parser() -> argparse.ArgumentParser:
    from core.annotation.formats import FORMATS
    from core.io.importers.aimotive import DEFAULT_CAMERA as AIMOTIVE_CAMERA
    from core.io.importers.aimotive import DEFAULT_RADAR as AIMOTIVE_RADAR
    from core.io.importers.can_mapping import MAPPING_EXAMPLE
    from core.io.importers.nuscenes import DEFAULT_CAMERA as NUSCENES_CAMERA
    from core.io.importers.nuscenes import DEFAULT_RADARS as NUSCENES_RADARS
    from core.io.importers.nuscenes import DEFAULT_VERSION as NUSCENES_VERSION
    from core.io.importers.video import DEFAULT_FPS
    from core.synth.scenarios import SCENARIOS

    parser = argparse.ArgumentParser(
        prog="fusionscope", description="Radar-vision fusion on recorded drives."
    )
    sub = parser.add_subparsers(dest="command", required=True)

    serve = sub.add_parser("serve", help="start the web inspector")
    serve.add_argument(
        "--recordings",
        default=str(DEFAULT_RECORDINGS),
        help="folder of recordings to serve (default: the bundled ones)",
    )
    serve.add_argument(
        "--recording",
        help=f"recording opened first (default: {DEFAULT_RECORDING} when the folder holds it, "
        "else the first by name)",
    )
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (default: 127.0.0.1)")
    serve.add_argument("--port", type=int, default=8080, help="port (default: 8080)")
    serve.add_argument(
        "--presets",
        default=str(DEFAULT_PRESETS),
        help=f"folder the inspector saves parameter presets in (default: {DEFAULT_PRESETS})",
    )
    serve.add_argument(
        "--present",
        action="store_true",
        help="every tab shows the presenter view (a demo: pictures, legend, figures, no "
        "controls) and cannot leave it",
    )
    serve.add_argument(
        "--no-token",
        action="store_true",
        help="serve without a token: any program on a machine that reaches the port may use "
        "the inspector (pages of other sites are still refused)",
    )
    serve.add_argument(
        "--allow-host",
        action="append",
        default=[],
        metavar="NAME",
        help="a host name the browser may reach the inspector by, besides IP addresses, "
        "localhost and --host (repeatable; other names are refused against DNS rebinding)",
    )
    serve.add_argument(
        "--max-upload-mb",
        type=float,
        default=64.0,
        metavar="MB",
        help="larger uploads (annotation files) are refused before they are kept (default: 64)",
    )
    serve.set_defaults(func=_cmd_serve)

    calibrate = sub.add_parser(
        "calibrate",
        help="camera intrinsics from chessboard images",
        description=(
            "Find the chessboard's inner corners in every image of FOLDER, fit one pinhole "
            "camera with plumb_bob distortion (k1 k2 p1 p2 k3) to them, print it and write a "
            "ROS camera_info YAML (which `fusionscope import --camera-info` reads). Images "
            "where the board is not found, or of another size than most, are listed and skipped."
        ),
    )
    calibrate.add_argument(
        "folder", metavar="FOLDER", help="folder of chessboard images (png, jpg, ...)"
    )
    calibrate.add_argument(
        "--board",
        metavar="COLSxROWS",
        required=True,
        help="inner corners per row x per column, e.g. 9x6",
    )
    calibrate.add_argument(
        "--square-m",
        metavar="M",
        type=_positive,
        default=0.025,
        help="square edge in metres (default: 0.025)",
    )
    calibrate.add_argument(
        "--out",
        metavar="FILE",
        default="camera_info.yaml",
        help="camera_info file to write (default: %(default)s)",
    )
    calibrate.set_defaults(func=_cmd_calibrate)

    imp = sub.add_parser(
        "import",
        help="make a recording from a video, a still image, a ROS bag, nuScenes or aiMotive",
        description="Make a recording folder that `fusionscope serve` opens.",
    )
    kinds = imp.add_subparsers(dest="kind", required=True)
    mapping_help = "MAPPING.yaml (--mapping), for example:\n\n" + textwrap.indent(
        MAPPING_EXAMPLE, "  "
    )
    video = kinds.add_parser(
        "video",
        help="any video OpenCV reads",
        epilog=mapping_help,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_paragraph(
            "Frames are made grey, resized to --width (height by the aspect ratio) and "
            "resampled to --fps: each output time takes the source frame nearest in time. "
            "Time stamps are the output times on the video's clock (0 at its first frame) plus "
            "--start-ns, or, with CAN, plus --video-start-s: the CAN log's time of the video's "
            "first frame."
        ),
    )
    video.add_argument("source", metavar="VIDEO", help="the video file")
    video.add_argument("out_dir", metavar="OUT_DIR", help="new or empty folder for the recording")
    _image_size_args(video)
    video.add_argument(
        "--fps",
        metavar="HZ",
        type=_positive,
        default=DEFAULT_FPS,
        help="output frame rate (default: %(default)s, paper 002)",
    )
    video.add_argument(
        "--start-ns",
        metavar="NS",
        type=_int_at_least(0),
        help="time stamp (ns) of the video's first frame, without CAN (default: 0)",
    )
    video.add_argument(
        "--from-s",
        metavar="S",
        type=_non_negative,
        default=0.0,
        help="start of the clip on the video's clock (s)",
    )
    video.add_argument(
        "--to-s", metavar="S", type=_positive, help="end of the clip on the video's clock (s)"
    )
    _can_args(video, from_bag=False)
    video.add_argument(
        "--video-start-s",
        metavar="S",
        type=_non_negative,
        help="with --can: the CAN-clock time (s) of the video's first frame",
    )
    _common_import_args(video)
    video.set_defaults(func=_cmd_import)

    still = kinds.add_parser(
        "still",
        help="one image at a known time (e.g. with a CAN log of that moment)",
        epilog=mapping_help,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="One frame, made grey and resized to --width, stamped --time-s.",
    )
    still.add_argument("source", metavar="IMAGE", help="the image file")
    still.add_argument("out_dir", metavar="OUT_DIR", help="new or empty folder for the recording")
    still.add_argument(
        "--time-s",
        metavar="S",
        type=_non_negative,
        help="time of the image (s); with --can on the CAN log's clock (required then); default 0",
    )
    _image_size_args(still)
    _can_args(still, from_bag=False)
    _common_import_args(still)
    still.set_defaults(func=_cmd_import)

    bag = kinds.add_parser(
        "bag",
        help="a ROS 1 .bag file or a ROS 2 bag folder, copied as is",
        epilog=mapping_help,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_paragraph(
            "The bag is copied into the recording; topics not named are found by message "
            "type. Images keep their size: the calibration must be for it. CAN: --can LOG, "
            "or (without --can) the bag's can_msgs/Frame topic, with --dbc and --mapping."
        ),
    )
    bag.add_argument("source", metavar="BAG", help="ROS 1 .bag file or ROS 2 bag folder")
    bag.add_argument("out_dir", metavar="OUT_DIR", help="new or empty folder for the recording")
    bag.add_argument(
        "--camera-topic", metavar="TOPIC", help="camera topic (default: the only image topic)"
    )
    bag.add_argument(
        "--radar-topic", metavar="TOPIC", help="radar topic (default: the only radar topic, if any)"
    )
    _can_args(bag, from_bag=True)
    _common_import_args(bag)
    bag.set_defaults(func=_cmd_import)

    nuscenes = kinds.add_parser(
        "nuscenes",
        help="one scene of a nuScenes version folder (camera, front radars, ego poses, 3D boxes)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_paragraph(
            "One scene of DATAROOT/VERSION (nuScenes' own layout: a full install or a cut-down "
            "folder; rows of sample_data without their file are skipped and counted). The "
            "camera's images become grey frames (12 Hz with sweeps, the keyframes' 2 Hz "
            "without); the radars' points (nuScenes' default filter) are brought to each "
            "frame's time with both ego poses; speed and yaw rate come from the ego poses; "
            "ground truth from the keyframes' 3D boxes (no true pitch, no guard rails). "
            "nuScenes is CC BY-NC-SA 4.0: keep the recording out of other repositories."
        ),
        epilog=textwrap.dedent(
            """\
            example:
              fusionscope import nuscenes ../shared/realdata/nuscenes-mini-scene-0523 \\
                  recordings-real/nuscenes-0523 --scene scene-0523
            """
        ),
    )
    nuscenes.add_argument("source", metavar="DATAROOT", help="folder holding VERSION/ and samples/")
    nuscenes.add_argument(
        "out_dir", metavar="OUT_DIR", help="new or empty folder for the recording"
    )
    nuscenes.add_argument(
        "--scene", required=True, metavar="NAME", help="scene name, e.g. scene-0523"
    )
    nuscenes.add_argument(
        "--version", default=NUSCENES_VERSION, help="version folder (default: %(default)s)"
    )
    nuscenes.add_argument(
        "--camera", default=NUSCENES_CAMERA, help="camera channel (default: %(default)s)"
    )
    nuscenes.add_argument(
        "--radars",
        default=",".join(NUSCENES_RADARS),
        metavar="CHANNELS",
        help="radar channels, comma-separated (default: %(default)s)",
    )
    _image_size_args(nuscenes)
    nuscenes.add_argument("--name", help="recording name (default: nuscenes-SCENE)")
    nuscenes.set_defaults(func=_cmd_import_dataset)

    aimotive = kinds.add_parser(
        "aimotive",
        help="one sequence of the aiMotive Multimodal Dataset (camera, radar, 3D boxes)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_paragraph(
            "One sequence folder (sensor/camera, sensor/radar, sensor/calibration, "
            "dynamic/box/3d_body). The camera is undistorted and made grey; the radar's "
            "detections are kept with their elevation ignored; the ego speed comes from the "
            "radar's stationary returns (the sequence records none), yaw rate 0; ground truth "
            "from the 3D boxes (no true pitch, no guard rails). aiMotive's data is "
            "CC BY-NC-SA 4.0: keep the recording out of other repositories."
        ),
        epilog=textwrap.dedent(
            """\
            example:
              fusionscope import aimotive ../shared/realdata/aimotive-night-motorway \\
                  recordings-real/aimotive-night
            """
        ),
    )
    aimotive.add_argument("source", metavar="SEQUENCE_DIR", help="the sequence folder")
    aimotive.add_argument(
        "out_dir", metavar="OUT_DIR", help="new or empty folder for the recording"
    )
    aimotive.add_argument("--camera", default=AIMOTIVE_CAMERA, help="camera (default: %(default)s)")
    aimotive.add_argument("--radar", default=AIMOTIVE_RADAR, help="radar (default: %(default)s)")
    _image_size_args(aimotive)
    aimotive.add_argument("--name", help="recording name (default: aimotive-SEQUENCE)")
    aimotive.set_defaults(func=_cmd_import_dataset)

    annotations = sub.add_parser(
        "annotations",
        help="export a recording's annotations to MOT, KITTI, COCO or CVAT, or import them",
        description=_paragraph(
            "Annotations are the boxes drawn in the inspector, kept in the recording's "
            "groundtruth.json. Formats: mot (MOT Challenge gt.txt), kitti (KITTI tracking "
            "label_02), coco (COCO JSON with track ids), cvat (CVAT for video 1.1 XML). Box "
            "edges, ids, frames, classes and attributes of each: core/annotation/formats.py."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = annotations.add_subparsers(dest="action", required=True)
    export = actions.add_parser(
        "export",
        help="write a recording's annotations to a file",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_paragraph(
            "Write the annotations of RECORDING (groundtruth.json with the edits of its "
            "journal; nothing in the recording is written) to OUT: the box of every frame "
            "a track is on, interpolated frames included, unless --keyframes-only. What the "
            "format cannot hold (radar distances snapped to keyframes, some attributes, in "
            "mot and kitti the frames marked annotated) is listed after writing."
        ),
    )
    export.add_argument("recording", type=Path, metavar="RECORDING", help="a recording folder")
    export.add_argument("out", type=Path, metavar="OUT", help="file to write (replaced whole)")
    export.add_argument("--format", required=True, choices=FORMATS, help="the file's format")
    export.add_argument(
        "--keyframes-only",
        action="store_true",
        help="write the keyframes' boxes only (mot, kitti and coco then read back with gaps "
        "between them; cvat keeps its interpolation)",
    )
    export.set_defaults(func=_cmd_annotations)
    load = actions.add_parser(
        "import",
        help="read annotations from a file into a recording",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=_paragraph(
            "Read FILE as annotations of RECORDING and save them into its groundtruth.json "
            "as one edit: tracks rebuilt as sparse keyframes, and the frames the file marks "
            "annotated (mot and kitti mark none: then every frame of the recording) marked "
            "annotated. Into a recording that already has tracks or annotated frames only with "
            "--replace, which deletes its tracks and unmarks its frames in the same edit. The "
            "evaluation counts only the frames marked annotated."
        ),
    )
    load.add_argument("recording", type=Path, metavar="RECORDING", help="a recording folder")
    load.add_argument("file", type=Path, metavar="FILE", help="the annotation file to read")
    load.add_argument("--format", required=True, choices=FORMATS, help="the file's format")
    load.add_argument(
        "--replace",
        action="store_true",
        help="delete every track of the recording and unmark every annotated frame first",
    )
    load.set_defaults(func=_cmd_annotations)

    info = sub.add_parser(
        "info",
        help="what a recording holds: streams, rates, gaps, camera-radar skew, warnings",
    )
    info.add_argument("recording", type=Path, help="a recording folder")
    info.add_argument(
        "--no-cache",
        action="store_true",
        help="build the index from the files even when a cached one is valid",
    )
    info.set_defaults(func=_cmd_info)

    run = sub.add_parser(
        "run",
        help="run the whole pipeline over a recording and write per-frame results",
        description=(
            "Process every frame of a recording with the fusion engine (pitch, motion "
            "stereo, guard-rail filter, vehicles, pedestrians, tracking) and write one JSON "
            "object per frame: boxes, classes, world positions, pitch, stage timings."
        ),
    )
    run.add_argument("recording", type=Path, help="a recording folder")
    run.add_argument("--params", metavar="FILE", help=PARAMS_HELP)
    run.add_argument("--out", type=Path, help="JSON-lines file to write (default: standard output)")
    run.add_argument(
        "--strict",
        action="store_true",
        help="refuse a recording whose reading gives warnings (skipped or repaired data, "
        "missing signals), and stop at a frame that cannot be read, instead of saying so "
        "and going on",
    )
    run.set_defaults(func=_cmd_run)

    evaluate = sub.add_parser(
        "evaluate",
        help="score the pipeline against the recordings' ground truth, as the papers did",
        description=(
            "Run the fusion engine over each recording and score it against its "
            "groundtruth.json: paper 001's frame-based vehicle statistics (RD, FN, RFN, FP, "
            "NVO) and events, paper 002's guard-rail errors, paper 000's pedestrians before "
            "and after each fusion filter, motion stereo's obstacle mask, the pitch, and "
            "the tracked output (CLEAR-MOT, IDF1). Definitions: README, 'How good is it'."
        ),
    )
    evaluate.add_argument("recordings", type=Path, nargs="+", help="recording folders")
    evaluate.add_argument("--params", metavar="FILE", help=PARAMS_HELP)
    evaluate.add_argument(
        "--compare",
        metavar="FILE",
        help="also evaluate under these parameters (a file, or `papers`) and print only the "
        "headline figures of both side by side",
    )
    evaluate.add_argument("--format", choices=("table", "markdown", "csv", "json"), default="table")
    evaluate.add_argument(
        "--strict",
        action="store_true",
        help="refuse a recording whose reading gives warnings (skipped or repaired data, "
        "missing signals), and stop at a frame that cannot be read, instead of saying so "
        "and going on",
    )
    evaluate.add_argument(
        "--baselines",
        action="store_true",
        help=(
            "also run OpenCV's HOG people detector, a Hough-line vanishing point and MOG2 "
            "background subtraction on the same frames and show them beside the stages"
        ),
    )
    evaluate.set_defaults(func=_cmd_evaluate)

    from core.bench import STAGES

    bench = sub.add_parser(
        "bench",
        help="time the stages on one thread against the paper's timing table",
        description=(
            "Time each stage and the whole frame (total) on frames of a recording (640x300 "
            "processed rows on the bundled drives), one thread: median, 10th and 90th "
            "percentiles of all runs after warm-up, beside the paper's figure (paper 000, "
            "Pentium 4 at 3 GHz), the speed-up and this project's budget. Every median is "
            "also a multiple of a reference kernel timed in the same run (cv2.warpPerspective "
            "of the 640x300 window to the bird's-eye grid), to compare machines. With total, "
            "also the frames per second of `fusionscope run`, decoding and writing included. "
            "With both vehicle and guardrail, also paper 002's table I: vehicle detection "
            "alone (VD), with the guard-rail filter (GRD) and with overlapping-boxes "
            "management (OBM)."
        ),
    )
    bench.add_argument(
        "--stage",
        action="append",
        choices=STAGES,
        help="stage to time, total for the whole frame; repeat for several (default: all)",
    )
    bench.add_argument(
        "--recording",
        type=Path,
        default=DEFAULT_RECORDINGS / DEFAULT_RECORDING,
        help=f"recording whose frames are used (default: the bundled {DEFAULT_RECORDING})",
    )
    bench.add_argument("--params", metavar="FILE", help=PARAMS_HELP)
    bench.add_argument(
        "--frames", type=_int_at_least(2), default=20, help="frames used (default: 20)"
    )
    bench.add_argument(
        "--repeat", type=_int_at_least(1), default=50, help="timed runs per frame (default: 50)"
    )
    bench.add_argument("--format", choices=("table", "json"), default="table")
    bench.set_defaults(func=_cmd_bench)

    sweep = sub.add_parser(
        "sweep",
        help="evaluate many parameter sets on many recordings on Dask and rank the sets",
        description=_paragraph(
            "Evaluate every parameter set of SWEEP.yaml (a grid or a seeded random sample of "
            "named parameters) on every recording, one Dask task per recording and set, on a "
            "local cluster or, with --scheduler, on a running Dask cluster. Each finished "
            "task is appended to the --results file at once; run the same command again to "
            "resume an interrupted sweep: the tasks in the file do not run again. At the end, "
            "the sets ranked by one figure of their total over the recordings, each with its "
            "worst frames. Needs Dask: pip install -e '.[cluster]'. The sweep file's format: "
            "README, 'Parameter sweeps'."
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sweep.add_argument("sweep", type=Path, metavar="SWEEP.yaml", help="the sweep file")
    sweep.add_argument(
        "recordings", nargs="+", metavar="RECORDING", help="recording folders (with ground truth)"
    )
    sweep.add_argument(
        "--results",
        type=Path,
        required=True,
        metavar="FILE",
        help="JSON-lines file of the finished tasks: read first, then appended to",
    )
    sweep.add_argument(
        "--metric",
        metavar="DOTTED",
        help="the figure ranked on, a dotted name of `evaluate --format json`'s total "
        "(default: the sweep file's, else vehicles.events.refined_share)",
    )
    sweep.add_argument(
        "--goal", choices=("max", "min"), help="best is highest or lowest (default: max)"
    )
    sweep.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="a running Dask scheduler (default: a local cluster started for the sweep)",
    )
    sweep.add_argument(
        "--workers",
        metavar="N",
        type=_int_at_least(1),
        help="worker processes of the local cluster, one thread each (default: 2)",
    )
    sweep.add_argument(
        "--top",
        metavar="K",
        type=_int_at_least(1),
        default=10,
        help="sets shown (default: %(default)s)",
    )
    sweep.add_argument("--format", choices=("table", "json"), default="table")
    sweep.set_defaults(func=_cmd_sweep)

    synth = sub.add_parser("synth", help="generate a synthetic drive with exact ground truth")
    synth.add_argument("--scenario", required=True, choices=sorted(SCENARIOS))
    synth.add_argument("--seconds", type=float, default=20.0, help="duration (default: 20)")
    synth.add_argument(
        "--seed", type=int, default=0, help="random seed; one seed, the same bytes (default: 0)"
    )
    synth.add_argument("out_dir", help="new or empty folder to write the recording into")
    synth.set_defaults(func=_cmd_synth)

    _add_export_scene(sub)
    _add_export_video(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    raise SystemExit(main())
