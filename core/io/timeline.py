"""Time stamps as recorded: the main body of a stream, and what falls outside it.

A stream's stamps can hold outliers: a logger that lost its clock writes 1970, a bad GPS fix
writes next year. Taken at face value one such stamp stretches a 60 s drive's timeline to 56
years. `main_block` keeps the largest run of stamps without a gap longer than `max_gap_ns`
(in time order) and marks the rest as outliers, to be skipped and reported.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

NS_PER_S = 1_000_000_000
# A stream silent for longer than this is not one drive any more.
DEFAULT_MAX_GAP_NS = 120 * NS_PER_S


def main_block(
    t_ns: npt.NDArray[np.int64], max_gap_ns: int = DEFAULT_MAX_GAP_NS
) -> npt.NDArray[np.bool_]:
    """(N,) bool: True for stamps in the largest gap-free run of the sorted stamps.

    Ties between runs of equal size go to the earliest. Empty input gives an empty mask.
    """
    t = np.asarray(t_ns, dtype=np.int64)
    keep = np.zeros(len(t), dtype=bool)
    if len(t) == 0:
        return keep
    order = np.argsort(t, kind="stable")
    sorted_t = t[order]
    breaks = np.flatnonzero(np.diff(sorted_t) > max_gap_ns) + 1
    starts = np.concatenate(([0], breaks))
    ends = np.concatenate((breaks, [len(t)]))
    k = int(np.argmax(ends - starts))
    keep[order[starts[k] : ends[k]]] = True
    return keep
