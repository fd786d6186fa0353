"""Fuzzing the manifest parser: any YAML gives a Manifest or a RecordingError, nothing else.

Two sources of input: valid manifests with one part replaced by arbitrary YAML values
(strings, numbers, lists, mappings, null, NaN), and arbitrary text as the whole file.
FUZZ_EXAMPLES sets the number of examples per test (default: a short run for CI).
"""

from __future__ import annotations

import copy
import os
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from core.io.errors import RecordingError
from core.io.manifest import MANIFEST_NAME, load_manifest, manifest_to_dict, parse_manifest
from tests.core.arbitrary import values

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "200"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

VALID: dict[str, Any] = {
    "format_version": 1,
    "name": "fuzz",
    "camera": {"bag": "bag", "topic": "/camera", "mono16_bits": 12},
    "radar": {
        "can": {
            "log": "can.log",
            "dbc": ["radar.dbc"],
            "channel": "can1",
            "messages": "TRACK_A_*",
            "distance": {"signal": "LONG_DIST", "unit": "m"},
            "lateral": {"signal": "LAT_DIST", "unit": "m", "sign": -1},
            "range_rate": {"signal": "REL_SPEED", "unit": "m/s"},
            "valid": {"signal": "VALID"},
        }
    },
    "can": {
        "bag": "bag",
        "topic": "/can",
        "dbc": "car.dbc",
        "speed": {"message": "SPEED", "signal": "SPEED", "unit": "km/h"},
        "yaw_rate": {"message": "KIN", "signal": "YAW", "unit": "deg/s", "sign": -1},
        "yaw_rate_bias": "standstill",
    },
    "assumptions": {"speed_mps": 27.0},
    "calibration": "calibration.yaml",
    "time_offsets_ns": {"camera": 0, "radar": -5, "can": 7},
    "max_radar_skew_ms": 25,
}


def paths(tree: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every key path of a nested mapping (lists indexed), the root excluded."""
    out = []
    items = (
        tree.items()
        if isinstance(tree, dict)
        else enumerate(tree)
        if isinstance(tree, list)
        else []
    )
    for key, value in items:
        out.append((*prefix, key))
        out += paths(value, (*prefix, key))
    return out


ALL_PATHS = paths(VALID)


def test_the_valid_manifest_parses_and_round_trips(tmp_path: Path) -> None:
    m = parse_manifest(VALID, tmp_path)
    again = parse_manifest(manifest_to_dict(m), tmp_path)
    assert again == m


@pytest.mark.fuzz
@FUZZ
@given(where=st.sampled_from(ALL_PATHS), value=values, drop=st.booleans())
def test_one_part_replaced_by_anything(where: tuple[Any, ...], value: Any, drop: bool) -> None:
    raw = copy.deepcopy(VALID)
    parent = raw
    for key in where[:-1]:
        parent = parent[key]
    if drop and isinstance(parent, dict):
        del parent[where[-1]]
    else:
        parent[where[-1]] = value
    try:
        parse_manifest(raw, Path("/nowhere"))
        event("parsed")
    except RecordingError as err:
        event("RecordingError")
        assert "recording.yaml" in str(err)


@pytest.mark.fuzz
@FUZZ
@given(text=st.text(max_size=300) | st.binary(max_size=300).map(lambda b: b.decode("latin-1")))
def test_any_text_as_the_manifest(text: str, tmp_path_factory: pytest.TempPathFactory) -> None:
    folder = tmp_path_factory.mktemp("m", numbered=True)
    (folder / MANIFEST_NAME).write_text(text, encoding="utf-8", errors="surrogateescape")
    with pytest.raises(RecordingError, match="recording"):
        load_manifest(folder)


def test_yaml_of_the_valid_manifest_reads_back(tmp_path: Path) -> None:
    (tmp_path / MANIFEST_NAME).write_text(yaml.safe_dump(VALID))
    assert load_manifest(tmp_path).radar == parse_manifest(VALID, tmp_path).radar
