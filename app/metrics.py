"""What the inspector's Metrics panel shows of one drive's evaluation: pure functions over a
`core.evaluation.evaluate.RecordingReport`, no viser.

- `metrics_markdown`: the evaluation's summary tables, as `fusionscope evaluate --format
  markdown` prints them (the error listings are the marks below instead);
- `error_marks`: one `ErrorMark` per frame with an error the evaluation lists under "Where
  the errors are", for a jump list;
- `slider_marks`: those frames as a viser slider's `marks`, labelled with short codes.

The errors, in `ERROR_KINDS` order (the listings of `core.evaluation.report.tables`):

    kind           listing                                   ids in the text
    vehicle FN     report.vehicles.fn_at                     truth ids
    vehicle RFN    report.vehicles.rfn_at                    truth ids
    vehicle FP     report.vehicles.fp_at                     radar targets
    guard-rail FN  report.guardrails.fn_at                   radar targets
    guard-rail FP  report.guardrails.fp_at                   radar targets
    pedestrian FN  report.pedestrians["vehicles"].missed_at  truth ids
    pedestrian FP  report.pedestrians["vehicles"].false_at   none: counted

Pedestrians are those after both fusion filters; the guard-rail FP include the vehicles
labelled guard rail.

NVO are right answers, and the tracked output's listings repeat the detections' frames:
neither is marked. The listings' frame indices are the recording's own, so a report of one
recording is expected (a total's listings mix recordings).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass

from core.evaluation.evaluate import RecordingReport
from core.evaluation.report import format_markdown, tables

Listing = tuple[tuple[int, int], ...]
SliderMark = int | tuple[int, str]


@dataclass(frozen=True)
class _Kind:
    """One kind of error: where the report lists it and how a person reads it.

    code: the short code of a slider label; one, many: the text before the ids of one error
    and of several on a frame; ids: the text names the ids (else it counts the errors).
    """

    name: str
    code: str
    listing: Callable[[RecordingReport], Listing]
    one: str
    many: str
    ids: bool = True


_KINDS = (
    _Kind("vehicle FN", "FN", lambda r: r.vehicles.fn_at, "FN vehicle", "FN vehicles"),
    _Kind("vehicle RFN", "RFN", lambda r: r.vehicles.rfn_at, "RFN vehicle", "RFN vehicles"),
    _Kind(
        "vehicle FP",
        "FP",
        lambda r: r.vehicles.fp_at,
        "FP vehicle from radar target",
        "FP vehicles from radar targets",
    ),
    _Kind(
        "guard-rail FN",
        "FN",
        lambda r: r.guardrails.fn_at,
        "FN guard rail at radar target",
        "FN guard rail at radar targets",
    ),
    _Kind(
        "guard-rail FP",
        "FP",
        lambda r: r.guardrails.fp_at,
        "FP guard rail at radar target",
        "FP guard rail at radar targets",
    ),
    _Kind(
        "pedestrian FN",
        "FN",
        lambda r: r.pedestrians["vehicles"].missed_at,
        "FN pedestrian",
        "FN pedestrians",
    ),
    _Kind(
        "pedestrian FP",
        "FP",
        lambda r: r.pedestrians["vehicles"].false_at,
        "FP pedestrian",
        "FP pedestrians",
        ids=False,
    ),
)
ERROR_KINDS: tuple[str, ...] = tuple(k.name for k in _KINDS)
CODE_OF_KIND: dict[str, str] = {k.name: k.code for k in _KINDS}
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


def _item(kind: _Kind, ids: Sequence[int]) -> str:
    if not kind.ids:
        return kind.one if len(ids) == 1 else f"{len(ids)} {kind.many}"
    joined = ", ".join(str(i) for i in sorted(ids))
    return f"{kind.one if len(ids) == 1 else kind.many} {joined}"


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
    found: dict[int, dict[str, list[int]]] = {}
    for kind in (k for k in _KINDS if k.name in kinds):
        for frame, what in kind.listing(report):
            found.setdefault(frame, {}).setdefault(kind.name, []).append(what)
    marks = []
    for frame in sorted(found):
        of_frame = found[frame]
        present = [k for k in _KINDS if k.name in of_frame]
        text = "; ".join(_item(k, of_frame[k.name]) for k in present)
        marks.append(ErrorMark(frame, tuple(k.name for k in present), f"frame {frame}: {text}"))
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
