"""Radar tracks sent over CAN (one DBC message per track slot), decoded into RadarScans.

A car's own forward radar (the Toyota RAV4's, opendbc `toyota_adas_radar.dbc`) reports its
tracks as a family of messages, TRACK_A_0..TRACK_A_15, one track each, all slots every cycle
(20 Hz). `RadarCanDecoder` collects them in one pass over the log (see
`core.io.canlog.decode_frames`) and groups them back into scans.
"""

from __future__ import annotations

import difflib
import math
import re
from fnmatch import fnmatchcase

import numpy as np
import numpy.typing as npt
from cantools.database.can import Database, Message

from core.io.canlog import (
    NS_PER_S,
    FrameDecoder,
    FrameLog,
    Warn,
    check_signals,
    id_text,
    missing_frames_warning,
)
from core.io.errors import RecordingError
from core.io.manifest import RadarCanSource, RadarField
from core.io.radarscans import MAX_ABS_RANGE_RATE_MPS, MAX_RANGE_M, RadarScans, plausible

FloatArray = npt.NDArray[np.float64]


def natural_key(name: str) -> tuple[str | int, ...]:
    """Sort key putting TRACK_A_2 before TRACK_A_10: digit runs compare as numbers."""
    return tuple(int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name))


def radar_messages(db: Database, pattern: str, where: str) -> list[Message]:
    """The DBC messages whose names match the shell pattern, sorted naturally.

    RecordingError listing close names when none matches.
    """
    family = [m for m in db.messages if fnmatchcase(m.name, pattern)]
    if not family:
        names = [m.name for m in db.messages]
        stem = re.sub(r"[*?\[\]]", "", pattern)
        close = difflib.get_close_matches(stem, names, n=5, cutoff=0.4)
        raise RecordingError(
            f"{where}: no DBC message matches {pattern!r} (radar track messages, a shell "
            f"pattern); close names: {', '.join(close) or 'none'}"
        )
    return sorted(family, key=lambda m: natural_key(m.name))


class RadarCanDecoder(FrameDecoder):
    """Radar tracks of a `RadarCanSource` from the frames of one pass, as RadarScans.

    where: names the source in messages; offset_ns: added to every stamp (the recording's
    radar time offset).

    Scans: the family's messages, in time order, are cut into scans where a message arrives
    whose slot (the message: TRACK_A_3) has already appeared in the current scan; a scan's
    stamp is that of its first message (the radar sends a cycle's messages within ~8 ms,
    after its measurement). Every family message counts as its slot's appearance, also an
    invalid one. Track id: the `track_id` signal when mapped, else the slot's place in the
    family (natural order).

    Each kept target is turned into the radar's polar frame, so RadarScans has one format for
    scans and tracks: range = hypot(distance, lateral), azimuth = atan2(lateral, distance)
    (positive left, after the mapping's sign); range_rate: the mapped signal, NaN when not
    mapped; amplitude NaN (tracks carry none).

    Notes:
        A radar's longitudinal relative speed (the RAV4's REL_SPEED) is taken as the range
        rate: the two differ by the cosine of the azimuth, under 1.5 % within 10 degrees of
        the axis, more for near targets off to the side. The RAV4's REL_SPEED is already
        positive receding (sign +1): on the real log it matches the change of LONG_DIST
        between scans (slope 1.01), so a car being approached has a negative range rate.
        The scan rule assumes the radar sends every slot every cycle (the RAV4 does); a
        radar that skips slots gets cycles merged until a slot comes again.
        Targets whose mapped `valid` signal is zero are dropped without a word (the radar
        says they are not there); targets with a non-finite value are dropped and reported
        with `warn`, as are frames the DBC cannot decode and stamps outside the log's main
        block (`timeline.main_block`).
    """

    def __init__(
        self, db: Database, source: RadarCanSource, where: str, offset_ns: int = 0
    ) -> None:
        self.source = source
        self.where = where
        self.offset_ns = offset_ns
        self._family = radar_messages(db, source.messages, where)
        fields = [source.distance, source.lateral, source.range_rate, source.valid]
        self._fields: list[RadarField | None] = [*fields, source.track_id]
        signals = [f.signal for f in self._fields if f is not None]
        for message in self._family:
            check_signals(message, signals, where)
        super().__init__(
            source.bus, FrameLog(self._family, [f.signal if f else "" for f in self._fields])
        )

    @property
    def messages(self) -> tuple[Message, ...]:
        """The family, in slot order."""
        return self._log.messages

    def result(self, warn: Warn) -> RadarScans:
        """All scans of the log, ascending in time (stamps plus offset_ns)."""
        src = self.source
        if not any(self._log.received):
            first, last = self._family[0], self._family[-1]
            what = f"{src.messages} ({len(self._family)} messages)"
            span = id_text(first.frame_id, first.is_extended_frame)
            if len(self._family) > 1:
                span += " to " + id_text(last.frame_id, last.is_extended_frame)
            warn(missing_frames_warning(self.where, what, span, src.bus.channel, self._traffic))
        t, slot, values = self._log.table(warn, self.where, "radar track")

        # 1. Scans: a new one wherever a slot comes again.
        scan_of = np.empty(len(t), dtype=np.int64)
        scan_t: list[int] = []
        seen: set[int] = set()
        for i, s in enumerate(slot.tolist()):
            if not scan_t or s in seen:
                scan_t.append(int(t[i]))
                seen = set()
            seen.add(s)
            scan_of[i] = len(scan_t) - 1

        # 2. Targets: valid and finite, in SI units and the engine's signs.
        distance, lateral, range_rate, valid, track_id = values.T  # as self._fields
        keep: npt.NDArray[np.bool_] = np.ones(len(t), dtype=bool)
        if src.valid is not None:
            keep = valid != 0
        used = [k for k, f in enumerate(self._fields) if f is not None]
        finite = np.all(np.isfinite(values[:, used]), axis=1)
        if not finite[keep].all():
            bad = keep & ~finite
            first_bad = self._family[int(slot[bad][0])].name
            warn(
                f"{self.where}: dropped {np.count_nonzero(bad)} radar targets with non-finite "
                f"values (first: {first_bad} at t={t[bad][0] / NS_PER_S:.6f} s)"
            )
        keep &= finite
        d = _si(distance[keep], src.distance)
        y = _si(lateral[keep], src.lateral)
        rr = _si(range_rate[keep], src.range_rate) if src.range_rate else np.full(len(d), np.nan)
        ids = track_id[keep].astype(np.int64) if src.track_id else slot[keep].astype(np.int64)
        sane = plausible(np.hypot(d, y), np.arctan2(y, d), rr)
        if not sane.all():
            warn(
                f"{self.where}: dropped {np.count_nonzero(~sane)} radar targets no radar "
                f"reports (range over {MAX_RANGE_M:g} m or range rate over "
                f"{MAX_ABS_RANGE_RATE_MPS:g} m/s; first at "
                f"t={t[keep][~sane][0] / NS_PER_S:.6f} s)"
            )
            kept_rows = np.flatnonzero(keep)
            keep[kept_rows[~sane]] = False
            d, y, rr, ids = d[sane], y[sane], rr[sane], ids[sane]
        scans = np.arange(len(scan_t) + 1)
        return RadarScans(
            t_ns=np.asarray(scan_t, dtype=np.int64) + self.offset_ns,
            start=np.searchsorted(scan_of[keep], scans, side="left").astype(np.int64),
            range_m=np.hypot(d, y),
            azimuth_rad=np.arctan2(y, d),
            range_rate_mps=rr,
            amplitude=np.full(len(d), math.nan),
            track_id=ids,
        )


def _si(raw: FloatArray, field: RadarField) -> FloatArray:
    return raw * (field.to_si * field.sign)
