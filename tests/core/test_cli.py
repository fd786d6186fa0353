"""The `fusionscope` command refuses bad arguments with a message naming them."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from app.access import Access
from core.cli import build_parser, main


def test_serve_refuses_a_recordings_folder_that_does_not_exist(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "nowhere"
    assert main(["serve", "--recordings", str(missing)]) == 2
    assert f"--recordings {missing}: expected a folder of recordings" in capsys.readouterr().err


def test_serve_refuses_a_recording_that_is_not_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["serve", "--recordings", str(tmp_path), "--recording", "nope"]) == 2
    assert "nope" in capsys.readouterr().err


def test_serve_defaults_to_loopback_port_8080_and_the_bundled_highway() -> None:
    args = build_parser().parse_args(["serve"])
    assert (args.host, args.port, args.recording) == ("127.0.0.1", 8080, None)
    assert (Path(args.recordings) / "highway" / "recording.yaml").is_file()


@pytest.mark.parametrize(("names", "first"), [(("a", "highway"), "highway"), (("b", "a"), None)])
def test_serve_opens_highway_first_when_the_folder_holds_it_else_the_first_by_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, names: tuple[str, ...], first: str | None
) -> None:
    # None: app.server takes the first recording by name (tests/app cover that part)
    for name in names:
        (tmp_path / name).mkdir()
        (tmp_path / name / "recording.yaml").write_text("format_version: 1\n")
    opened: list[str | None] = []
    monkeypatch.setattr("app.server.serve", lambda root, recording, *rest: opened.append(recording))
    assert main(["serve", "--recordings", str(tmp_path)]) == 0
    assert opened == [first]


@pytest.mark.parametrize("no_token", [False, True])
def test_serve_makes_a_token_per_run_unless_told_not_and_answers_to_its_host_names(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, no_token: bool
) -> None:
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "recording.yaml").write_text("format_version: 1\n")
    accesses: list[Access] = []
    monkeypatch.setattr("app.server.serve", lambda *args: accesses.append(args[6]))
    args = ["serve", "--recordings", str(tmp_path), "--allow-host", "Box.lan"]
    for _ in range(2):
        assert main([*args, *(["--no-token"] if no_token else [])]) == 0
    if no_token:
        assert [access.token for access in accesses] == [None, None]
    else:
        assert all(access.token for access in accesses)
        assert accesses[0].token != accesses[1].token
    assert accesses[0].allowed_hosts == {"127.0.0.1", "box.lan"}


def test_serve_refuses_an_upload_limit_that_is_not_positive(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["serve", "--recordings", str(tmp_path), "--max-upload-mb", "0"]) == 2
    assert "--max-upload-mb: expected a positive size, got 0.0" in capsys.readouterr().err


def test_serve_warns_that_another_host_reaches_it_and_who_can_use_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # a recording that is not there ends the command before anything binds
    args = ["serve", "--recordings", str(tmp_path), "--recording", "nope", "--host", "0.0.0.0"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "warning: --host 0.0.0.0" in err and "anyone who has the printed URL" in err
    assert main([*args, "--no-token"]) == 2
    assert "anyone who can reach this port" in capsys.readouterr().err
    assert main(["serve", "--recordings", str(tmp_path), "--recording", "nope"]) == 2
    assert "warning" not in capsys.readouterr().err


def test_a_subcommand_is_required(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main([])
    assert "serve" in capsys.readouterr().err


def test_info_reports_streams_skew_and_open_time(capsys: pytest.CaptureFixture[str]) -> None:
    highway = Path(build_parser().parse_args(["serve"]).recordings) / "highway"
    assert main(["info", str(highway), "--no-cache"]) == 0
    out = capsys.readouterr().out
    assert "frames     150" in out
    assert "index built in" in out
    for stream in ("camera", "radar", "CAN speed", "CAN yaw rate"):
        assert f"\n{stream} " in out
    assert "0 frame(s) without a scan" in out
    assert main(["info", str(highway)]) == 0
    assert "(index from cache)" in capsys.readouterr().out


def test_info_on_a_folder_without_a_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["info", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fusionscope info: ") and "recording.yaml" in err


WARNING = "radar: 3 returns with non-finite values dropped"


@pytest.fixture(scope="module")
def one_second(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from core.synth.generate import generate

    path = tmp_path_factory.mktemp("warned") / "highway"
    generate("highway", 1.0, 3, path)
    return path


@pytest.fixture()
def warned(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every Drive opened reports WARNING, as one whose reading skipped something."""
    from core.io import drive

    class WarnedDrive(drive.Drive):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            self.warnings = (WARNING,)

    monkeypatch.setattr(drive, "Drive", WarnedDrive)
    monkeypatch.setattr("core.evaluation.evaluate.Drive", WarnedDrive)


@pytest.mark.usefixtures("warned")
@pytest.mark.parametrize("command", ["run", "evaluate"])
def test_run_and_evaluate_print_the_drives_warnings_and_strict_refuses_it(
    one_second: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    out = ["--out", str(tmp_path / "r.jsonl")] if command == "run" else ["--format", "json"]
    assert main([command, str(one_second), *out]) == 0
    captured = capsys.readouterr()
    assert f"fusionscope {command}: warning: highway: {WARNING}\n" in captured.err
    if command == "evaluate":
        assert json.loads(captured.out)["recordings"][0]["warnings"] == [WARNING]
        assert json.loads(captured.out)["total"]["warnings"] == [f"highway: {WARNING}"]
    (tmp_path / "r.jsonl").unlink(missing_ok=True)
    assert main([command, str(one_second), *out, "--strict"]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith(
        f"fusionscope {command}: highway: --strict: refused, reading it gave 1 warning(s): "
        f"{WARNING}"
    )
    assert not (tmp_path / "r.jsonl").exists() and captured.out == ""


DAMAGED = 3


@pytest.fixture()
def damaged(monkeypatch: pytest.MonkeyPatch) -> None:
    """Frame DAMAGED of every Drive opened cannot be read, as a damaged PNG in a bag
    (tests/core/io/test_errors.py makes one for real)."""
    from core.io import drive
    from core.io.errors import RecordingError

    class DamagedDrive(drive.Drive):
        def frame(self, i: int) -> Any:
            if i == DAMAGED:
                raise RecordingError(f"bag: frame {i}: damaged PNG data")
            return super().frame(i)

    monkeypatch.setattr(drive, "Drive", DamagedDrive)
    monkeypatch.setattr("core.evaluation.evaluate.Drive", DamagedDrive)


@pytest.mark.usefixtures("damaged")
def test_run_skips_a_frame_it_cannot_read_and_says_so_at_the_end(
    one_second: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.jsonl"
    assert main(["run", str(one_second), "--out", str(out)]) == 0
    frames = [json.loads(line)["frame"] for line in out.read_text().splitlines()]
    assert DAMAGED not in frames and len(frames) == 9 and frames[DAMAGED : DAMAGED + 1] == [4]
    err = capsys.readouterr().err
    assert (
        "fusionscope run: warning: highway: skipped 1 of 10 frame(s) that could not be read "
        "(--strict stops at the first):\n  frame 3: bag: frame 3: damaged PNG data\n"
    ) in err
    out.unlink()
    assert main(["run", str(one_second), "--out", str(out), "--strict"]) == 2
    err = capsys.readouterr().err
    assert f"damaged PNG data; nothing written to {out}" in err
    assert not out.exists() and not out.with_name("r.jsonl.partial").exists()


@pytest.mark.usefixtures("damaged")
def test_evaluate_scores_the_frames_it_can_read_and_names_the_others(
    one_second: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["evaluate", str(one_second), "--format", "json"]) == 0
    captured = capsys.readouterr()
    why = "frame 3 could not be read and is not scored: bag: frame 3: damaged PNG data"
    assert f"fusionscope evaluate: warning: highway: {why}\n" in captured.err
    (recording,) = json.loads(captured.out)["recordings"]
    assert recording["warnings"] == [why] and recording["frames"] == 9
    assert main(["evaluate", str(one_second), "--strict"]) == 2
    assert "damaged PNG data" in capsys.readouterr().err
