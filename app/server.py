"""The inspector's web server: one viser server, a session per client, a render worker per drive.

    serve(recordings_root, recording, host, port, presets, access=Access(new_token()))
    server = InspectorServer(root, None, "127.0.0.1", 0, presets=folder); server.start(); ...

Every request passes `app.access` first: pages of other sites, Host names that are not this
server's, and (with a token) requests without the token are refused.

Only recordings listed by `app.catalog` under the recordings root are opened. A recording
that cannot be opened is reported on the page of the client that asked for it; the server
stays up.
"""

from __future__ import annotations

import contextlib
import functools
import io
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import viser

from app.access import NO_TOKEN, Access, guarding, page_address
from app.catalog import list_recordings, resolve_recording
from app.clip_export import export_clip
from app.engines import ClientEngines
from app.metrics_panel import Evaluate
from app.page_url import read_page, show_query
from app.presenter import PresenterSession
from app.presets import PresetStore
from app.session import ClientSession
from app.state import ViewState
from app.upload_limit import DEFAULT_MAX_UPLOAD_BYTES, limit_uploads
from app.view import CanSeries, FrameSource, FrameView, can_series, render_view
from app.view_link import Clip, ViewLink, link_query, parse_link_query
from app.worker import RenderWorker
from core.annotation.store import AnnotationStore
from core.engine import FrameResult, FusionEngine
from core.evaluation.evaluate import RecordingReport, evaluate_recording
from core.io import Drive
from core.io.errors import RecordingError
from core.params import Params

log = logging.getLogger(__name__)

DriveOpener = Callable[[Path], FrameSource]
Session = ClientSession | PresenterSession
PARAMETER_SETS = ("A", "B")  # a client's engines are keyed (client id, set)
# a preview's exact replay waits this long for the values to rest: while a slider moves
# (up to 20 changes a second) every change is previewed, and no replay holds one up or
# competes with the page decoding it
EXACT_AFTER_S = 0.15


def open_drive(path: Path) -> FrameSource:
    """`core.io.Drive(path)`."""
    drive: FrameSource = Drive(path)
    return drive


@dataclass
class _OpenDrive:
    drive: FrameSource
    engines: ClientEngines
    worker: RenderWorker[int, ViewState, FrameView | Exception]
    can: CanSeries | None
    evaluate: Evaluate | None  # the whole drive scored under some parameters; None: no truth
    annotations: AnnotationStore | None  # None: the recording is not a folder of ours


class InspectorServer:
    """The inspector on `host:port` (port 0: any free port) for recordings under `recordings_root`.

    `recording` names the recording new clients see first (default: the first by name);
    `presets` is the folder parameter presets are saved in (the only place it writes);
    `access`: what a request must show (`app.access`; the default needs no token);
    `max_upload_bytes`: larger uploads are refused before they are kept (`app.upload_limit`);
    `present`: every tab shows the presenter view and cannot leave it (`fusionscope serve
    --present`). A tab opened with a view link (`app.view_link`) in its URL shows that view.
    Raises ValueError when the root is not a folder or `recording` is not under it.
    """

    def __init__(
        self,
        recordings_root: Path,
        recording: str | None = None,
        host: str = "127.0.0.1",
        port: int = 8080,
        open_drive: DriveOpener = open_drive,
        *,
        presets: Path,
        present: bool = False,
        access: Access = NO_TOKEN,
        max_upload_bytes: int = DEFAULT_MAX_UPLOAD_BYTES,
    ) -> None:
        self.recordings_root = Path(recordings_root).resolve()
        self.recordings = list_recordings(self.recordings_root)
        if recording is not None:
            resolve_recording(self.recordings_root, recording)
        self.default_recording = recording or (self.recordings[0] if self.recordings else None)
        self.host = host
        self.requested_port = port
        self._open_drive = open_drive
        self.presets = PresetStore(presets)
        self.present = present
        self.access = access
        self.max_upload_bytes = max_upload_bytes
        self._drives: dict[str, _OpenDrive] = {}
        self._sessions: dict[int, Session] = {}
        self._lock = threading.Lock()
        self._server: viser.ViserServer | None = None

    @property
    def port(self) -> int:
        """The bound port (after `start`)."""
        if self._server is None:
            raise RuntimeError("port: the server is not started")
        return self._server.get_port()

    def start(self) -> int:
        """Start serving in background threads; returns the bound port."""
        # viser's banner gives the address without the token, which is refused: `serve`
        # prints the one to open
        with guarding(self.access) as guard, contextlib.redirect_stdout(io.StringIO()):
            server = viser.ViserServer(host=self.host, port=self.requested_port, verbose=False)
        if not guard.used:
            server.stop()
            raise RuntimeError(
                f"viser {viser.__version__} did not start its web server through "
                "websockets.asyncio.server.serve: the inspector's access checks (app.access) "
                "cannot be installed, so it does not serve"
            )
        limit_uploads(server.gui, self.max_upload_bytes, self._upload_refused)
        server.gui.configure_theme(control_width="large", show_logo=False, show_share_button=False)
        server.gui.set_panel_label("fusionscope")
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        self._server = server
        threading.Thread(target=self._warm_up, name="warm-up", daemon=True).start()
        return server.get_port()

    def _upload_refused(self, client_id: int, why: str) -> None:
        client = self._server.get_clients().get(client_id) if self._server else None
        if client is not None:
            client.add_notification("Upload refused", why, color="red")

    def _warm_up(self) -> None:
        """Open the first recording and run the engine on its first frames, so the first
        client does not wait for the drive's index or the engine's compiled code (numba
        compiles on first use after an install). A failure here is left to the client who
        opens the drive to see."""
        if self.default_recording is None:
            return
        try:
            drive = self._drive(self.default_recording).drive
            FusionEngine(Params(), drive.camera).seek(drive, min(1, len(drive) - 1))
        except Exception:
            log.debug("warm-up of %s failed", self.default_recording, exc_info=True)

    def stop(self) -> None:
        """Stop playback, workers, drives and the web server."""
        with self._lock:
            sessions, self._sessions = list(self._sessions.values()), {}
            drives, self._drives = list(self._drives.values()), {}
        for session in sessions:
            session.close()
        for entry in drives:
            entry.engines.close()
            entry.worker.stop()
            entry.drive.close()
            if entry.annotations is not None:
                entry.annotations.close()
        if self._server is not None:
            self._server.stop()
            self._server = None

    # --- clients ------------------------------------------------------------------------
    def _connect(self, client: viser.ClientHandle) -> None:
        """A new tab: the view its URL carries (read from the page), else a new one."""
        limit_uploads(client.gui, self.max_upload_bytes, self._upload_refused)
        try:
            query = read_page(client, "location.search")
        except (TimeoutError, RuntimeError):
            log.warning("the URL of client %d could not be read", client.client_id)
            query = ""
        link, problems = parse_link_query(query)
        if link.recording is not None and link.recording not in self.recordings:
            problems += (f"recording: no recording {link.recording!r} here",)
            link = replace(link, recording=None)
        if self.present or link.present:
            self._open_presenter(client, link)
        else:
            self._open_inspector(client, link)
        if problems:
            client.add_notification(
                "Parts of the link were left out", "; ".join(problems), color="yellow"
            )

    def _open_inspector(self, client: viser.ClientHandle, link: ViewLink) -> None:
        """The full inspector in `client`'s tab, showing `link`."""
        recording = link.recording or self.default_recording
        session = ClientSession(
            client,
            self.recordings,
            recording,
            self._show_recording,
            self.presets,
            self._present,
            self._export,
        )
        with self._lock:
            self._sessions[client.client_id] = session
        if recording is None:
            session.show_error(
                "No recordings to show",
                f"no folder with a recording.yaml under {self.recordings_root}",
            )
        else:
            self._show_recording(session, recording, link)

    def _open_presenter(self, client: viser.ClientHandle, link: ViewLink) -> None:
        """The presenter view in `client`'s tab, showing `link`."""
        on_leave = None if self.present else self._inspect
        session = PresenterSession(client, link, on_leave)
        with self._lock:
            self._sessions[client.client_id] = session
        recording = link.recording or self.default_recording
        if recording is None:
            session.show_error("No recordings to show", f"none under {self.recordings_root}")
            return
        entry = self._open(session, recording)
        if entry is not None:
            client_id = client.client_id
            request = functools.partial(entry.worker.submit, client_id)
            session.show_drive(recording, len(entry.drive), entry.drive.frame_rate_hz, request)
        show_query(client, link_query(replace(session.link(), present=True)))

    def _export(
        self,
        recording: str,
        kind: str,
        clip: Clip,
        state: ViewState,
        progress: Callable[[int, int], None],
    ) -> tuple[str, bytes]:
        path = resolve_recording(self.recordings_root, recording)
        return export_clip(path, kind, clip, state, progress)

    def _present(self, session: ClientSession) -> None:
        """An inspector tab becomes a presenter of what it shows."""
        self._switch(session, lambda client: self._open_presenter(client, session.link()))

    def _inspect(self, session: PresenterSession) -> None:
        """A presenter tab goes back to the full inspector, on what it showed."""
        self._switch(session, lambda client: self._open_inspector(client, session.link()))

    def _switch(self, session: Session, open_view: Callable[[viser.ClientHandle], None]) -> None:
        client = session.client
        with self._lock:  # no frame reaches the old view while the page is emptied
            self._sessions.pop(client.client_id, None)
        session.close()
        client.gui.reset()
        client.scene.reset()
        open_view(client)

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            session = self._sessions.pop(client.client_id, None)
            drives = list(self._drives.values())
        if session is not None:
            session.close()
        for entry in drives:
            entry.worker.forget(client.client_id)
            for which in PARAMETER_SETS:
                entry.engines.forget((client.client_id, which))

    def _open(self, session: Session, name: str) -> _OpenDrive | None:
        """The open drive `name`; None, with the reason on the session's page, when it
        cannot be opened."""
        try:
            return self._drive(name)
        except (RecordingError, ValueError) as err:
            session.show_error(f"Cannot show this recording: {name}", str(err))
        except Exception as err:  # any reader failure must reach the page, not end the server
            log.exception("opening recording %s failed", name)
            session.show_error(
                f"Cannot show this recording: {name}", f"{type(err).__name__}: {err}"
            )
        return None

    def _show_recording(
        self, session: ClientSession, name: str, link: ViewLink | None = None
    ) -> None:
        """Recording `name` in an inspector tab, at the view `link` describes (None: from
        its first frame, with the tab's layers and parameters)."""
        entry = self._open(session, name)
        if entry is None:
            return
        client_id = session.client.client_id
        session.show_drive(
            name,
            len(entry.drive),
            entry.drive.frame_rate_hz,
            functools.partial(entry.worker.submit, client_id),
            entry.drive.notes,
            entry.can,
            entry.evaluate,
            entry.annotations,
            link,
        )

    # --- drives -------------------------------------------------------------------------
    def _drive(self, name: str) -> _OpenDrive:
        """The open drive `name` with its render worker, opened on first use."""
        with self._lock:
            if name in self._drives:
                return self._drives[name]
            drive = self._open_drive(resolve_recording(self.recordings_root, name))
            engines = ClientEngines(drive.camera)

            # per client, the last view rendered and what it was made of: a settling view
            # (`app.engines`) is rendered again until its tracks are from the start, and
            # is neither drawn nor sent again while nothing changed
            drawn: dict[int, tuple[ViewState, FrameResult, FrameResult | None, FrameView]] = {}
            sent: dict[int, tuple[object, FrameView]] = {}  # the session it was sent to

            def render(client_id: int, state: ViewState) -> FrameView | Exception:
                try:
                    index = state.frame
                    a, b = PARAMETER_SETS
                    result = engines.result((client_id, a), drive, state.params, index, True)
                    result_b = None
                    if state.params_b is not None:
                        params_b = state.params_b
                        result_b = engines.result((client_id, b), drive, params_b, index, True)
                    before = drawn.get(client_id)
                    if before is not None and before[:3] == (state, result, result_b):
                        return before[3]
                    view = render_view(drive, state, result, drive.frame(index), result_b)
                    drawn[client_id] = (state, result, result_b, view)
                    return view
                except RecordingError as err:  # a damaged frame: say so on the page
                    return err
                except Exception as err:  # the page says so; the log keeps the traceback
                    log.exception("engine on frame %d of %s failed", state.frame, name)
                    return err

            def publish(client_id: int, state: ViewState, view: FrameView | Exception) -> None:
                session = self._sessions.get(client_id)
                if session is None:
                    drawn.pop(client_id, None)
                    sent.pop(client_id, None)
                    return
                if isinstance(view, RecordingError):
                    session.show_frame_error(name, state.frame, "cannot be read", str(view))
                elif isinstance(view, Exception):
                    why = f"{type(view).__name__}: {view}"
                    session.show_frame_error(name, state.frame, "failed in the engine", why)
                else:
                    before = sent.get(client_id)
                    if before is None or before[0] is not session or before[1] is not view:
                        session.show_view(name, view)
                    sent[client_id] = (session, view)
                    return
                sent.pop(client_id, None)

            def again(view: FrameView | Exception) -> bool:
                return isinstance(view, FrameView) and (view.preview or view.settling)

            worker = RenderWorker(
                render, publish, name=f"render-{name}", again=again, again_after_s=EXACT_AFTER_S
            )
            annotations = _open_annotations(drive.path)
            evaluate = None
            editable = annotations is not None and annotations.read_only_reason is None
            if drive.has_truth or editable:

                def evaluate(
                    params: Params, progress: Callable[[int, int], None]
                ) -> RecordingReport:
                    return evaluate_recording(
                        drive.path, params, progress, timing=False, frames=drive
                    )

            entry = _OpenDrive(drive, engines, worker, can_series(drive), evaluate, annotations)
            self._drives[name] = entry
            return entry


def _open_annotations(path: Path) -> AnnotationStore | None:
    """The annotation store of the recording at `path` (read-only, with its reason, when its
    file cannot be edited); None when it cannot be opened at all."""
    try:
        return AnnotationStore.open(path)
    except (RecordingError, OSError):
        log.warning("the annotations of %s cannot be opened", path, exc_info=True)
        return None


def serve(
    recordings_root: Path,
    recording: str | None,
    host: str,
    port: int,
    presets: Path,
    present: bool = False,
    access: Access = NO_TOKEN,
    max_upload_bytes: int = DEFAULT_MAX_UPLOAD_BYTES,
) -> None:
    """Run the inspector until Ctrl-C; presets are saved in the folder `presets`; `present`:
    every tab is a presenter view; `access`: what a request must show (`app.access`);
    `max_upload_bytes`: the largest upload taken (`app.upload_limit`)."""
    inspector = InspectorServer(
        recordings_root,
        recording,
        host,
        port,
        presets=presets,
        present=present,
        access=access,
        max_upload_bytes=max_upload_bytes,
    )
    bound = inspector.start()
    address = page_address(host, bound, access)
    print(f"fusionscope inspector: {address}  (Ctrl-C to stop)", flush=True)
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        pass
    finally:
        inspector.stop()
