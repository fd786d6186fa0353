"""The `fusionscope` command: one entry point, one subcommand per job."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

DEFAULT_RECORDINGS = Path(__file__).resolve().parents[1] / "recordings"
DEFAULT_RECORDING = "highway"


class ProgressBar:
    """A one-line progress bar on stderr."""

    def __init__(self, label: str, width: int = 40) -> None:
        self.label = label
        self.width = width

    def __call__(self, done: int, total: int) -> None:
        filled = self.width * done // max(total, 1)
        bar = "#" * filled + "." * (self.width - filled)
        end = "\n" if done >= total else ""
        sys.stderr.write(f"\r{self.label} [{bar}] {done}/{total}{end}")
        sys.stderr.flush()


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


def _cmd_serve(args: argparse.Namespace) -> int:
    from app.server import serve

    root = Path(args.recordings)
    if not root.is_dir():
        print(
            f"fusionscope serve: --recordings {root}: expected a folder of recordings, "
            "it does not exist",
            file=sys.stderr,
        )
        return 2
    try:
        serve(root, args.recording, args.host, args.port)
    except ValueError as err:
        print(f"fusionscope serve: {err}", file=sys.stderr)
        return 2
    return 0


def build_parser() -> argparse.ArgumentParser:
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
        default=DEFAULT_RECORDING,
        help=f"recording opened first (default: {DEFAULT_RECORDING})",
    )
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (default: 127.0.0.1)")
    serve.add_argument("--port", type=int, default=8080, help="port (default: 8080)")
    serve.set_defaults(func=_cmd_serve)

    synth = sub.add_parser("synth", help="generate a synthetic drive with exact ground truth")
    synth.add_argument("--scenario", required=True, choices=sorted(SCENARIOS))
    synth.add_argument("--seconds", type=float, default=20.0, help="duration (default: 20)")
    synth.add_argument(
        "--seed", type=int, default=0, help="random seed; one seed, the same bytes (default: 0)"
    )
    synth.add_argument("out_dir", help="new or empty folder to write the recording into")
    synth.set_defaults(func=_cmd_synth)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    raise SystemExit(main())
