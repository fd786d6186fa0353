"""One CAN frame as the decoders see it, whichever file it came from (a log or a bag)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class CanFrame:
    """A data frame: time stamp (ns on the source's own clock), id, payload, bus channel.

    channel: the logger's channel name ("can0", "1", ...), None when the source has none.
    """

    t_ns: int
    arbitration_id: int
    is_extended: bool
    data: bytes
    channel: str | None = None
