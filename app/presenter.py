"""The presenter view of one browser tab: a demo for people who never open a parameter panel.

The camera picture with what was found drawn on it, large on the right, under a few large
figures of the frame (`app.presenter_view.with_figures`); the bird's-eye view in the 3D
scene beside it; on the left the recording's name and a legend of the colours in plain
words. It plays a clip at the drive's real rate, over and over. The page has no parameter,
layer or annotation controls: the view comes from the link that opened it
(`app.view_link`) and only play/pause (and, when the server is not a presenter-only one,
the way back to the inspector) can be clicked. The tab's own engine runs on the server's
render worker, as an inspector tab's does.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import replace

import viser

from app.bird_eye import BirdEyeViews
from app.draw import scaled_to_width
from app.legend import legend_strip
from app.player import Player
from app.presenter_view import with_figures
from app.session import escape_markdown
from app.state import DEMO_LAYERS, Panels, ViewState
from app.view import FrameView
from app.view_link import Clip, ViewLink

PRESENTER_CAMERA_WIDTH_PX = 780  # the 3D view beside it as wide as in the inspector
PICTURE_WIDTH_PX = PRESENTER_CAMERA_WIDTH_PX - 40  # the panel's margins and scroll bar
LEGEND_WIDTH_PX = 320  # the left panel's
PRESENTER_PANELS = Panels(bird_eye=True, can=False, stage="none")


class PresenterSession:
    """The presenter view on `client`, showing what `link` says (recording, clip, frame,
    layers, parameter sets A and B). `on_leave(session)`: the viewer asked for the full
    inspector (None: no way back, a presenter-only server)."""

    def __init__(
        self,
        client: viser.ClientHandle,
        link: ViewLink,
        on_leave: Callable[[PresenterSession], None] | None,
    ) -> None:
        self.client = client
        self.recording: str | None = None
        self._lock = threading.RLock()
        self._state = ViewState(
            frame=link.frame or 0,
            layers=link.layers or DEMO_LAYERS,
            params=link.params,
            params_b=link.params_b,
            panels=PRESENTER_PANELS,
        )
        self._clip: Clip | None = link.clip  # the link's until `show_drive` knows the drive
        self._inspector_panels = link.panels  # handed back to the inspector on leaving
        self._frame_rate_hz = 0.0
        self._request: Callable[[ViewState], None] | None = None
        self._player = Player(f"presenter-{client.client_id}")

        gui = client.gui
        self._title = gui.add_markdown("", order=0)
        self._message = gui.add_markdown("", order=1)  # what went wrong with a frame
        self._play = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE, order=2)
        self._play.on_click(lambda _: self.set_playing(not self._player.playing))
        if on_leave is not None:
            back = gui.add_button("Back to the inspector", icon=viser.Icon.ADJUSTMENTS, order=3)
            back.on_click(lambda _: on_leave(self))
        gui.add_markdown("**What the colours mean**", order=4)
        gui.add_image(legend_strip(self._state.layers, LEGEND_WIDTH_PX), format="png", order=5)
        gui.main_panel.dock_left()
        self._camera_panel = gui.add_panel()
        self._camera_tab = self._camera_panel.add_tab("Camera")
        self._camera_panel.dock_right()
        self._camera_panel.set_width(PRESENTER_CAMERA_WIDTH_PX)
        self._image: viser.GuiImageHandle | None = None
        self._bird_eyes = BirdEyeViews(client)

    def show_drive(
        self,
        name: str,
        frame_count: int,
        frame_rate_hz: float,
        request: Callable[[ViewState], None],
    ) -> None:
        """Play the clip of the link (the whole drive when it named none or one past the
        drive's end) of drive `name`, from the link's frame."""
        last = frame_count - 1
        clip = self._clip or (0, last)
        if clip[1] > last:
            clip = (0, last)
        with self._lock:
            self.recording = name
            self._frame_rate_hz = frame_rate_hz
            self._clip = clip
            self._request = request
            frame = min(max(self._state.frame, clip[0]), clip[1])
            self._state = replace(self._state, frame=frame)
        self._title.content = (
            f"# {escape_markdown(name)}\n\nframes {clip[0]}–{clip[1]} of {frame_count}, "
            "playing at the drive's real rate, over and over"
        )
        self._submit()
        if frame_count > 1 and frame_rate_hz > 0:
            self.set_playing(True)

    def show_view(self, recording: str, view: FrameView) -> None:
        """Put a rendered frame on the page (if still wanted)."""
        if recording != self.recording:
            return
        picture = scaled_to_width(view.image, PICTURE_WIDTH_PX)  # to fill its panel
        if view.figures is not None:  # in the picture: shown with it, never before it
            picture = with_figures(picture, view.figures)
        with self.client.atomic():
            if self._image is None:
                with self._camera_tab:
                    self._image = self.client.gui.add_image(picture, format="jpeg")
            else:
                self._image.image = picture
            self._message.content = ""
            self._bird_eyes.show(view.bird_eyes, self._state.params)
        self.client.flush()  # out at once, as the inspector's (app.session)

    def show_frame_error(self, recording: str, frame: int, what: str, message: str) -> None:
        if recording == self.recording:
            self._message.content = f"**frame {frame} {what}:** {escape_markdown(message)}"

    def show_error(self, headline: str, detail: str = "") -> None:
        self.set_playing(False)
        self._title.content = f"**{escape_markdown(headline)}**\n\n{escape_markdown(detail)}"

    def link(self) -> ViewLink:
        """What this tab shows, as a link (the inspector it goes back to opens it)."""
        s = self._state
        panels = self._inspector_panels
        return ViewLink(self.recording, s.frame, s.layers, panels, s.params, s.params_b, self._clip)

    def set_playing(self, playing: bool) -> None:
        if playing:
            self._player.start(lambda: 1.0 / self._frame_rate_hz, self._next_frame)
        else:
            self._player.stop()
        self._play.label = "Pause" if playing else "Play"
        self._play.icon = viser.Icon.PLAYER_PAUSE if playing else viser.Icon.PLAYER_PLAY

    def close(self) -> None:
        self._player.stop()

    def _next_frame(self) -> bool:
        """One frame on; after the clip's last, its first."""
        with self._lock:
            first, last = self._clip or (0, 0)  # set by show_drive, which starts the player
            frame = self._state.frame + 1
            self._state = replace(self._state, frame=first if frame > last else frame)
        self._submit()
        return True

    def _submit(self) -> None:
        with self._lock:
            request, state = self._request, self._state
        if request is not None:
            request(state)
