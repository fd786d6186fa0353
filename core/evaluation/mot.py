"""CLEAR-MOT (Bernardin and Stiefelhagen 2008) and IDF1 (Ristani et al. 2016) of tracked
boxes against truth tracks, with image boxes and IoU as the distance.

Per frame, a truth object and a track *match* when their boxes overlap by at least
IOU_MATCH of their union. CLEAR-MOT's correspondences: the pairs matched on the previous
frame are kept while they still match, the rest are assigned optimally (largest total
IoU). An id switch is a truth object matched to another track than the last one it was
matched to. MOTA = 1 - (misses + false positives + id switches) / truth objects; MOTP =
mean IoU of the matched pairs. IDF1 assigns truth ids to track ids once for the whole
sequence, maximising the frames each pair matches (IDTP); IDF1 = 2 IDTP / (truth objects +
track boxes).

Objects that are there but not to be tracked (vehicles the radar never saw, for a
radar-guided tracker) are "ignored" boxes, as MOT16's distractors: a track left unmatched
after the assignment that overlaps one by IOU_MATCH is left out of the figures, neither a
false positive nor a track box.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from core.tracking import solve_assignment

from .objects import Box, iou

IOU_MATCH = 0.5


@dataclass(frozen=True)
class MotScore:
    truth: int
    hypotheses: int
    matches: int
    misses: int
    false_positives: int
    id_switches: int
    iou_sum: float
    idtp: int
    switches_at: tuple[tuple[int, int], ...]  # (frame index, truth id)

    @property
    def mota(self) -> float:
        if not self.truth:
            return 0.0
        return 1.0 - (self.misses + self.false_positives + self.id_switches) / self.truth

    @property
    def motp(self) -> float:
        return self.iou_sum / self.matches if self.matches else 0.0

    @property
    def idf1(self) -> float:
        total = self.truth + self.hypotheses
        return 2 * self.idtp / total if total else 0.0


class MotAccumulator:
    """Feed it one frame at a time with `update`; `score()` gives the figures so far."""

    def __init__(self) -> None:
        self._last_match: dict[int, int] = {}  # truth id -> track id it was last matched to
        self._previous: dict[int, int] = {}  # pairs matched on the previous frame
        self._pair_frames: dict[tuple[int, int], int] = defaultdict(int)
        self._truth = self._hyp = self._matches = self._fp = self._misses = 0
        self._iou_sum = 0.0
        self._switches: list[tuple[int, int]] = []

    def update(
        self,
        index: int,
        truth: Sequence[tuple[int, Box]],
        tracks: Sequence[tuple[int, Box]],
        ignored: Sequence[Box] = (),
    ) -> None:
        """One frame: (truth id, box) of the objects to track, (track id, box) reported, and
        the boxes of objects neither to track nor to count as false (module docstring)."""
        overlap = np.array([[iou(t, h) for _, h in tracks] for _, t in truth]).reshape(
            len(truth), len(tracks)
        )
        for a, (tid, _) in enumerate(truth):
            for b, (hid, _) in enumerate(tracks):
                if overlap[a, b] >= IOU_MATCH:
                    self._pair_frames[(tid, hid)] += 1
        pairs: dict[int, int] = {}
        t_index = {tid: a for a, (tid, _) in enumerate(truth)}
        h_index = {hid: b for b, (hid, _) in enumerate(tracks)}
        for tid, hid in self._previous.items():
            if (
                tid in t_index
                and hid in h_index
                and overlap[t_index[tid], h_index[hid]] >= IOU_MATCH
            ):
                pairs[t_index[tid]] = h_index[hid]
        free_t = [a for a in range(len(truth)) if a not in pairs]
        free_h = [b for b in range(len(tracks)) if b not in pairs.values()]
        if free_t and free_h:
            sub = overlap[np.ix_(free_t, free_h)]
            cost = np.where(sub >= IOU_MATCH, 1.0 - sub, np.inf)
            for r, c in solve_assignment(cost):
                pairs[free_t[r]] = free_h[c]
        self._previous = {}
        for a, b in pairs.items():
            tid, hid = truth[a][0], tracks[b][0]
            if tid in self._last_match and self._last_match[tid] != hid:
                self._switches.append((index, tid))
            self._last_match[tid] = hid
            self._previous[tid] = hid
            self._iou_sum += float(overlap[a, b])
        matched = set(pairs.values())
        left_out = sum(
            1
            for b, (_, box) in enumerate(tracks)
            if b not in matched and any(iou(box, g) >= IOU_MATCH for g in ignored)
        )
        self._truth += len(truth)
        self._hyp += len(tracks) - left_out
        self._matches += len(pairs)
        self._misses += len(truth) - len(pairs)
        self._fp += len(tracks) - len(pairs) - left_out

    def score(self) -> MotScore:
        truth_ids = sorted({t for t, _ in self._pair_frames})
        hyp_ids = sorted({h for _, h in self._pair_frames})
        idtp = 0
        if truth_ids and hyp_ids:
            gain = np.zeros((len(truth_ids), len(hyp_ids)))
            for (t, h), n in self._pair_frames.items():
                gain[truth_ids.index(t), hyp_ids.index(h)] = n
            # every pair allowed: the assignment then maximises the matched frames alone
            idtp = int(sum(gain[r, c] for r, c in solve_assignment(-gain)))
        return MotScore(
            truth=self._truth,
            hypotheses=self._hyp,
            matches=self._matches,
            misses=self._misses,
            false_positives=self._fp,
            id_switches=len(self._switches),
            iou_sum=self._iou_sum,
            idtp=idtp,
            switches_at=tuple(self._switches),
        )
