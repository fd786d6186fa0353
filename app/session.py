"""One browser tab: its controls, its `ViewState`, its playback thread, its panels.

Controls only replace the state and ask for a render; the render worker runs the engine and
draws, and `show_view` puts the finished pictures, read-out and timings on the page in one
atomic update.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Sequence
from dataclasses import replace

import viser

from app.params_panel import ParamsPanel
from app.state import Layers, ViewState
from app.view import OVERLAY_OF_LAYER, FrameView, timings_markdown
from core.params import Params, ParamsError

CAMERA_PANEL_WIDTH_PX = 680
WAITING_TEXT = "rendering…"
MARKDOWN_SPECIALS = "\\`*_{}[]<>()#+-.!|~"
PLAYBACK_RATES = ("0.25x", "0.5x", "1x", "2x", "4x")  # of the drive's own frame rate
# the layers' checkbox labels: the overlays' own names
LAYER_LABELS = {**OVERLAY_OF_LAYER, "truth": "ground truth"}


def _run_command(action: Callable[[], None], _: object) -> None:
    action()


def _escape_markdown(text: str) -> str:
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
    ) -> None:
        self.client = client
        self.recording: str | None = None
        self._lock = threading.RLock()
        self._state = ViewState()
        self._frame_count = 0
        self._frame_rate_hz = 0.0
        self._request: Callable[[ViewState], None] | None = None
        self._stop_playing = threading.Event()
        self._player: threading.Thread | None = None
        self._on_pick_recording = on_pick_recording

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
        self._params_panel = ParamsPanel(gui, self.set_parameter, self.reset_parameters, order=4)
        self._add_commands(gui)

        gui.main_panel.dock_left()
        self._camera_panel = gui.add_panel()
        self._camera_tab = self._camera_panel.add_tab("Camera")
        self._timings_tab = self._camera_panel.add_tab("Timings")
        self._camera_panel.dock_right()
        self._camera_panel.set_width(CAMERA_PANEL_WIDTH_PX)
        self._image: viser.GuiImageHandle | None = None
        self._timings: viser.GuiMarkdownHandle | None = None
        self._panel_images: dict[str, viser.GuiImageHandle] = {}

    # --- what the server tells this client ----------------------------------------------
    def show_error(self, headline: str, detail: str = "") -> None:
        """Replace the drive controls with a message saying what is wrong."""
        self._drop_drive()
        self._camera_panel.visible = False
        first, _, rest = detail.partition("\n")
        text = f"**{_escape_markdown(headline)}**\n\n{_escape_markdown(first)}"
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
    ) -> None:
        """Build the timeline for a drive of `frame_count` frames and render its first frame.

        notes: what the viewer should know about the recording (assumptions, what was skipped
        on reading), listed under its name.
        """
        self._drop_drive()
        gui = self.client.gui
        with self._lock:
            self.recording = name
            self._frame_count = frame_count
            self._frame_rate_hz = frame_rate_hz
            self._request = request
            self._state = replace(self._state, frame=0, playing=False)
        self._camera_panel.visible = True
        self._message.content = (
            f"**{_escape_markdown(name)}** — {frame_count} frames at {frame_rate_hz:.1f} Hz"
        ) + "".join(f"\n\n- {_escape_markdown(note)}" for note in notes)
        if frame_count == 0:
            return
        duration_s = (frame_count - 1) / frame_rate_hz if frame_rate_hz > 0 else 0.0
        with gui.add_folder("Timeline", order=2) as self._timeline:
            self._slider = gui.add_slider("frame", 0, max(frame_count - 1, 0), 1, 0)
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
        self._slider.on_update(lambda event: self.go_to(event.target.value))
        self._play.on_click(lambda _: self.set_playing(not self._state.playing))
        step_back.on_click(lambda _: self.step(-1))
        step_on.on_click(lambda _: self.step(+1))
        self._submit()

    def show_view(self, recording: str, view: FrameView) -> None:
        """Put a rendered frame and its read-out on the page together (if still wanted)."""
        if recording != self.recording or self._readout is None:
            return
        gui = self.client.gui
        with self.client.atomic():
            if self._image is None:
                with self._camera_tab:
                    self._image = gui.add_image(view.image, format="jpeg")
                with self._timings_tab:
                    self._timings = gui.add_markdown("")
            else:
                self._image.image = view.image
            for title, image in view.panels:
                if title in self._panel_images:
                    self._panel_images[title].image = image
                else:
                    with self._camera_panel.add_tab(title):
                        self._panel_images[title] = gui.add_image(image, format="jpeg")
            if self._timings is not None:
                self._timings.content = timings_markdown(view.timings)
            self._readout.content = f"`{view.readout}`"

    def show_frame_error(self, recording: str, frame: int, what: str, message: str) -> None:
        """Say in the read-out what went wrong with `frame` (the image keeps the last frame)."""
        if recording != self.recording or self._readout is None:
            return
        self._readout.content = f"**frame {frame} {what}:** {_escape_markdown(message)}"

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
        if self._slider is not None:
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
                self._stop_playing = threading.Event()
                self._player = threading.Thread(
                    target=self._play_loop,
                    args=(self._stop_playing, 1.0 / self._frame_rate_hz),
                    name=f"player-{self.client.client_id}",
                    daemon=True,
                )
                self._player.start()
            else:
                self._stop_playing.set()
        if self._play is not None:
            self._play.label = "Pause" if playing else "Play"
            self._play.icon = viser.Icon.PLAYER_PAUSE if playing else viser.Icon.PLAYER_PLAY

    def set_parameter(self, dotted: str, value: object) -> None:
        """Run the engine with one parameter changed; a value the parameters refuse is
        reported on the page and the field goes back to the value in use."""
        with self._lock:
            current = self._state.params
        try:
            params = current.with_value(dotted, value)
        except ParamsError as err:
            self.client.add_notification(
                f"{dotted}: value refused", str(err), color="red", auto_close_seconds=8.0
            )
            self._params_panel.show(current)
            return
        self._set_params(params)

    def reset_parameters(self) -> None:
        """Every parameter back to the papers' value."""
        self._set_params(Params())
        self._params_panel.show(Params())

    def close(self) -> None:
        """The client left: stop playback."""
        self._stop_playing.set()

    # --- internals ---------------------------------------------------------------------
    def _play_loop(self, stop: threading.Event, period_s: float) -> None:
        """Advance the state one frame per period (at the chosen rate) until paused or at
        the last frame."""
        while not stop.wait(period_s / self._rate_factor()):
            if self._state.frame >= self._frame_count - 1:
                self.set_playing(False)
                return
            self.step(+1)

    def _rate_factor(self) -> float:
        rate = self._rate
        return 1.0 if rate is None else float(rate.value.rstrip("x"))

    def _add_commands(self, gui: viser.GuiApi) -> None:
        """Keyboard commands (viser's command palette) and a panel that lists them."""
        keys: list[tuple[str, str, Callable[[], None]]] = [
            ("Play / pause", "space", self._toggle_playing),
            ("Step back one frame", "arrowleft", functools.partial(self.step, -1)),
            ("Step on one frame", "arrowright", functools.partial(self.step, +1)),
            ("Go to the first frame", "home", functools.partial(self.go_to, 0)),
            ("Go to the last frame", "end", self._go_to_end),
        ]
        keys += [
            (
                f"Toggle layer: {LAYER_LABELS[name]}",
                str(k),
                functools.partial(self._toggle_layer, name),
            )
            for k, name in zip("1234567890", Layers.names(), strict=False)
        ]
        lines = ["| key | does |", "| --- | --- |"]
        for label, hotkey, action in keys:
            command = gui.add_command(label, hotkey=hotkey)  # type: ignore[arg-type]
            command.on_trigger(functools.partial(_run_command, action))
            lines.append(f"| {hotkey} | {label} |")
        with gui.add_folder("Keys", order=5, expand_by_default=False):
            gui.add_markdown(
                "\n".join(lines) + "\n\nThe command palette (Ctrl+K / Cmd+K) lists them too."
            )

    def _toggle_playing(self) -> None:
        self.set_playing(not self._state.playing)

    def _go_to_end(self) -> None:
        self.go_to(self._frame_count - 1)

    def _toggle_layer(self, name: str) -> None:
        box = self._layer_boxes[name]
        box.value = not box.value  # type: ignore[misc]  # its update callback sets the layers

    def _set_params(self, params: Params) -> None:
        with self._lock:
            self._state = replace(self._state, params=params)
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

    def _drop_drive(self) -> None:
        self.set_playing(False)
        with self._lock:
            self.recording = None
            self._request = None
            self._frame_count = 0
        if self._timeline is not None:
            self._timeline.remove()
        for handle in (self._image, self._timings, *self._panel_images.values()):
            if handle is not None:
                handle.remove()
        self._panel_images = {}
        self._timeline = self._slider = self._play = self._readout = self._image = None
        self._timings = self._rate = None
