"""A tab's view as the query of its page's URL, and back: shareable views.

    ?recording=highway&frame=90&layers=radar,vehicles&panels=bird_eye&stage=symmetry
     &a.vehicle.symmetry_threshold=0.4&compare=1&b.pitch.lines_kept=9&clip=30-89&present=1

Only what differs from a new tab is written: the parameters are the values that differ from
the defaults (as JSON numbers, booleans or lists, so a float comes back bit for bit), `compare`
says that set B exists (it may equal the defaults), `clip` is an inclusive frame range and
`present` opens the presenter view. Layers and panels are the names of those switched on
(`app.state.Layers`, `Panels`), empty for none.

Reading a query never fails: each part that cannot be used is left at the new tab's value
and named in `problems`, saying what was expected and what came.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import TypeVar
from urllib.parse import parse_qsl, urlencode

from app.access import TOKEN_KEY
from app.param_sets import changed_names
from app.state import STAGES, Layers, Panels
from core.params import Params, ParamsError

Clip = tuple[int, int]  # first and last frame, inclusive
A_PREFIX, B_PREFIX = "a.", "b."
T = TypeVar("T")
KEYS = ("recording", "frame", "layers", "panels", "stage", "compare", "clip", "present")


@dataclass(frozen=True)
class ViewLink:
    """What a link reproduces. None: as a new tab has it (the first recording, frame 0, the
    default layers and panels, the whole drive as clip)."""

    recording: str | None = None
    frame: int | None = None
    layers: Layers | None = None
    panels: Panels | None = None
    params: Params = field(default_factory=Params)
    params_b: Params | None = None
    clip: Clip | None = None
    present: bool = False


def link_query(link: ViewLink) -> str:
    """The URL query (with its '?') of `link`."""
    pairs: list[tuple[str, str]] = []
    if link.recording is not None:
        pairs.append(("recording", link.recording))
    if link.frame is not None:
        pairs.append(("frame", str(link.frame)))
    if link.layers is not None:
        pairs.append(("layers", _switched_on(link.layers)))
    if link.panels is not None:
        pairs.append(("panels", _switched_on(link.panels)))
        pairs.append(("stage", link.panels.stage))
    pairs += _param_pairs(A_PREFIX, link.params)
    if link.params_b is not None:
        pairs.append(("compare", "1"))
        pairs += _param_pairs(B_PREFIX, link.params_b)
    if link.clip is not None:
        pairs.append(("clip", f"{link.clip[0]}-{link.clip[1]}"))
    if link.present:
        pairs.append(("present", "1"))
    return "?" + urlencode(pairs, safe=",")


def parse_link_query(query: str) -> tuple[ViewLink, tuple[str, ...]]:
    """The view a URL query (with or without its '?') describes, and what in it could not be
    used (each part of those left as a new tab has it)."""
    problems: list[str] = []
    values: dict[str, str] = {}
    changes: dict[str, dict[str, object]] = {A_PREFIX: {}, B_PREFIX: {}}
    for key, value in parse_qsl(query.removeprefix("?"), keep_blank_values=True):
        prefix = key[:2]
        if prefix in changes:
            try:
                changes[prefix][key[2:]] = json.loads(value)
            except ValueError:
                problems.append(f"{key}: expected a number, true/false or a list, got {value!r}")
        elif key in KEYS:
            values[key] = value
        elif key != TOKEN_KEY:  # the server's access token (app.access), checked before this
            problems.append(f"{key}: not a part of a view (expected one of {', '.join(KEYS)})")
    panels = None
    if "panels" in values or "stage" in values:
        panels = _parsed(
            lambda: _panels(values.get("panels"), values.get("stage")), "panels", problems
        )
    comparing = "compare" in values or bool(changes[B_PREFIX])
    link = ViewLink(
        recording=values.get("recording") or None,
        frame=_parsed(lambda: _frame(values["frame"]), "frame", problems),
        layers=_parsed(lambda: _layers(values["layers"]), "layers", problems),
        panels=panels,
        params=_params(changes[A_PREFIX], "a", problems),
        params_b=_params(changes[B_PREFIX], "b", problems) if comparing else None,
        clip=_parsed(lambda: parse_clip(values["clip"]), "clip", problems),
        present=_parsed(lambda: _flag(values["present"]), "present", problems) or False,
    )
    return link, tuple(problems)


def _parsed(parse: Callable[[], T], key: str, problems: list[str]) -> T | None:
    """`parse()`; None when the query lacks the part (KeyError) or it is refused (noted)."""
    try:
        return parse()
    except KeyError:
        return None
    except ValueError as err:
        problems.append(f"{key}: {err}")
        return None


def _switched_on(switches: Layers | Panels) -> str:
    return ",".join(f.name for f in fields(switches) if getattr(switches, f.name) is True)


def _param_pairs(prefix: str, params: Params) -> list[tuple[str, str]]:
    return [(prefix + name, json.dumps(params.value_of(name))) for name in changed_names(params)]


def _names(text: str, allowed: tuple[str, ...], what: str) -> set[str]:
    names = {n for n in text.split(",") if n}
    unknown = sorted(names - set(allowed))
    if unknown:
        raise ValueError(f"expected {what} of {', '.join(allowed)}, got {', '.join(unknown)}")
    return names


def _layers(text: str) -> Layers:
    on = _names(text, Layers.names(), "layer names")
    return Layers(**{name: name in on for name in Layers.names()})


def _panels(text: str | None, stage: str | None) -> Panels:
    default = Panels()
    if stage is not None and stage not in STAGES:
        raise ValueError(f"stage: expected one of {', '.join(STAGES)}, got {stage!r}")
    switches = {n: getattr(default, n) for n in Panels.switches()}
    if text is not None:
        on = _names(text, Panels.switches(), "panel names")
        switches = {n: n in on for n in Panels.switches()}
    return Panels(**switches, stage=stage or default.stage)


def _whole(text: str, what: str) -> int:
    if not text.isdigit():
        raise ValueError(f"expected {what} (a whole number from 0), got {text!r}")
    return int(text)


def _frame(text: str) -> int:
    return _whole(text, "a frame index")


def parse_clip(text: str) -> Clip:
    """'first-last' frames (inclusive); ValueError saying what was expected."""
    first, dash, last = text.partition("-")
    if not dash:
        raise ValueError(f"expected first-last frames such as 30-89, got {text!r}")
    clip = _whole(first, "a first frame"), _whole(last, "a last frame")
    if clip[0] > clip[1]:
        raise ValueError(f"expected the first frame at most the last, got {text!r}")
    return clip


def _flag(text: str) -> bool:
    if text not in ("0", "1"):
        raise ValueError(f"expected 0 or 1, got {text!r}")
    return text == "1"


def _params(values: dict[str, object], which: str, problems: list[str]) -> Params:
    """The default parameters with `values`; all of them or, when the set is refused, none."""
    try:
        return Params().with_values(values)
    except ParamsError as err:
        problems.append(f"{which}: {err} (set {which.upper()} left at the defaults)")
        return Params()
