"""The "Metrics" folder of one tab: the evaluation of the whole drive under set A, on request.

"Evaluate the drive" runs `evaluate(params, progress)` on a background thread with a
progress bar; the page stays live meanwhile. When it is done the folder shows the
evaluation's tables (`app.metrics.metrics_markdown`), and for the kind of error chosen
(vehicle FN by default: on the bundled drives some error is listed on nearly every frame,
so all kinds at once would mark every frame) the frames with it become marks on the
timeline (`on_marks`), a jump list, and "previous" / "next" buttons (`on_jump(frame)`).
A failed evaluation is said in the folder; the log keeps the traceback.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Sequence

import viser

from app.metrics import (
    ERROR_KINDS,
    ErrorMark,
    SliderMark,
    error_marks,
    metrics_markdown,
    slider_marks,
)
from core.evaluation.evaluate import RecordingReport
from core.params import Params

log = logging.getLogger(__name__)

Evaluate = Callable[[Params, Callable[[int, int], None]], RecordingReport]
DEFAULT_KIND = "vehicle FN"
NO_MARK = "(no frame with this error)"
PICK = "(pick a frame)"
LABELLED_MARKS = 4  # slider labels that stay readable in the side panel
PROGRESS_STEP_PERCENT = 2.0  # the bar is updated at most this often


class MetricsPanel:
    """The Metrics folder for one drive. evaluate: None when the drive has no ground truth
    (the folder says so); params: set A when the button is pressed; on_marks(slider marks)
    and on_jump(frame) act on the timeline; frame(): the frame shown now."""

    def __init__(
        self,
        gui: viser.GuiApi,
        order: float,
        evaluate: Evaluate | None,
        params: Callable[[], Params],
        on_marks: Callable[[tuple[SliderMark, ...]], None],
        on_jump: Callable[[int], None],
        frame: Callable[[], int],
    ) -> None:
        self._gui = gui
        self._evaluate = evaluate
        self._params = params
        self._on_marks = on_marks
        self._on_jump = on_jump
        self._frame = frame
        self._report: RecordingReport | None = None
        self._marks: tuple[ErrorMark, ...] = ()
        self._running = threading.Lock()
        self.folder = gui.add_folder("Metrics", order=order, expand_by_default=False)
        with self.folder:
            if evaluate is None:
                gui.add_markdown(
                    "This drive has no ground truth (`groundtruth.json`): nothing to score."
                )
                return
            self._button = gui.add_button("Evaluate the drive under A", icon=viser.Icon.CHART_BAR)
            self._progress = gui.add_progress_bar(0.0, visible=False)
            self._kind = gui.add_dropdown("mark", ERROR_KINDS, initial_value=DEFAULT_KIND)
            self._jump = gui.add_dropdown("jump to", (NO_MARK,))
            steps = gui.add_button_group("errors", ("Previous", "Next"))
            self._tables = gui.add_markdown("")
        self._button.on_click(lambda _: self._start())
        self._kind.on_update(lambda _: self._show_marks())
        self._jump.on_update(
            lambda event: self._jump_to(event.target.value) if event.client else None
        )
        steps.on_click(lambda event: self._step(+1 if event.target.value == "Next" else -1))

    def remove(self) -> None:
        self.folder.remove()

    # --- evaluation --------------------------------------------------------------------
    def _start(self) -> None:
        if self._evaluate is None or not self._running.acquire(blocking=False):
            return  # one evaluation at a time
        self._button.disabled = True
        self._progress.value = 0.0  # type: ignore[misc]  # asymmetric viser property
        self._progress.visible = True
        self._tables.content = "evaluating…"
        threading.Thread(target=self._run, args=(self._params(),), daemon=True).start()

    def _run(self, params: Params) -> None:
        assert self._evaluate is not None
        shown = [0.0]

        def progress(done: int, total: int) -> None:
            percent = 100.0 * done / max(total, 1)
            if percent - shown[0] >= PROGRESS_STEP_PERCENT or done == total:
                shown[0] = percent
                self._progress.value = percent  # type: ignore[misc]

        try:
            report = self._evaluate(params, progress)
        except Exception as err:  # the folder says so; the log keeps the traceback
            log.exception("evaluation failed")
            self._tables.content = f"**The evaluation failed:** {type(err).__name__}: {err}"
        else:
            self._report = report
            self._tables.content = metrics_markdown(report)
            self._show_marks()
        finally:
            self._progress.visible = False
            self._button.disabled = False
            self._running.release()

    # --- marks --------------------------------------------------------------------------
    def _show_marks(self) -> None:
        if self._report is None:
            return
        self._marks = error_marks(self._report, (self._kind.value,))
        texts = tuple(m.text for m in self._marks)
        self._jump.options = (PICK, *texts) if texts else (NO_MARK,)
        self._on_marks(slider_marks(self._marks, LABELLED_MARKS))

    def _jump_to(self, text: str) -> None:
        frames = [m.frame for m in self._marks if m.text == text]
        if frames:
            self._on_jump(frames[0])

    def _step(self, direction: int) -> None:
        """To the next (+1) or previous (-1) marked frame from the one shown."""
        now = self._frame()
        frames: Sequence[int] = [m.frame for m in self._marks]
        ahead = [f for f in frames if (f - now) * direction > 0]
        if ahead:
            self._on_jump(min(ahead) if direction > 0 else max(ahead))
