"""One browser tab: its controls, its `ViewState`, its playback thread, its panels.

Controls only replace the state and ask for a render; the render worker runs the engine and
draws, and `show_view` puts the finished pictures, read-out, timings, CAN plot and A/B list
on the page in one atomic update. Parameter changes go through the tab's
`app.param_sets.ParamSets` (undo, redo, presets, A and B).
"""

from __future__ import annotations

import functools
import logging
import threading
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import replace

import viser
import viser.uplot

from app.annotate import AnnotationPanel
from app.bird_eye import BirdEyeViews
from app.clip_export import EXPORT_KINDS
from app.history import History
from app.metrics import SliderMark
from app.metrics_panel import Evaluate, MetricsPanel
from app.page_url import copy_page_url, read_page, show_query
from app.param_sets import ParamSets, Sets
from app.params_panel import NoticeColour, ParamsPanel
from app.player import Pacer, Player, Rest
from app.presets import PresetStore
from app.state import INSPECTOR_LAYERS, Layers, Panels, ViewState
from app.view import (
    CAN_WINDOW_HALF_S,
    OVERLAY_OF_LAYER,
    STAGE_TITLES,
    CanSeries,
    FrameView,
    can_window,
    median_timings,
    timings_markdown,
)
from app.view_link import Clip, ViewLink, link_query, parse_clip
from core.annotation.store import AnnotationStore
from core.engine import StageTimings
from core.params import ParamsError

CAMERA_PANEL_WIDTH_PX = 680
WAITING_TEXT = "rendering…"
MARKDOWN_SPECIALS = "\\`*_{}[]<>()#+-.!|~"
PLAYBACK_RATES = ("0.25x", "0.5x", "1x", "2x", "4x")  # of the drive's own frame rate
# the layers' checkbox labels: the overlays' own names
LAYER_LABELS = {**OVERLAY_OF_LAYER, "truth": "ground truth"}
PANEL_LABELS = {"bird_eye": "bird's-eye view (3D)", "can": "CAN speed and yaw rate"}
# the right-hand panel, top to bottom
STAGE_CHOICE_ORDER, CAMERA_ORDER, DIFF_ORDER, TIMINGS_ORDER, CAN_ORDER = range(5)
ANNOTATION_ORDER = 6.5  # the Annotation folder: after Metrics (6), before Keys (7)
DEMO_ORDER = 2.5  # the Share and demo folder: under the Timeline (2)
TIMINGS_WINDOW = 50  # frames in the running median of the stage timings
# While playing, the frame slider, the read-out and the CAN plot follow the playhead at most
# this often: every update re-renders them in the page, which at 40 frames/s kept the page
# from decoding the pictures (the camera picture's caption carries the read-out of its own
# frame). They show the playhead exactly again when playback stops.
PLAYHEAD_PERIOD_S = 0.2
# The page's URL follows the view once it has rested this long (and at once when a tab opens a
# view or copies its link): the script that sets it is a message viser's page applies in its
# 3D render loop, which then draws the scene for 250 ms, so one per seek or parameter change
# held up the pictures of the next (headless Chromium without a GPU: 30-40 ms of each).
LINK_REST_S = 0.5
NOTICE_SECONDS = 8.0
# (recording, kind, clip, state, progress) -> (file name, bytes): `app.clip_export.export_clip`
Exporter = Callable[[str, str, Clip, ViewState, Callable[[int, int], None]], tuple[str, bytes]]
log = logging.getLogger(__name__)


def _run_command(action: Callable[[], object], _: object) -> None:
    action()


def escape_markdown(text: str) -> str:
    """`text` shown literally by the markdown widget (file paths, reader messages)."""
    return "".join("\\" + c if c in MARKDOWN_SPECIALS else c for c in text)


class ClientSession:
    """The inspector as one client sees it.

    `on_pick_recording(session, name)` is called when the client picks another recording;
    the server answers with `show_drive` or `show_error`. `show_drive` gets `request`, which
    hands a state snapshot to the drive's render worker.
    """

    def __init__(
        self,
        client: viser.ClientHandle,
        recordings: list[str],
        selected: str | None,
        on_pick_recording: Callable[[ClientSession, str], None],
        presets: PresetStore,
        on_present: Callable[[ClientSession], None],
        exporter: Exporter,
    ) -> None:
        self.client = client
        self.recording: str | None = None
        self._lock = threading.RLock()
        self._state = ViewState()
        self._frame_count = 0
        self._frame_rate_hz = 0.0
        self._request: Callable[[ViewState], None] | None = None
        self._player = Player(f"player-{client.client_id}")
        self._on_pick_recording = on_pick_recording
        self._on_present = on_present
        self._exporter = exporter
        self._exporting = False  # one export per tab at a time
        self._clip: Clip | None = None  # None: the whole drive
        self._shown_query = ""  # the page URL's query, as last set
        self._can: CanSeries | None = None
        self._slider_pace = Pacer(PLAYHEAD_PERIOD_S)
        self._readout_pace = Pacer(PLAYHEAD_PERIOD_S)  # the read-out and the CAN plot
        self._link_rest = Rest(LINK_REST_S, self._show_link, f"link-{client.client_id}")
        self._recent_timings: deque[StageTimings] = deque(maxlen=TIMINGS_WINDOW)
        self._history = History()  # parameter changes and annotation edits, one stack
        self._param_sets = ParamSets(presets, self._history, self._set_params)

        gui = client.gui
        self._message = gui.add_markdown("", order=0)
        self._picker = gui.add_dropdown(
            "recording",
            tuple(recordings) or ("(none)",),
            initial_value=selected or (recordings[0] if recordings else "(none)"),
            disabled=not recordings,
            order=1,
        )
        self._picker.on_update(lambda _: self._on_pick_recording(self, self._picker.value))
        self._timeline: viser.GuiFolderHandle | None = None
        self._demo: viser.GuiFolderHandle | None = None
        self._slider: viser.GuiSliderHandle[int] | None = None
        self._play: viser.GuiButtonHandle | None = None
        self._readout: viser.GuiMarkdownHandle | None = None
        self._rate: viser.GuiDropdownHandle[str] | None = None

        with gui.add_folder("Layers", order=3):
            self._layer_boxes = {
                name: gui.add_checkbox(LAYER_LABELS[name], getattr(self._state.layers, name))
                for name in Layers.names()
            }
        for box in self._layer_boxes.values():
            box.on_update(lambda _: self._set_layers())
        with gui.add_folder("Panels", order=4, expand_by_default=False):
            self._panel_boxes = {
                name: gui.add_checkbox(PANEL_LABELS[name], getattr(self._state.panels, name))
                for name in Panels.switches()
            }
        for box in self._panel_boxes.values():
            box.on_update(lambda _: self._set_panels())
        self._params_panel = ParamsPanel(gui, self._param_sets, self.notify, order=5)
        self._annotation = AnnotationPanel(
            client,
            self._history,
            self.notify,
            ANNOTATION_ORDER,
            self._set_annotating,
            lambda: self._state.params,
        )
        self._add_commands(gui)

        gui.main_panel.dock_left()
        self._camera_panel = gui.add_panel()
        self._camera_tab = self._camera_panel.add_tab("Camera")
        with self._camera_tab:
            self._stage_choice = gui.add_dropdown(
                "stage",
                tuple(STAGE_TITLES.values()),
                initial_value=STAGE_TITLES[self._state.panels.stage],
                hint="the stage picture under the camera (only what is shown is drawn)",
                order=STAGE_CHOICE_ORDER,
            )
        self._stage_choice.on_update(lambda _: self._set_panels())
        self._camera_panel.dock_right()
        self._camera_panel.set_width(CAMERA_PANEL_WIDTH_PX)
        self._image: viser.GuiImageHandle | None = None
        self._diff: viser.GuiMarkdownHandle | None = None
        self._can_plot: viser.GuiUplotHandle | None = None
        self._can_frame = -1  # the frame the CAN plot is around
        self._timings: viser.GuiMarkdownHandle | None = None
        self._metrics: MetricsPanel | None = None
        self._bird_eyes = BirdEyeViews(client)

    # --- what the server tells this client ----------------------------------------------
    def show_error(self, headline: str, detail: str = "") -> None:
        """Replace the drive controls with a message saying what is wrong."""
        self._drop_drive()
        self._camera_panel.visible = False
        first, _, rest = detail.partition("\n")
        text = f"**{escape_markdown(headline)}**\n\n{escape_markdown(first)}"
        if rest.strip():
            text += f"\n\n```text\n{rest}\n```"
        self._message.content = text

    def show_drive(
        self,
        name: str,
        frame_count: int,
        frame_rate_hz: float,
        request: Callable[[ViewState], None],
        notes: Sequence[str] = (),
        can: CanSeries | None = None,
        evaluate: Evaluate | None = None,
        annotations: AnnotationStore | None = None,
        link: ViewLink | None = None,
    ) -> None:
        """Build the timeline for a drive of `frame_count` frames and render its first frame
        (or the view `link` describes: frame, clip, layers, panels, parameter sets).

        notes: what the viewer should know about the recording (assumptions, what was skipped
        on reading), listed under its name. can: its CAN signals for the plot. evaluate:
        scores the whole drive under some parameters (None: the drive has no ground truth).
        annotations: the recording's annotation store (None: it cannot be annotated).
        """
        self._drop_drive()
        gui = self.client.gui
        with self._lock:
            self.recording = name
            self._frame_count = frame_count
            self._frame_rate_hz = frame_rate_hz
            self._request = request
            self._state = replace(self._state, frame=0, playing=False)
            self._can = can
            self._recent_timings.clear()
        self._annotation.open(annotations, frame_count)
        self._camera_panel.visible = True
        self._message.content = (
            f"**{escape_markdown(name)}** — {frame_count} frames at {frame_rate_hz:.1f} Hz"
        ) + "".join(f"\n\n- {escape_markdown(note)}" for note in notes)
        if frame_count == 0:
            return
        duration_s = (frame_count - 1) / frame_rate_hz if frame_rate_hz > 0 else 0.0
        with gui.add_folder("Timeline", order=2) as self._timeline:
            self._add_frame_slider(())
            self._play = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY)
            step_back = gui.add_button("Step -1", icon=viser.Icon.CHEVRON_LEFT)
            step_on = gui.add_button("Step +1", icon=viser.Icon.CHEVRON_RIGHT)
            self._rate = gui.add_dropdown("rate", PLAYBACK_RATES, initial_value="1x")
            jump = gui.add_number(
                "go to time s", 0.0, min=0.0, max=duration_s, step=0.1, hint="seconds from start"
            )
            self._readout = gui.add_markdown(WAITING_TEXT)
        jump.on_update(
            lambda event: (
                self.go_to(round(event.target.value * frame_rate_hz))
                if event.client is not None
                else None
            )
        )
        self._metrics = MetricsPanel(
            gui,
            6,
            evaluate,
            lambda: self._state.params,
            self._set_marks,
            self.go_to,
            lambda: self._state.frame,
        )
        self._play.on_click(lambda _: self.set_playing(not self._state.playing))
        step_back.on_click(lambda _: self.step(-1))
        step_on.on_click(lambda _: self.step(+1))
        self._add_demo_folder(gui)
        if link is None:
            self._submit()
        else:
            self._open_link(link)
        self._show_link()

    def link(self) -> ViewLink:
        """What this tab shows, as a view link."""
        s = self._state
        return ViewLink(
            self.recording, s.frame, s.layers, s.panels, s.params, s.params_b, self._clip
        )

    def _open_link(self, link: ViewLink) -> None:
        """Show the view `link` describes on the open drive (its frame and clip clamped)."""
        last = self._frame_count - 1
        if link.clip is not None and link.clip[1] <= last:
            self._set_clip(link.clip)
        elif link.clip is not None:
            clip = f"{link.clip[0]}-{link.clip[1]}"
            self.notify(
                "Clip left out", f"clip: expected frames up to {last}, got {clip}", "yellow"
            )
        for name, box in self._layer_boxes.items():
            box.value = getattr(link.layers or INSPECTOR_LAYERS, name)  # type: ignore[misc]
        panels = link.panels or Panels()
        for name, box in self._panel_boxes.items():
            box.value = getattr(panels, name)  # type: ignore[misc]
        self._stage_choice.value = STAGE_TITLES[panels.stage]  # type: ignore[misc]
        self._param_sets.open_link(link.params, link.params_b)
        self.go_to(min(link.frame or 0, last))
        self._submit()

    def _add_demo_folder(self, gui: viser.GuiApi) -> None:
        """Share this view, present it, export the clip."""
        with gui.add_folder("Share and demo", order=DEMO_ORDER, expand_by_default=False) as f:
            self._demo = f
            self._clip_field = gui.add_text(
                "clip frames",
                f"0-{self._frame_count - 1}",
                hint="first-last frame the presenter loops over and the exports cover",
            )
            copy = gui.add_button("Copy link", icon=viser.Icon.LINK)
            self._link_text = gui.add_markdown("")
            present = gui.add_button("Present this view", icon=viser.Icon.PRESENTATION)
            exports = {
                kind: gui.add_button(label, icon=viser.Icon.DOWNLOAD)
                for kind, label in EXPORT_KINDS.items()
            }
        for kind, button in exports.items():
            button.on_click(functools.partial(lambda kind, _: self._export(kind), kind))
        self._clip_field.on_update(lambda event: self._clip_typed(event.target.value))
        copy.on_click(lambda _: self._copy_link())
        present.on_click(lambda _: self._on_present(self))

    def _export(self, kind: str) -> None:
        """Export the clip as `kind` on a thread; the browser downloads the file."""
        with self._lock:
            if self._exporting or self.recording is None or self._demo is None:
                if self._exporting:
                    self.notify("An export is running", "wait for it to finish", "gray")
                return
            self._exporting = True
            recording, state, folder = self.recording, self._state, self._demo
        clip = self._clip or (0, self._frame_count - 1)
        threading.Thread(
            target=self._run_export,
            args=(recording, kind, clip, state, folder),
            name=f"export-{self.client.client_id}",
            daemon=True,
        ).start()

    def _run_export(
        self, recording: str, kind: str, clip: Clip, state: ViewState, folder: viser.GuiFolderHandle
    ) -> None:
        with folder:
            bar = self.client.gui.add_progress_bar(0.0, animated=True)

        def progress(done: int, total: int) -> None:
            bar.value = 100.0 * done / max(total, 1)  # type: ignore[misc]  # viser: asymmetric property

        try:
            name, data = self._exporter(recording, kind, clip, state, progress)
            self.client.send_file_download(name, data, save_immediately=True)
            self.notify("Exported", f"{name}: {len(data) / 1e6:.1f} MB", "green")
        except Exception as err:  # the page says so; the log keeps the traceback
            log.exception("exporting %s of %s failed", kind, recording)
            self.notify("The export failed", f"{type(err).__name__}: {err}")
        finally:
            bar.remove()
            with self._lock:
                self._exporting = False

    def _clip_typed(self, text: str) -> None:
        try:
            clip = parse_clip(text.strip())
            if clip[1] >= self._frame_count:
                raise ValueError(f"expected frames up to {self._frame_count - 1}, got {text!r}")
        except ValueError as err:
            self.notify("Clip not changed", f"clip frames: {err}")
            return
        self._set_clip(clip)
        self._link_rest.poke()

    def _set_clip(self, clip: Clip) -> None:
        self._clip = None if clip == (0, self._frame_count - 1) else clip
        text = f"{clip[0]}-{clip[1]}"
        if self._clip_field.value != text:
            self._clip_field.value = text  # type: ignore[misc]

    def _copy_link(self) -> None:
        self._show_link()
        copy_page_url(self.client)
        try:
            url = read_page(self.client, "location.href")
        except (TimeoutError, RuntimeError) as err:
            self.notify("The link could not be read", str(err))
            return
        self._link_text.content = f"Copied: `{url}`"

    def _show_link(self) -> None:
        """Make the page's URL carry this view (not while playing: it changes every frame)."""
        with self._lock:
            if self._state.playing or self.recording is None:
                return
            query = link_query(self.link())
            if query == self._shown_query:
                return
            self._shown_query = query
        show_query(self.client, query)

    def show_view(self, recording: str, view: FrameView) -> None:
        """Put a rendered frame and its read-out on the page together (if still wanted)."""
        if recording != self.recording or self._readout is None:
            return
        gui = self.client.gui
        self._recent_timings.append(view.timings)
        with self.client.atomic():
            if self._image is None:
                with self._camera_tab:
                    self._image = gui.add_image(view.with_stage, format="jpeg", order=CAMERA_ORDER)
                    self._diff = gui.add_markdown("", order=DIFF_ORDER)
            else:
                self._image.image = view.with_stage
            if self._diff is not None and self._diff.content != view.diff:
                self._diff.content = view.diff
            readout = self._due(self._readout_pace)
            if readout:
                self._show_can(view.frame)
            self._show_stage(view)
            self._bird_eyes.show(view.bird_eyes, self._state.params)
            if readout:
                self._readout.content = f"`{view.readout}`"
        # out at once: viser otherwise sends the next batch up to 1/60 s after the one before
        self.client.flush()
        if view.annotation is not None:
            self._annotation.show_frame(view.frame, *view.annotation)

    def _show_can(self, frame: int) -> None:
        """The CAN plot around `frame` (removed when switched off; none without CAN; not sent
        again for the frame it shows, as after a parameter change)."""
        if not self._state.panels.can or self._can is None:
            if self._can_plot is not None:
                self._can_plot.remove()
                self._can_plot = None
            return
        if self._can_plot is not None and frame == self._can_frame:
            return
        self._can_frame = frame
        data = can_window(self._can, frame)
        if self._can_plot is not None:
            self._can_plot.data = data
            return
        half = CAN_WINDOW_HALF_S
        with self._camera_tab:
            self._can_plot = self.client.gui.add_uplot(
                data,
                (
                    viser.uplot.Series(label="s from the playhead"),
                    viser.uplot.Series(label="speed km/h", stroke="#1f77b4", width=2, scale="kmh"),
                    viser.uplot.Series(label="yaw deg/s", stroke="#d62728", width=2, scale="degps"),
                ),
                title="CAN speed and yaw rate; the playhead is at 0 s",
                scales={
                    "x": {"time": False, "range": (-half, half)},
                    "kmh": {"auto": True},
                    "degps": {"auto": True},
                },
                axes=(
                    {"label": "s from the playhead"},
                    {"scale": "kmh", "label": "km/h"},
                    {"scale": "degps", "label": "deg/s", "side": 1},
                ),
                aspect=4.0,
                order=CAN_ORDER,
            )

    def _show_stage(self, view: FrameView) -> None:
        """The timings table under the camera, when it is the stage chosen (a stage picture
        is part of the camera picture, `FrameView.with_stage`)."""
        gui = self.client.gui
        if self._state.panels.stage == "timings":
            median = median_timings(self._recent_timings)
            table = timings_markdown(view.timings, median, len(self._recent_timings))
            if self._timings is None:
                with self._camera_tab:
                    self._timings = gui.add_markdown(table, order=TIMINGS_ORDER)
            else:
                self._timings.content = table
        elif self._timings is not None:
            self._timings.remove()
            self._timings = None

    def show_frame_error(self, recording: str, frame: int, what: str, message: str) -> None:
        """Say in the read-out what went wrong with `frame` (the image keeps the last frame)."""
        if recording != self.recording or self._readout is None:
            return
        self._readout.content = f"**frame {frame} {what}:** {escape_markdown(message)}"

    # --- controls -> state ----------------------------------------------------------------
    def go_to(self, frame: int) -> None:
        """Show `frame` (clamped to the drive)."""
        with self._lock:
            if self._frame_count == 0:
                return
            frame = min(max(frame, 0), self._frame_count - 1)
            if frame == self._state.frame:
                return
            self._state = replace(self._state, frame=frame)
        if self._slider is not None and self._due(self._slider_pace):
            self._slider.value = frame  # type: ignore[misc]  # mypy: asymmetric viser property
        self._submit()

    def step(self, delta: int) -> None:
        self.go_to(self._state.frame + delta)

    def set_playing(self, playing: bool) -> None:
        """Start or stop playback at the drive's frame rate; playing from the end starts over."""
        if playing and self._state.frame == self._frame_count - 1:
            self.go_to(0)
        with self._lock:
            if playing == self._state.playing or self._frame_count == 0:
                return
            self._state = replace(self._state, playing=playing)
            if playing:
                self._player.start(self._frame_period_s, self._play_step)
            else:
                self._player.stop()
        if self._play is not None:
            self._play.label = "Pause" if playing else "Play"
            self._play.icon = viser.Icon.PLAYER_PAUSE if playing else viser.Icon.PLAYER_PLAY
        if not playing:
            self._show_playhead()  # and the link to where playback stopped

    def notify(self, title: str, message: str, color: NoticeColour = "red") -> None:
        """A notification in this tab's page (a refused value, a saved preset)."""
        self.client.add_notification(title, message, color=color, auto_close_seconds=NOTICE_SECONDS)

    def close(self) -> None:
        """The client left: stop playback."""
        self._player.stop()
        self._link_rest.cancel()

    # --- internals ---------------------------------------------------------------------
    def _due(self, pace: Pacer) -> bool:
        """Whether to update a playhead indicator now: always unless playing."""
        return not self._state.playing or pace.due()

    def _show_playhead(self) -> None:
        """The frame slider at the playhead, and the frame rendered again for the read-out
        and the CAN plot (after playback)."""
        frame = self._state.frame
        if self._slider is not None and self._slider.value != frame:
            self._slider.value = frame  # type: ignore[misc]  # mypy: asymmetric viser property
        self._submit()

    def _frame_period_s(self) -> float:
        """Between two frames at the chosen rate of the drive's frame rate."""
        rate = self._rate
        factor = 1.0 if rate is None else float(rate.value.rstrip("x"))
        return 1.0 / (self._frame_rate_hz * factor)

    def _play_step(self) -> bool:
        """One frame on; at the last frame, pause and stop the player."""
        if self._state.frame >= self._frame_count - 1:
            self.set_playing(False)
            return False
        self.step(+1)
        return True

    def _add_commands(self, gui: viser.GuiApi) -> None:
        """Keyboard commands (viser's command palette) and a panel that lists them."""
        sets = self._param_sets
        # (label, key, modifier, action)
        keys: list[tuple[str, str, str | None, Callable[[], object]]] = [
            ("Play / pause", "space", None, self._toggle_playing),
            ("Step back one frame", "arrowleft", None, functools.partial(self.step, -1)),
            ("Step on one frame", "arrowright", None, functools.partial(self.step, +1)),
            ("Go to the first frame", "home", None, functools.partial(self.go_to, 0)),
            ("Go to the last frame", "end", None, self._go_to_end),
            ("Undo (parameters and annotations)", "Z", "cmd/ctrl", self._undo),
            ("Redo (parameters and annotations)", "Z", "cmd/ctrl+shift", self._redo),
            ("Compare with B on / off", "C", None, self._toggle_comparing),
            ("Swap A and B", "S", None, functools.partial(self._guarded, sets.swap)),
        ]
        keys += [
            (
                f"Toggle layer: {LAYER_LABELS[name]}",
                str(k),
                None,
                functools.partial(self._toggle_layer, name),
            )
            for k, name in zip("1234567890", Layers.names(), strict=False)
        ]
        lines = ["| key | does |", "| --- | --- |"]
        for label, hotkey, modifier, action in keys:
            command = gui.add_command(label, hotkey=hotkey, modifier=modifier)  # type: ignore[arg-type]
            command.on_trigger(functools.partial(_run_command, action))
            shown = (
                hotkey if modifier is None else f"{modifier.replace('cmd/ctrl', 'Ctrl')}+{hotkey}"
            )
            lines.append(f"| {shown} | {label} |")
        with gui.add_folder("Keys", order=7, expand_by_default=False):
            gui.add_markdown(
                "\n".join(lines) + "\n\nThe command palette (Ctrl+K / Cmd+K) lists them too."
            )

    def _guarded(self, action: Callable[[], object]) -> None:
        """Run a parameter action from a key; a refusal becomes a notification."""
        try:
            action()
        except ParamsError as err:
            self.notify("Not possible", str(err))

    def _undo(self) -> None:
        if self._history.undo() is None:
            self.notify("Nothing to undo", "no parameter change or annotation left to undo", "gray")

    def _redo(self) -> None:
        if self._history.redo() is None:
            self.notify("Nothing to redo", "nothing undone to redo", "gray")

    def _set_annotating(self, on: bool) -> None:
        with self._lock:
            self._state = replace(self._state, annotating=on)
        self._submit()

    def _toggle_comparing(self) -> None:
        self._param_sets.set_comparing(self._param_sets.sets.b is None)

    def _toggle_playing(self) -> None:
        self.set_playing(not self._state.playing)

    def _go_to_end(self) -> None:
        self.go_to(self._frame_count - 1)

    def _toggle_layer(self, name: str) -> None:
        box = self._layer_boxes[name]
        box.value = not box.value  # type: ignore[misc]  # its update callback sets the layers

    def _set_params(self, sets: Sets) -> None:
        """The parameter sets changed (an edit, undo, redo, a preset): show and run them."""
        with self._lock:
            self._state = replace(self._state, params=sets.a, params_b=sets.b)
        self._params_panel.show(sets)
        self._submit()

    def _set_marks(self, marks: tuple[SliderMark, ...]) -> None:
        """Marks under the frame slider (viser sets a slider's marks when it is made, so the
        slider is made again in the same place)."""
        with self._lock:
            old, timeline = self._slider, self._timeline
            if old is None or timeline is None:
                return
            with timeline:
                self._add_frame_slider(marks, old.order)
            old.remove()

    def _add_frame_slider(self, marks: tuple[SliderMark, ...], order: float | None = None) -> None:
        """The timeline's frame slider at the current frame, in the current GUI container."""
        self._slider = self.client.gui.add_slider(
            "frame",
            0,
            max(self._frame_count - 1, 0),
            1,
            self._state.frame,
            marks=marks or None,
            order=order,
        )
        self._slider.on_update(lambda event: self.go_to(event.target.value))

    def _set_panels(self) -> None:
        stage = next(k for k, title in STAGE_TITLES.items() if title == self._stage_choice.value)
        switches = {name: box.value for name, box in self._panel_boxes.items()}
        panels = Panels(**switches, stage=stage)
        with self._lock:
            self._state = replace(self._state, panels=panels)
        self._submit()

    def _set_layers(self) -> None:
        layers = Layers(**{name: box.value for name, box in self._layer_boxes.items()})
        with self._lock:
            self._state = replace(self._state, layers=layers)
        self._submit()

    def _submit(self) -> None:
        with self._lock:
            request, state = self._request, self._state
        if request is not None:
            request(state)
            if not state.playing:  # not while playing: stopping submits the frame again
                self._link_rest.poke()

    def _drop_drive(self) -> None:
        self.set_playing(False)
        with self._lock:
            self.recording = None
            self._request = None
            self._frame_count = 0
        if self._timeline is not None:
            self._timeline.remove()
        if self._demo is not None:
            self._demo.remove()
            self._demo = None
        if self._metrics is not None:
            self._metrics.remove()
            self._metrics = None
        for handle in (self._image, self._diff, self._can_plot, self._timings):
            if handle is not None:
                handle.remove()
        self._bird_eyes.remove()
        self._timeline = self._slider = self._play = self._readout = self._image = None
        self._timings = self._rate = self._diff = self._can_plot = None
