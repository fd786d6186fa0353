"""What the inspector's Metrics panel shows of one drive's evaluation: pure functions over a
`core.evaluation.evaluate.RecordingReport`, no viser.

- `metrics_markdown`: the evaluation's summary tables, as `fusionscope evaluate --format
  markdown` prints them (the error listings are the marks below instead);
- `error_marks`: one `ErrorMark` per frame with an error the evaluation lists under "Where
  the errors are", for a jump list;
- `slider_marks`: those frames as a viser slider's `marks`, labelled with short codes.

The errors are `core.evaluation.evaluate.error_listings`, in its order (`ERROR_KINDS`): the
listings of `fusionscope evaluate`'s "Where the errors are". Their frame indices are the
recording's own, so a report of one recording is expected (a total's listings mix
recordings).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

from core.evaluation.evaluate import ErrorListing, RecordingReport, error_listings
from core.evaluation.report import format_markdown, tables

SliderMark = int | tuple[int, str]


@dataclass(frozen=True)
class _Words:
    """How a person reads one kind of error: code, the short code of a slider label; one,
    many: the text before the ids of one error and of several on a frame."""

    code: str
    one: str
    many: str


_WORDS = {
    "vehicle FN": _Words("FN", "FN vehicle", "FN vehicles"),
    "vehicle RFN": _Words("RFN", "RFN vehicle", "RFN vehicles"),
    "vehicle FP": _Words("FP", "FP vehicle from radar target", "FP vehicles from radar targets"),
    "guard-rail FN": _Words(
        "FN", "FN guard rail at radar target", "FN guard rail at radar targets"
    ),
    "guard-rail FP": _Words(
        "FP", "FP guard rail at radar target", "FP guard rail at radar targets"
    ),
    "pedestrian FN": _Words("FN", "FN pedestrian", "FN pedestrians"),
    "pedestrian FP": _Words("FP", "FP pedestrian", "FP pedestrians"),
}
ERROR_KINDS: tuple[str, ...] = tuple(_WORDS)  # error_listings' kinds, in its order
CODE_OF_KIND: dict[str, str] = {kind: w.code for kind, w in _WORDS.items()}
CODES = ("FN", "RFN", "FP")  # in a label's order
# Labels are a few characters ("FN+FP", about 35 px); a slider in viser's side panel is about
# 300 px wide, so more than about 8 labels run into each other.
MAX_LABELLED_MARKS = 8


@dataclass(frozen=True)
class ErrorMark:
    """The errors of one frame: frame index; kinds: those present, in `ERROR_KINDS` order;
    text: e.g. "frame 37: FN vehicle 3; FP pedestrian" (kinds separated by "; ", ids of one
    kind by ", ")."""

    frame: int
    kinds: tuple[str, ...]
    text: str

    @property
    def label(self) -> str:
        """The slider label: the codes of its kinds, e.g. "FN", "FN+FP", "FN+RFN+FP"."""
        present = {CODE_OF_KIND[k] for k in self.kinds}
        return "+".join(c for c in CODES if c in present)


def metrics_markdown(report: RecordingReport) -> str:
    """The evaluation's summary tables of one drive in markdown, as `fusionscope evaluate
    --format markdown` prints them for that drive alone (`core.evaluation.report`)."""
    return format_markdown(tables([report], report, listings=False))


def _item(listing: ErrorListing, ids: Sequence[int]) -> str:
    words = _WORDS[listing.kind]
    if not listing.ids:
        return words.one if len(ids) == 1 else f"{len(ids)} {words.many}"
    joined = ", ".join(str(i) for i in sorted(ids))
    return f"{words.one if len(ids) == 1 else words.many} {joined}"


def error_marks(
    report: RecordingReport, kinds: Collection[str] = ERROR_KINDS
) -> tuple[ErrorMark, ...]:
    """One mark per frame with an error of one of `kinds` (of `ERROR_KINDS`, module
    docstring), sorted by frame; none for a drive without such errors.

    On the bundled drives every frame has some error (a vehicle no search area contains, RFN,
    on almost all), so a panel that wants fewer marks picks the kinds to show.
    """
    unknown = sorted(set(kinds) - set(ERROR_KINDS))
    if unknown:
        raise ValueError(f"kinds: expected some of {', '.join(ERROR_KINDS)}; got {unknown[0]!r}")
    listings = [e for e in error_listings(report) if e.kind in kinds]
    found: dict[int, dict[str, list[int]]] = {}
    for listing in listings:
        for frame, what in listing.at:
            found.setdefault(frame, {}).setdefault(listing.kind, []).append(what)
    marks = []
    for frame in sorted(found):
        of_frame = found[frame]
        present = [e for e in listings if e.kind in of_frame]
        text = "; ".join(_item(e, of_frame[e.kind]) for e in present)
        marks.append(ErrorMark(frame, tuple(e.kind for e in present), f"frame {frame}: {text}"))
    return tuple(marks)


def slider_marks(
    marks: Sequence[ErrorMark], limit: int = MAX_LABELLED_MARKS
) -> tuple[SliderMark, ...]:
    """The marks as viser's slider `marks`: (frame, label) for a labelled mark, the bare
    frame for one without a label.

    Every frame is a mark. When there are more than `limit` marks, only `limit` of them keep
    their label, spread evenly over the list: mark k of n is labelled when k = floor((j + 1/2)
    n / limit) for some j in 0 .. limit - 1 (the middles of `limit` equal parts of the list),
    so the labels stay readable and the ticks still show every frame with an error.
    """
    if limit < 0:
        raise ValueError(f"limit: expected a number of labels >= 0, got {limit}")
    n = len(marks)
    if n <= limit:
        return tuple((m.frame, m.label) for m in marks)
    labelled = {int((j + 0.5) * n / limit) for j in range(limit)}
    return tuple((m.frame, m.label) if k in labelled else m.frame for k, m in enumerate(marks))
