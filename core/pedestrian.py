"""Pedestrian detection by vertical symmetry and its fusion filters (paper 000, II-D).

Paper 000 gives the method in words and refers to Bertozzi et al. 2000 ([3]) for it: scan
the image for vertical symmetry of edges and grey levels and for edge density, keep
symmetric areas with a human aspect ratio, use the pitch and the road plane to extend the
box down to the road when the legs break the symmetry, prune by size and perspective, then
keep only candidates motion stereo also marks as obstacle and drop those inside detected
vehicles. The steps here:

1. Strip and bands. Distance hypotheses d_k = min_distance_m * distance_step_ratio^k up to
   max_distance_m. Band k stands a scan_height_m person on the road at d_k: its foot row
   v_k (where the road at d_k projects, with this frame's pitch) and its box height h_k
   (pixels). Bands whose foot row falls outside the camera's row window are left out. The
   strip (the paper's grey strip) covers every band from its tallest person's head
   (max_height_m) down to its foot row.
2. Scan. Vertical edges |Sobel_x| > edge_threshold of the strip. For each band, the column
   profiles of its box (rows v_k - h_k .. v_k): edge pixels and grey sum per column, summed
   in bins of s_k = max(1, round(h_k / scan_bins)) columns, so every band is scanned at
   about the same resolution in bins. For each axis (a bin's centre):
   - the half-width w is the outermost pair of border columns mirrored about the axis
     (both with edges on more than border_column_fraction of the box height); it must be a
     human one, aspect_min .. aspect_max times h_k / 2, or the axis scores 0;
   - edge symmetry S_e = 2 sum_x min(e(j - x), e(j + x)) / sum_x (e(j - x) + e(j + x));
   - grey symmetry S_g = (sum Even^2 - sum Odd^2) / (sum Even^2 + sum Odd^2) of the mean
     grey profile less its mean over the window (0 on a flat window);
   - edge density rho: edge pixels / box pixels in the window, at least min_edge_density;
   - score = (S_e + max(S_g, 0)) / 2. The symmetry map holds it per band and column.
3. Candidates: local maxima of the score along a band (within their half-width) that reach
   symmetry_threshold, strongest first; of band boxes overlapping by more than
   SAME_PERSON_IOU of their union (one person seen by neighbouring bands) the strongest.
4. Refinement with the road plane, on the strip's signed edges within the half-width of
   the axis, from the band's hip row (START_FRACTION h_k above v_k). A row is symmetric
   when at least two edges lie in it and row_symmetry_fraction of them are mirrored about
   the axis by an edge of opposite sign (within MIRROR_TOLERANCE_PX, or half the band's bin
   where wider: the axis is a bin's centre); a run of rows ends at gap_fraction h_k rows
   that break it.
   - downwards, symmetric rows continue the symmetric area, rows holding any edge the legs
     (down to FEET_BELOW_FRACTION h_k under v_k), which end at FEET_GAP_FRACTION of the
     gap. When the legs go on below the symmetric area, they broke its symmetry and the
     box is extended down to the feet (`extended`); the road plane then judges where
     those feet stand. (Extending to the band's road row instead, when the legs show no
     edges, let anything symmetric above the road pass as a person of that band: a tree
     trunk 30 m away framed by a 10 m band.)
   - upwards, symmetric rows continue the body: the last is the top. A body still going on
     at the head row of the tallest person standing where the box's base is (max_height_m
     there; `head_row_at_base`, beyond the paper: where the band's person would stand) has
     no top (a pole, a tree trunk, the edge of something behind): verdict "no_top";
   - constraints, where the box's base meets the road: it stands within PERSPECTIVE_BANDS
     band steps of the band's distance ("perspective": the scan framed part of someone
     nearer or farther), a person's height ("size"), a human width / height ("aspect").
     Beyond the paper (`keep_off_band_boxes`), a box off its band's distance that passes
     the others is kept: the refinement found its head and feet wherever the scan seeded
     it, and its height and width are checked where it stands. When one box per person is
     chosen it ranks after the boxes at their band's distance.
5. Fusion, in the paper's order: a box with less than min_obstacle_fraction of its pixels
   in motion stereo's reprojected obstacle mask is "motion_stereo"; of the rest, one lying
   more than vehicle_overlap_fraction inside a detected vehicle's box is "vehicle". Then,
   beyond the paper, one whose base stands by a radar target moving over ground faster than
   radar_min_speed_mps (within radar_gate_lateral_m sideways and radar_gate_distance_fraction
   of the box's distance along x) is "radar"; and, given the previous frame, one whose pixels
   match the previous frame where they were in the image better, by more than
   image_motion_margin of NCC, than where a still object would have been under the car's
   motion (`core.image_motion`: a part of a vehicle keeping pace with the car) is
   "image_motion". With the verification of step 6 on, a box
   motion stereo did not mark is not dropped yet: it goes through the other filters (one
   they reject is "motion_stereo", the filter that rejected it first) and on to step 6.
6. Verification, beyond the paper (`verify_with_hog`): a box that passed every filter is
   "hog" when OpenCV's HOG people SVM scores its window below `hog_min_score`
   (`core.hog.people_scores`); a box motion stereo did not mark needs
   `hog_without_motion_min_score` and is "motion_stereo" below it. The others are
   "pedestrian". Beyond that (`hog_person_at_base`), a box below its floor whose top lies
   SHORT_FRACTION or more below the head of a `scan_height_m` person standing on its base
   is scored again as that person (its top at their head, at least PERSON_ASPECT of their
   height wide about the axis) and, reaching the floor, takes that box and is
   "pedestrian". A person's box that ends rejected, at step 5 or here, gives way to the
   first of up to `hog_alternatives` other boxes that passed step 4 and framed the same
   person (those the one-box-per-person choice of step 4 left out, in its order) that
   passes steps 5-6; none passing, the chosen box stays with its verdict.

Notes:
    - Symmetry is measured on the column profiles of a band's box (per-column sums of edge
      pixels and grey levels), not row by row over the box as in [3]: a band costs
      O(columns x width) instead of O(columns x width x height), which is what brings the
      scan of all bands to about a millisecond. The vertical structure comes back in step
      4, which looks at each row of the candidate.
    - The human width is read from the border columns (step 2) instead of keeping the
      window width of highest symmetry: on a plain background symmetry stays as high for
      every window wider than the person, so its maximum does not fix a width.
    - Bands scan a person of scan_height_m; shorter or taller people are found in the band
      whose box best matches and get their real height from step 4. With no edges on the
      legs the image cannot tell a near person from a taller, farther one: the band decides.
    - Steps 3-4 go beyond the paper's words (which give no rule for duplicates, the top,
      or the feet); their constants are named in this module and measured on the bundled
      drives (tests/core/test_bundled_pipeline.py reports recall and precision). The
      mirror tolerance of half a bin and the legs' shorter gap (FEET_GAP_FRACTION) were
      measured on stop_and_go / exurban drives of new seeds (1818-2525, 1313-1717 + 2727,
      2929): final recall 0.51 / 0.47 / 0.53 -> 0.51 / 0.49 / 0.55 and 0.21 / 0.20 / 0.21
      -> 0.22 / 0.23 / 0.22, precision 0.97-1.00 as before, highway and the real drives
      unchanged.
    - Step 4, boxes off their band's distance (`keep_off_band_boxes`, beyond the paper):
      a person 3-10 m away was often seeded by a farther band, whose box frames the torso;
      the refinement then found the head and the feet, and the perspective constraint
      rejected the right box. Kept when its size fits and ranked after the boxes at their
      band's distance, final recall on stop_and_go / exurban, seeds 1818-2525: 0.51 / 0.22
      -> 0.53 / 0.24; seeds 1313-1717, 2727 and 2929: 0.50 / 0.23 -> 0.54 / 0.25;
      precision 0.97-0.99 as before; false boxes per frame on highway 0.014 -> 0.014 and
      0.016 -> 0.017; the real drives unchanged.
    - Step 4's head row where the box stands, and step 6's alternatives (both beyond the
      paper): a person 8 m away was seeded by the 6.6 m band, whose box framed the shirt
      and legs down to the zebra stripes (HOG -3.2), and by the 11.7 m band, whose
      refinement found head and feet (IoU 0.85 with the truth, HOG 0.8). The second box
      ran past the 11.7 m band's head row and was "no_top"; it now meets the head row of
      8 m. Passed, it still ranked after the first (at its band's distance) and lost the
      one-box-per-person choice; ranking by score or preferring boxes not extended lost
      0.04-0.05 of the recall on stop_and_go, so the choice stays and the SVM decides only
      when the chosen box fails. On drives of new seeds (20 s each), final recall /
      precision, before -> after, seeds 1818-2121 (tuning): stop_and_go 0.545 / 0.996 ->
      0.600 / 0.991, exurban 0.225 / 0.986 -> 0.281 / 0.984; seeds 4242 + 4343
      (checking): stop_and_go 0.608 / 0.995 -> 0.679 / 0.994, exurban 0.233 / 0.977 ->
      0.294 / 0.982; false boxes per frame on highway 0.002 -> 0.007 and 0.005 -> 0.005;
      nuScenes the same; aiMotive 0 -> 1 false box in 50 frames (a fence post 59 m away,
      a 17 px box); seeds 6161 + 6262 (checked afterwards): stop_and_go 0.608 / 0.995 ->
      0.684 / 0.991, exurban 0.176 / 0.982 -> 0.225 / 0.986, highway 0 -> 0.003. The
      head row alone gave 0.005-0.017 of that, 2 alternatives 0.045-0.065 on stop_and_go,
      5 a little more on exurban. HOG windows per frame on the
      bundled drives 1.5 / 2.7 / 3.6 -> 1.9 / 5.0 / 5.9 (0.15 ms each).
      The stage tables count the boxes the candidates end with, so the "symmetry alone"
      figures count a passing alternative instead of the box it replaced.
    - Candidates are not tracked over frames here; `core.tracking` does (beyond the paper).
    - The radar filter of step 5 is not in the paper, which keeps radar out of pedestrian
      detection because people reflect little. Its vehicle filter removes boxes only on the
      vehicles vision confirmed; the symmetric parts of the others (a truck's twin wheels,
      the side of a car too wide for its search area) passed as people. A target moving
      faster than a jog is such a vehicle. On the bundled drives the filter removed 17-33 % of
      the false boxes that passed both of the paper's filters, and no true one
      (`tests/core/test_bundled_pipeline.py`); radar_gate_lateral_m 0 switches it off.
    - The image-motion filter of step 5 is not in the paper either. On highway drives of
      new seeds 36 of 39 false boxes after the HOG verification were the wheels of trucks
      1-12 m ahead in the next lane, beside the radar's field of view: no target for the
      radar filter, most (30) with no track near them for the tracker's speed gate. A
      truck beside the car keeps its pace, so its wheel stays where it was in the image,
      while anything standing on the road moves and grows by tens of pixels a frame at
      highway speed (`core.image_motion`). A box that matches the previous frame where it
      was better, by more than `image_motion_margin` (0.2) of NCC, than where a still
      object would have been is removed; a person walks at 1-2 m/s and follows the still
      place. Measured on drives of new seeds (20 s each), false boxes per frame on highway
      and recall / precision on exurban and stop_and_go, off -> on: seeds 1818-2525 0.024
      -> 0.003, 0.235 / 0.990 -> 0.234 / 0.994, 0.554 / 0.998 -> 0.553 / 0.998; seeds 4242
      + 4343 0.018 -> 0.005, the others the same; seeds 5151 + 5252 0.028 -> 0.005, the
      others the same; false pedestrian tracks on highway 0.011 / 0.005 / 0.010 -> 0.003 /
      0.005 / 0.000 per frame; nuScenes and aiMotive the same. The true people's NCC with
      the still place beat the other by 0.28 (median; 95 % by more than 0.03, none by less
      than -0.16), the false boxes' lost by 0.12 (median). Margins 0.05 and 0.1 removed a
      few true people on exurban for the same false boxes. The filter costs two 16 x 32
      resamplings per box that reaches it (1-3 a frame) and keeping each frame at a
      quarter of its resolution; the papers' preset switches it off (2).
    - Step 6 is not in the paper. After both of its filters and the radar one, the boxes
      kept on drives of new seeds (20 s each) were still mostly false: precision 0.10-0.19
      on exurban, 0.41-0.52 on stop_and_go, 1.2-1.7 false boxes per frame on highway (a
      drive without people: guard-rail posts, truck wheels, vehicle sides, shadows) and on
      nuScenes (poles, bushes). The symmetry detector finds where a person could be; the
      SVM of Dalal and Triggs, trained on real people, tells a person from a post by the
      shape of its gradients. On seeds 101 and 202 the SVM scored the false boxes -3.8
      (median; 1-6 % above -1) and the true ones on stop_and_go 2.5 (88-90 % above -1);
      exurban's true people, far and small, score lower (median -0.6). `hog_min_score`
      -1 kept boxes a little below the SVM's own threshold (0), trading a few far people
      for most false boxes. Each verified box costs one 64x128 HOG descriptor (about
      0.15 ms).
    - Steps 5-6, motion stereo as evidence rather than a gate (beyond the paper): of the
      people the symmetry found, motion stereo's filter dropped most on drives of new seeds
      (exurban recall 0.40-0.46 -> 0.11-0.16, stop_and_go 0.58-0.71 -> 0.45-0.51): a
      standing person marks few of motion stereo's 0.1 m cells, and far ones fewer (the
      dropped true boxes had 0.01-0.09 of their pixels marked, against 0.1 needed). The
      SVM tells them from posts without it: a box motion stereo did not mark is kept when
      the SVM scores it at least 0.5, one it marked at least 0.3 (`hog_min_score`, was -1,
      which let 0.1-0.28 false boxes per frame through on highway drives). Seeds 101 and
      202 (tuning) and 404, 505 and 707 (checking), final recall / precision, before -> after:
      exurban 0.03-0.10 / 0.67-0.84 -> 0.17-0.22 / 0.97-1.00, stop_and_go 0.36-0.45 /
      0.99-1.00 -> 0.48-0.59 / 0.99-1.00; false boxes per frame on highway 0.07-0.28 ->
      0.01-0.03; nuScenes 0.07 -> 0.03 (and one true box); aiMotive 0 both. Without
      motion stereo at all (one threshold of 0 for every box) nuScenes had 0.1-0.2 false
      boxes per frame on poles and bushes. The boxes motion stereo did not mark raise the
      SVM's windows from 1.0-1.7 to 2.4-3.5 per frame on the synthetic drives (nuScenes
      1.7 -> 5.1, aiMotive 0.2 -> 6.6).
    - Step 6, a person standing on the box's base (`hog_person_at_base`, beyond the paper):
      the SVM scored the truth boxes of exurban's people (drives of seeds 1818-2121, 10-40
      m away) at least 0.3 on 63-89 % of them, yet most were missed: the symmetric area of
      a grey shirt on a grey background ends at the hips, and the box of the legs alone
      scores low. Scored again as a 1.7 m person on the same base (one window, only for a
      box at least a fifth shorter), on drives of new seeds (20 s each), final recall /
      precision, off -> on: exurban, seeds 1818-2121 0.281 / 0.984 -> 0.314 / 0.986,
      4242-5252 0.285 / 0.971 -> 0.306 / 0.973, 6161 + 6262 0.225 / 0.986 -> 0.235 /
      0.987, 8181 + 8282 0.233 / 0.973 -> 0.276 / 0.977; stop_and_go 0.600 / 0.991 -> 0.637
      / 0.988, 0.626 / 0.995 -> 0.697 / 0.992, 0.684 / 0.991 -> 0.705 / 0.991, 0.674 /
      1.000 -> 0.726 / 0.996; false boxes per frame on highway the same on every set.
      Tracked recall rose with it (exurban +0.017 to +0.100, stop_and_go +0.003 to +0.065);
      pedestrian MOTA exurban +0.006 to +0.057, stop_and_go +0.013 / +0.033 / -0.005 /
      -0.016. nuScenes 1 -> 2 of its 10 people found, precision 0.50 -> 0.67; aiMotive one
      false box more in 50 frames (a reflector post 32 m away). The box's width of the legs
      alone (0.82 of the truth's, median) gave IoU 0.69 with the truth (median); at least
      PERSON_ASPECT of the height wide, 0.80. The SVM's windows per frame on the bundled
      drives 4.3 -> 5.9 (8.1 when every box below its floor was scored again).
    - Step 3, `symmetry_threshold` 0.4 (the papers' preset: 0.6): with step 6 deciding, the
      scan's threshold only says which areas reach the SVM. Of exurban's visible people
      without a candidate (seeds 1818, 4242, 5151), 30 of 86 had no peak near their axis, the
      best band scoring 0.4-0.59 there (a grey shirt on a grey background, the guard rail's
      posts beside the legs). Final recall / precision on drives of new seeds (20 s each),
      0.6 -> 0.4, seeds 1818-2121 / 4242-5252 / 6161 + 6262 / 8181 + 8282: exurban 0.314 /
      0.306 / 0.235 / 0.276 -> 0.352 / 0.330 / 0.277 / 0.306, precision 0.966-0.989;
      stop_and_go 0.637 / 0.697 / 0.705 / 0.726 -> 0.661 / 0.721 / 0.725 / 0.752, precision
      0.986-0.996; false boxes per frame on highway 0.007 / 0.006 / 0.003 / 0.018 -> 0.008 /
      0.007 / 0.003 / 0.018. Tracked recall rose on those sets (exurban +0.002 to +0.045,
      stop_and_go +0.015 to +0.033), pedestrian MOTA too (exurban +0.009 to +0.043,
      stop_and_go +0.002 to +0.041). nuScenes 2 -> 3 of its 10 people found, precision 0.67
      -> 0.75, the same false boxes; aiMotive the same. Checked afterwards on seeds 9393 +
      9494, not used before: exurban 0.287 -> 0.294, stop_and_go 0.664 -> 0.681, precision
      0.978 and 0.998 -> 0.994, highway 0.010 false boxes per frame both; tracked recall
      exurban 0.283 -> 0.280 (precision 0.909 -> 0.889), stop_and_go 0.758 -> 0.779,
      pedestrian MOTA +0.004 and +0.010: the gain holds there, smaller on exurban. 0.5 gained
      about a third of that, 0.35 a little more than 0.4 for more windows; `max_candidates`
      40 changed nothing. Cost: the SVM's windows per frame on the bundled drives 3.0 / 6.5
      / 8.2 -> 5.0 / 10.4 / 14.3 (highway / exurban / stop_and_go), the whole frame about +6
      % on highway and +9 % on stop_and_go (paired runs, 2026-12-03), the compiled
      descriptor (`core.hog`) already counted: it takes back part of that.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import cv2
import numba
import numpy as np
import numpy.typing as npt

from core import hog, image_motion, symmetry
from core.camera import CameraModel
from core.checks import require_2d_array
from core.ego import EgoMotion
from core.io.frame import RadarTarget, real_speed_mps
from core.params import PedestrianParams
from core.search_area import intersection_area, rect_area

Box = tuple[float, float, float, float]
F32Array = npt.NDArray[np.float32]
FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
U8Array = npt.NDArray[np.uint8]

Verdict = Literal[
    "pedestrian",
    "no_top",
    "perspective",
    "size",
    "aspect",
    "motion_stereo",
    "vehicle",
    "radar",
    "image_motion",
    "hog",
]
CONSTRAINT_VERDICTS: tuple[Verdict, ...] = ("no_top", "perspective", "size", "aspect")
# the candidates that passed those constraints and reached the fusion filters (fig. 6-7)
FUSION_VERDICTS: tuple[Verdict, ...] = (
    "pedestrian",
    "motion_stereo",
    "vehicle",
    "radar",
    "image_motion",
    "hog",
)

# Step 4 starts at the hip of a scan_height_m person, which is still the chest of a child
# of min_height_m (hips lie at about 0.5 of a person's height, shoulders at 0.8).
START_FRACTION = 0.45
# A row's mirrored partner may sit this many pixels off, or half the band's bin where that
# is more: the axis is a bin's centre, up to half a bin off the body's. (With 1 px at every
# band, near people, whose bands' bins are 5-8 px, lost the rows of their chest and head:
# on stop_and_go drives of new seeds, the box of a person 3-10 m away from the band of
# their distance ended a third of their height below the head, median.)
MIRROR_TOLERANCE_PX = 1
# Rows without edges that end the legs: this share of the gap that ends a run (at the whole
# gap, the legs ran on into the shadow and road markings a few rows below the feet, and a
# person on a zebra crossing was extended into its stripes).
FEET_GAP_FRACTION = 0.5
# Feet are looked for down to this share of the band's box height below its road row: the
# strongest band for a person is often a farther one, whose box frames the symmetric torso.
FEET_BELOW_FRACTION = 0.5
# Step 3: band boxes overlapping by more than this share of their union frame one person
# (0.5 also merged the band of the right size into a stronger one framing a torso: 11 of 65
# pedestrians fewer found on the bundled stop_and_go drive).
SAME_PERSON_IOU = 0.7
# A box's base may stand this many band steps off its band's distance (step 4).
PERSPECTIVE_BANDS = 3.0
# Step 6: a person box of a given height is at least this share of it wide (the synthetic
# people's boxes: 0.28 / 0.35 / 0.41 at the 10th / 50th / 90th percentile; standing
# pedestrians in real data are about 0.41), where the symmetric area held only the legs.
PERSON_ASPECT = 0.35
# Step 6 scores a box again only when its top lies at least this share of that person's
# height below their head (a box nearly as tall would give the SVM the same window).
SHORT_FRACTION = 0.2

_jit = numba.njit(cache=True, nogil=True)


@dataclass(frozen=True)
class Bands:
    """The distance hypotheses of one frame (step 1), each an array (B,).

    distance_m: d_k; foot_row_px: v_k, the full-image row where the road at d_k is (a
    box's exclusive bottom); height_px: h_k, a scan_height_m person there; px_per_m: image
    pixels per metre at d_k; bin_px: s_k, columns per bin.
    """

    distance_m: FloatArray
    foot_row_px: IntArray
    height_px: IntArray
    px_per_m: FloatArray
    bin_px: IntArray

    def __len__(self) -> int:
        return len(self.distance_m)


@dataclass(frozen=True)
class PedestrianCandidate:
    """One symmetric area and what became of it.

    band: its distance hypothesis; axis_px: the symmetry axis column (full image, pixel
    centres at whole numbers); half_width_px: the border pair's distance from the axis;
    score, edge_symmetry, grey_symmetry, edge_density: step 2 at that axis; box_px: (u0, v0,
    u1, v1) the symmetric area, top to where its symmetry ends; extended_box_px: the box
    down to the feet (= box_px when not extended; step 6 may raise its top to a person's
    standing on its base, and height_m is then scan_height_m); extended: the legs broke the
    symmetry and go on below it; distance_m, lateral_m: where the extended box's base meets
    the road (vehicle frame); height_m, width_m: its world size there (NaN with no top);
    obstacle_fraction: share of the extended box marked by motion stereo (NaN when a
    constraint rejected it first); verdict: see `Verdict`; hog_score: the HOG people SVM's
    score of its window (step 6; NaN when not verified).
    """

    band: int
    axis_px: float
    half_width_px: float
    score: float
    edge_symmetry: float
    grey_symmetry: float
    edge_density: float
    box_px: Box
    extended_box_px: Box
    extended: bool
    distance_m: float
    lateral_m: float
    height_m: float
    width_m: float
    obstacle_fraction: float
    verdict: Verdict
    hog_score: float = math.nan


@dataclass(frozen=True, eq=False)
class PedestrianResult:
    """One frame of pedestrian detection with its intermediates.

    strip_rows_px: (first, stop) full-image rows of the search strip; bands: the distance
    hypotheses; symmetry: (B, W) float32 score of step 2 per band and column (0 where no
    human-wide symmetric area is centred); half_width_px: (B, W) float32 the border pair's
    half-width at each axis (0 without one); candidates: every candidate of step 3 with its
    verdict, strongest first.
    """

    strip_rows_px: tuple[int, int]
    bands: Bands
    symmetry: F32Array
    half_width_px: F32Array
    candidates: tuple[PedestrianCandidate, ...]

    def with_verdict(self, *verdicts: Verdict) -> tuple[PedestrianCandidate, ...]:
        return tuple(c for c in self.candidates if c.verdict in verdicts)

    @property
    def kept(self) -> tuple[PedestrianCandidate, ...]:
        return self.with_verdict("pedestrian")

    @property
    def rejected_by_motion_stereo(self) -> tuple[PedestrianCandidate, ...]:
        return self.with_verdict("motion_stereo")

    @property
    def rejected_by_vehicle(self) -> tuple[PedestrianCandidate, ...]:
        return self.with_verdict("vehicle")

    @property
    def pruned(self) -> tuple[PedestrianCandidate, ...]:
        """Candidates the size and perspective constraints removed (step 4)."""
        return self.with_verdict(*CONSTRAINT_VERDICTS)


# --- step 1: strip and bands ----------------------------------------------------------------


def bands_for(camera: CameraModel, params: PedestrianParams) -> Bands:
    """Step 1: the distance bands whose foot row lies inside the camera's row window."""
    count = math.floor(
        math.log(params.max_distance_m / params.min_distance_m)
        / math.log(params.distance_step_ratio)
    )
    d = np.asarray(
        params.min_distance_m * params.distance_step_ratio ** np.arange(count + 1), np.float64
    )
    n = len(d)
    points = np.zeros((2 * n, 3))
    points[:n, 0] = points[n:, 0] = d
    points[n:, 2] = 1.0  # a metre above the road
    pixels, in_front = camera.project(points)
    feet, heads = pixels[:n], pixels[n:]
    ok_feet, ok_heads = in_front[:n], in_front[n:]
    px_per_m = feet[:, 1] - heads[:, 1]
    first, stop = camera.row_window_px
    with np.errstate(invalid="ignore"):
        foot = np.round(feet[:, 1])
        keep = ok_feet & ok_heads & (px_per_m > 0) & (foot > first) & (foot <= stop)
    height = np.maximum(np.round(params.scan_height_m * px_per_m[keep]), 1).astype(np.int64)
    return Bands(
        distance_m=d[keep],
        foot_row_px=foot[keep].astype(np.int64),
        height_px=height,
        px_per_m=px_per_m[keep],
        bin_px=np.maximum(np.round(height / params.scan_bins), 1).astype(np.int64),
    )


def _px_per_m(bands: Bands, row_px: IntArray) -> FloatArray:
    """Pixels per metre of height of something standing on the road at full-image rows
    `row_px`: on a flat road they grow linearly with the row's distance below the horizon,
    so the bands' figures are fitted by a line (one band: its own figure)."""
    if len(bands) == 1:
        return np.full(len(row_px), bands.px_per_m[0])
    # the least-squares line, in closed form (np.polyfit's SVD cost 0.2 ms a frame)
    mean_row, mean_px = bands.foot_row_px.mean(), bands.px_per_m.mean()
    centred = bands.foot_row_px - mean_row
    slope = np.dot(centred, bands.px_per_m - mean_px) / np.dot(centred, centred)
    return np.maximum(slope * (row_px - mean_row) + mean_px, 0.0)


def _strip_rows(camera: CameraModel, bands: Bands, params: PedestrianParams) -> tuple[int, int]:
    first, stop = camera.row_window_px
    if len(bands) == 0:
        return first, first
    tallest = np.ceil(params.max_height_m * bands.px_per_m * (1 + params.gap_fraction))
    top = int(np.min(bands.foot_row_px - tallest))
    bottom = int(np.max(bands.foot_row_px + np.ceil(params.gap_fraction * bands.height_px)))
    return max(first, top), min(stop, bottom)


# --- step 2: the scan -----------------------------------------------------------------------


@_jit
def _prefix_rows(
    edges: npt.NDArray[np.int8], grey: U8Array, at: IntArray
) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.int32]]:
    """Per column, the edge pixels and the grey sum of the strip's rows above each row of
    `at` (K,) ascending in 0 .. R: (K, W) int32 each. Only the band boxes' first and last
    rows are kept, not a (R + 1, W) table: less memory to fill and to read back."""
    rows, width = edges.shape
    out_e = np.empty((len(at), width), dtype=np.int32)
    out_g = np.empty((len(at), width), dtype=np.int32)
    run_e = np.zeros(width, dtype=np.int32)
    run_g = np.zeros(width, dtype=np.int32)
    k = 0
    for r in range(rows + 1):
        while k < len(at) and at[k] == r:
            out_e[k] = run_e
            out_g[k] = run_g
            k += 1
        if r == rows or k == len(at):
            break
        for c in range(width):
            run_e[c] += edges[r, c] != 0
            run_g[c] += grey[r, c]
    return out_e, out_g


@_jit
def _column_sums(
    prefix: npt.NDArray[np.int32], k0: int, k1: int, bin_px: int, offset: int, bins: int
) -> FloatArray:
    """Sum between prefix rows k0 and k1 per bin of bin_px columns from column `offset`."""
    out = np.zeros(bins)
    for j in range(bins):
        c0 = offset + j * bin_px
        s = 0
        for c in range(c0, c0 + bin_px):
            s += prefix[k1, c] - prefix[k0, c]
        out[j] = s
    return out


@_jit
def _scan(
    edges: npt.NDArray[np.int8],
    grey: U8Array,
    row0: IntArray,
    row1: IntArray,
    bin_px: IntArray,
    min_half: IntArray,
    max_half: IntArray,
    border_fraction: float,
    min_density: float,
) -> tuple[F32Array, F32Array, F32Array, F32Array, F32Array]:
    """Step 2 on the strip's signed edges (R, W) and grey (R, W): per band b the box rows
    row0[b] .. row1[b] (strip rows), bins of bin_px[b] columns, human half-widths
    min_half[b] .. max_half[b] (bins). Returns (B, W) score, half-width (px), S_e, S_g, rho,
    each bin's values written to all of its columns."""
    width = edges.shape[1]
    n_bands = len(row0)
    at = np.unique(np.concatenate((row0, row1)))
    cum_e, cum_g = _prefix_rows(edges, grey, at)
    k0 = np.searchsorted(at, row0)
    k1 = np.searchsorted(at, row1)
    score = np.zeros((n_bands, width), dtype=np.float32)
    half_px = np.zeros((n_bands, width), dtype=np.float32)
    s_edge = np.zeros((n_bands, width), dtype=np.float32)
    s_grey = np.zeros((n_bands, width), dtype=np.float32)
    density = np.zeros((n_bands, width), dtype=np.float32)
    for b in range(n_bands):
        s = bin_px[b]
        bins = width // s
        offset = (width - bins * s) // 2
        h = row1[b] - row0[b]
        e = _column_sums(cum_e, k0[b], k1[b], s, offset, bins)
        g = _column_sums(cum_g, k0[b], k1[b], s, offset, bins) / (h * s)
        border = border_fraction * h * s
        for j in range(bins):
            reach = min(max_half[b], j, bins - 1 - j)
            w = reach  # the outermost pair of edge-rich columns, 0 without one
            while w > 0 and not (e[j - w] > border and e[j + w] > border):
                w -= 1
            if w == 0 or w < min_half[b]:
                continue
            pairs = 0.0
            total = e[j]
            even = 0.0
            even2 = 0.0
            odd2 = 0.0
            for x in range(1, w + 1):
                pairs += min(e[j - x], e[j + x])
                total += e[j - x] + e[j + x]
                a = (g[j - x] + g[j + x]) / 2
                even += a
                even2 += a * a
                odd2 += (g[j + x] - g[j - x]) ** 2 / 4
            rho = total / (h * s * (2 * w + 1))
            if rho < min_density:
                continue
            mean = (g[j] + 2 * even) / (2 * w + 1)
            # sum over x of (a_x - mean)^2, the even part of the mean-removed profile
            even2 = even2 - 2 * mean * even + w * mean * mean
            se = 2 * pairs / (total - e[j]) if total > e[j] else 0.0
            energy = even2 + odd2
            sg = (even2 - odd2) / energy if energy > 1e-9 else 0.0
            c0 = offset + j * s
            for c in range(c0, c0 + s):
                score[b, c] = (se + max(sg, 0.0)) / 2
                half_px[b, c] = w * s
                s_edge[b, c] = se
                s_grey[b, c] = sg
                density[b, c] = rho
    return score, half_px, s_edge, s_grey, density


@_jit
def _peaks(score: F32Array, half_px: F32Array, bin_px: IntArray, threshold: float) -> IntArray:
    """Step 3's local maxima: (P, 2) (band, bin's first column) of bins whose score reaches
    `threshold` and is the largest within half their half-width (the first of equals)."""
    n_bands, width = score.shape
    found = []
    for b in range(n_bands):
        s = bin_px[b]
        bins = width // s
        offset = (width - bins * s) // 2
        for j in range(bins):
            c = offset + j * s
            v = score[b, c]
            if v < threshold:
                continue
            reach = max(1, int(half_px[b, c] / s))
            best = True
            for k in range(max(0, j - reach), min(bins, j + reach + 1)):
                other = score[b, offset + k * s]
                if other > v or (other == v and k < j):
                    best = False
                    break
            if best:
                found.append((b, c))
    out = np.empty((len(found), 2), dtype=np.int64)
    for i in range(len(found)):
        out[i, 0] = found[i][0]
        out[i, 1] = found[i][1]
    return out


@_jit
def _groups(boxes: FloatArray, fraction: float, max_keep: int, of_union: bool) -> IntArray:
    """Non-maximum suppression of `boxes` (P, 4) (u0, v0, u1, v1), strongest first: the first
    `max_keep` that do not overlap an earlier kept one by more than `fraction` of the smaller
    of the two (of their union when `of_union`) are kept. Per box, the index of the kept box
    it is one with (its own when kept; the first kept one it overlaps so), -1 for one left
    out by `max_keep`."""
    group = np.full(len(boxes), -1, dtype=np.int64)
    kept = np.empty(min(len(boxes), max_keep), dtype=np.int64)
    n = 0
    for i in range(len(boxes)):
        u0, v0, u1, v1 = boxes[i]
        area = (u1 - u0) * (v1 - v0)
        for k in kept[:n]:
            a0, b0, a1, b1 = boxes[k]
            shared = max(0.0, min(u1, a1) - max(u0, a0)) * max(0.0, min(v1, b1) - max(v0, b0))
            other = (a1 - a0) * (b1 - b0)
            base = area + other - shared if of_union else min(area, other)
            if shared > fraction * max(base, 1.0):
                group[i] = k
                break
        if group[i] < 0 and n < max_keep:
            group[i] = kept[n] = i
            n += 1
    return group


def _nms(boxes: FloatArray, fraction: float, max_keep: int, of_union: bool) -> IntArray:
    """Indices of the boxes `_groups` keeps, strongest first."""
    group = _groups(boxes, fraction, max_keep, of_union)
    return np.flatnonzero(group == np.arange(len(boxes)))


# --- step 4: refinement ---------------------------------------------------------------------


@_jit
def _row_edges(
    edges: npt.NDArray[np.int8], r: int, c0: int, c1: int, a2: int, tolerance: int
) -> tuple[int, int]:
    """(edges, edges mirrored about column a2 / 2 by one of opposite sign within
    `tolerance` px) on row r of `edges` between columns c0 and c1 (exclusive)."""
    count = mirrored = 0
    for c in range(c0, c1):
        e = edges[r, c]
        if e == 0:
            continue
        count += 1
        for shift in range(-tolerance, tolerance + 1):
            m = a2 - c + shift
            if c0 <= m < c1 and m != c and edges[r, m] == -e:
                mirrored += 1
                break
    return count, mirrored


@_jit
def _feet(
    edges: npt.NDArray[np.int8],
    start: IntArray,
    down_stop: IntArray,
    col0: IntArray,
    col1: IntArray,
    axis2: IntArray,
    gap: IntArray,
    feet_gap: IntArray,
    fraction: float,
    tolerance: IntArray,
) -> IntArray:
    """Step 4's downward row scans for each candidate i on the strip's signed edges (strip
    rows). A row is symmetric when, between columns col0[i] and col1[i] (exclusive), it
    holds at least two edges and `fraction` of them are mirrored about column axis2[i] / 2
    by an edge of opposite sign within tolerance[i] px. From start[i] down to down_stop[i]
    (exclusive), symmetric rows give the bottom of the symmetric area (until gap[i] rows
    are not), and rows holding any edge the feet (until feet_gap[i] rows hold none).
    Returns (N, 2): the feet's and the symmetric area's last rows (start[i] - 1 when
    none)."""
    out = np.empty((len(start), 2), dtype=np.int64)
    for i in range(len(start)):
        c0, c1, a2 = col0[i], col1[i], axis2[i]
        feet = sym = start[i] - 1
        feet_misses = sym_misses = 0
        feet_on = sym_on = True
        for r in range(start[i], down_stop[i]):
            count, mirrored = _row_edges(edges, r, c0, c1, a2, tolerance[i])
            if feet_on:
                if count > 0:
                    feet, feet_misses = r, 0
                else:
                    feet_misses += 1
                    feet_on = feet_misses < feet_gap[i]
            if sym_on:
                if count >= 2 and mirrored >= fraction * count:
                    sym, sym_misses = r, 0
                else:
                    sym_misses += 1
                    sym_on = sym_misses < gap[i]
            if not (feet_on or sym_on):
                break
        out[i, 0], out[i, 1] = feet, sym
    return out


@_jit
def _top(
    edges: npt.NDArray[np.int8],
    start: IntArray,
    up_stop: IntArray,
    col0: IntArray,
    col1: IntArray,
    axis2: IntArray,
    gap: IntArray,
    fraction: float,
    tolerance: IntArray,
) -> IntArray:
    """Step 4's upward row scans (rows symmetric as in `_feet`): from start[i] up to
    up_stop[i], symmetric rows continue the body until gap[i] rows are not. Returns (N, 2):
    the top row, and 1 when the body still went on at up_stop."""
    out = np.empty((len(start), 2), dtype=np.int64)
    for i in range(len(start)):
        c0, c1, a2 = col0[i], col1[i], axis2[i]
        top, misses, going = start[i] + 1, 0, 1
        for r in range(start[i], up_stop[i] - 1, -1):
            count, mirrored = _row_edges(edges, r, c0, c1, a2, tolerance[i])
            if count >= 2 and mirrored >= fraction * count:
                top, misses = r, 0
            else:
                misses += 1
                if misses >= gap[i]:
                    going = 0
                    break
        out[i, 0], out[i, 1] = top, going
    return out


def _world(camera: CameraModel, boxes: FloatArray, axis_px: FloatArray) -> FloatArray:
    """(N, 4) distance_m, lateral_m, width_m, height_m of boxes (N, 4) standing on the road:
    where the base under the axis meets it, the base corners' lateral positions and the top's
    height on the vertical plane there (NaN when the base is at or above the horizon)."""
    n = len(boxes)
    pts = np.concatenate(
        [
            np.column_stack([axis_px, boxes[:, 3]]),
            boxes[:, [0, 3]],
            boxes[:, [2, 3]],
            np.column_stack([axis_px, boxes[:, 1]]),
        ]
    )
    rays = camera.rays_vehicle(pts)
    o = camera.position_vehicle_m
    base, left, right, top = rays[:n], rays[n : 2 * n], rays[2 * n : 3 * n], rays[3 * n :]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(base[:, 2] < 0, o[0] - o[2] / base[:, 2] * base[:, 0], np.nan)
        y_left = o[1] + left[:, 1] * (x - o[0]) / left[:, 0]
        y_right = o[1] + right[:, 1] * (x - o[0]) / right[:, 0]
        height = o[2] + top[:, 2] * (x - o[0]) / top[:, 0]
    return np.column_stack([x, (y_left + y_right) / 2, y_left - y_right, height])


def _constraints(
    no_top: npt.NDArray[np.bool_],
    band_distance_m: FloatArray,
    world: FloatArray,
    params: PedestrianParams,
) -> tuple[list[Verdict | None], npt.NDArray[np.bool_]]:
    """Step 4's size and perspective constraints on boxes whose bases meet the road at
    world[:, 0] (NaN, a base at or above the horizon, fails them): the first that fails
    per box, None when a box passes, and whether each box stands off its band's distance
    (with `keep_off_band_boxes`, that alone fails none)."""
    distance_m, _, width_m, height_m = world.T
    with np.errstate(divide="ignore", invalid="ignore"):
        # the box was scanned as a person at band_distance_m: its base must stand within
        # PERSPECTIVE_BANDS band steps of there, or the scan framed the wrong part of someone
        steps = np.abs(np.log(distance_m / band_distance_m)) / math.log(params.distance_step_ratio)
        aspect = width_m / height_m
        off_band = ~(steps <= PERSPECTIVE_BANDS)
        failed = [
            no_top,
            np.zeros_like(off_band) if params.keep_off_band_boxes else off_band,
            ~((params.min_height_m <= height_m) & (height_m <= params.max_height_m)),
            ~((params.aspect_min <= aspect) & (aspect <= params.aspect_max)),
        ]
    stacked = np.array(failed)  # (4, N): each constraint's failures, in the order above
    first = np.where(stacked.any(axis=0), stacked.argmax(axis=0) + 1, 0).tolist()
    names: tuple[Verdict | None, ...] = (None, *CONSTRAINT_VERDICTS)
    return [names[k] for k in first], off_band


# --- step 5: fusion -------------------------------------------------------------------------


def _obstacle_fraction(box: Box, mask: U8Array, mask_first_row: int) -> float:
    """Share of the box's pixels (full image) that the reprojected mask marks; rows outside
    the mask count as unmarked."""
    u0, v0, u1, v1 = (round(x) for x in box)
    area = max(0, u1 - u0) * max(0, v1 - v0)
    if area == 0:
        return 0.0
    r0, r1 = max(v0 - mask_first_row, 0), min(v1 - mask_first_row, mask.shape[0])
    c0, c1 = max(u0, 0), min(u1, mask.shape[1])
    if r1 <= r0 or c1 <= c0:
        return 0.0
    return float(np.count_nonzero(mask[r0:r1, c0:c1])) / area


def _inside_vehicle(box: Box, vehicle_boxes_px: Sequence[Box], fraction: float) -> bool:
    area = max(rect_area(box), 1.0)
    return any(intersection_area(box, v) / area > fraction for v in vehicle_boxes_px)


def _moving_targets_m(
    targets: Sequence[RadarTarget], ego_speed_mps: float, params: PedestrianParams
) -> FloatArray:
    """(N, 2) float64 (x_m, y_m) in the vehicle frame of the radar targets moving over ground
    faster than radar_min_speed_mps (`core.guardrail.real_speed_mps`; none when the ego speed
    is NaN, unknown)."""
    moving = [
        (t.x_m, t.y_m)
        for t in targets
        if abs(real_speed_mps(t, ego_speed_mps)) > params.radar_min_speed_mps
    ]
    return np.array(moving, dtype=np.float64).reshape(-1, 2)


def _on_moving_target(
    distance_m: float, lateral_m: float, moving_m: FloatArray, params: PedestrianParams
) -> bool:
    """Whether a box whose base stands at (distance_m, lateral_m) has a moving target within
    the radar gates."""
    near = (np.abs(moving_m[:, 1] - lateral_m) < params.radar_gate_lateral_m) & (
        np.abs(moving_m[:, 0] - distance_m) < params.radar_gate_distance_fraction * distance_m
    )
    return bool(near.any())


def _moves_with_car(
    image: U8Array,
    previous: U8Array | None,
    camera: CameraModel,
    box: Box,
    distance_m: float,
    lateral_m: float,
    ego: EgoMotion | None,
    params: PedestrianParams,
) -> bool:
    """Step 5's image-motion filter (`core.image_motion`); False when it cannot tell."""
    if previous is None or ego is None or not params.image_motion_filter:
        return False
    motion = image_motion.box_motion(image, previous, camera, box, distance_m, lateral_m, ego)
    return motion is not None and motion.with_car(params.image_motion_margin)


# --- the stage ------------------------------------------------------------------------------


def _verified(
    image: U8Array,
    camera: CameraModel,
    candidates: list[PedestrianCandidate],
    params: PedestrianParams,
) -> list[PedestrianCandidate]:
    """Step 6: the candidates that passed steps 4-5 with the SVM's score of their window, kept
    when it reaches the floor for how motion stereo marked them ("hog" or "motion_stereo"
    below it). With `hog_person_at_base`, a box below its floor is scored again as a person
    of `scan_height_m` standing on its base, and takes that box when it reaches the floor."""
    kept = [i for i, c in enumerate(candidates) if c.verdict == "pedestrian"]
    scores = hog.people_scores(image, [candidates[i].extended_box_px for i in kept])
    out = list(candidates)
    low: list[int] = []
    for i, hog_score in zip(kept, scores, strict=True):
        verdict: Verdict = "pedestrian"
        if hog_score < _hog_floor(candidates[i], params):
            verdict = "hog" if _marked(candidates[i], params) else "motion_stereo"
            low.append(i)
        out[i] = dataclasses.replace(candidates[i], verdict=verdict, hog_score=hog_score)
    if params.hog_person_at_base and low:
        tall = _people_at_base([candidates[i] for i in low], camera, params.scan_height_m)
        standing = [(i, box) for i, box in zip(low, tall, strict=True) if box is not None]
        scores = hog.people_scores(image, [box for _, box in standing]) if standing else ()
        for (i, box), hog_score in zip(standing, scores, strict=True):
            if hog_score >= _hog_floor(candidates[i], params):
                out[i] = dataclasses.replace(
                    candidates[i],
                    extended_box_px=box,
                    height_m=params.scan_height_m,
                    verdict="pedestrian",
                    hog_score=hog_score,
                )
    return out


def _marked(candidate: PedestrianCandidate, params: PedestrianParams) -> bool:
    """Step 5: motion stereo marked the candidate's box as obstacle."""
    return candidate.obstacle_fraction >= params.min_obstacle_fraction


def _hog_floor(candidate: PedestrianCandidate, params: PedestrianParams) -> float:
    """Step 6: the SVM score a box needs, by how motion stereo marked it."""
    if _marked(candidate, params):
        return params.hog_min_score
    return params.hog_without_motion_min_score


def _people_at_base(
    candidates: Sequence[PedestrianCandidate], camera: CameraModel, height_m: float
) -> list[Box | None]:
    """Step 6: each candidate's box with its top where a person `height_m` tall standing on
    its base (at distance_m, lateral_m) has the head; None when that is no box."""
    heads = [[c.distance_m, c.lateral_m, height_m] for c in candidates]
    head_px, ok = camera.project(heads)
    out: list[Box | None] = []
    for c, top_px, seen in zip(candidates, head_px[:, 1].tolist(), ok.tolist(), strict=True):
        u0, v0, u1, v1 = c.extended_box_px
        if not (seen and math.isfinite(top_px) and top_px < v1 - 1):
            out.append(None)
        elif v0 - top_px < SHORT_FRACTION * (v1 - top_px):
            out.append(None)  # as tall as that person already
        else:
            half_px = max(u1 - u0, PERSON_ASPECT * (v1 - top_px)) / 2
            out.append((c.axis_px - half_px, top_px, c.axis_px + half_px, v1))
    return out


def detect_pedestrians(
    image: U8Array,
    camera: CameraModel,
    obstacle_mask: U8Array,
    mask_first_row_px: int,
    vehicle_boxes_px: Sequence[Box],
    radar_targets: Sequence[RadarTarget],
    ego_speed_mps: float,
    params: PedestrianParams,
    previous: U8Array | None = None,
    ego: EgoMotion | None = None,
) -> PedestrianResult:
    """Pedestrians in one frame (paper 000, II-D), steps 1-6 of the module docstring.

    image: (H, W) uint8 grey full frame as `camera.intrinsics` says; camera: this frame's
    camera, pitch included; obstacle_mask: (n, W) uint8, motion stereo's reprojected
    obstacle mask (nonzero: obstacle), its row 0 being full-image row mask_first_row_px
    (`MotionStereoResult.image_mask`); vehicle_boxes_px: (u0, v0, u1, v1) boxes of this
    frame's detected vehicles; radar_targets: this frame's radar targets; ego_speed_mps:
    the car's speed (NaN: unknown, and the radar filter removes nothing); previous: the
    previous frame as `core.image_motion.keep` kept it, and ego: the car's motion since
    (either None: no image-motion filter).
    """
    camera.check_image(image)
    require_2d_array("obstacle_mask", obstacle_mask, np.uint8, "uint8 mask")
    if previous is not None and previous.shape != image_motion.kept_shape(*image.shape):
        raise ValueError(
            "previous: expected the frame before as core.image_motion.keep gives it, shape "
            f"{image_motion.kept_shape(*image.shape)}, got {previous.shape}"
        )
    width = camera.intrinsics.width_px
    if obstacle_mask.shape[1] != width:
        raise ValueError(
            f"obstacle_mask: expected {width} columns (the image's), got {obstacle_mask.shape[1]}"
        )
    bands = bands_for(camera, params)
    first, stop = _strip_rows(camera, bands, params)
    n = len(bands)
    if n == 0 or stop <= first:
        empty = np.zeros((n, width), dtype=np.float32)
        return PedestrianResult((first, first), bands, empty, empty.copy(), ())

    # 2. the scan
    strip = np.ascontiguousarray(image[first:stop])
    # OpenCV's Sobel: symmetry.sobel's numbers in half its time on a strip this wide
    derivative = np.asarray(cv2.Sobel(strip, cv2.CV_16S, 1, 0, ksize=3), np.int16)
    edges = symmetry.signed_edges(derivative, float(params.edge_threshold))
    row1 = bands.foot_row_px - first
    row0 = np.maximum(row1 - bands.height_px, 0)
    half = bands.height_px / 2 / bands.bin_px
    score, half_px, s_edge, s_grey, density = _scan(
        edges,
        strip,
        row0,
        np.minimum(row1, stop - first),
        bands.bin_px,
        np.maximum(np.ceil(params.aspect_min * half), 1).astype(np.int64),
        np.floor(params.aspect_max * half).astype(np.int64),
        params.border_column_fraction,
        params.min_edge_density,
    )

    # 3. candidates: peaks, strongest first
    peaks = _peaks(score, half_px, bands.bin_px, params.symmetry_threshold)
    band, col = peaks[:, 0], peaks[:, 1]
    order = np.argsort(-score[band, col], kind="stable")
    band, col = band[order], col[order]
    axis = col + (bands.bin_px[band] - 1) / 2
    hw = half_px[band, col].astype(np.float64)
    foot = bands.foot_row_px[band]
    # the same person in neighbouring bands: boxes of about one size on one place
    box = np.column_stack([axis - hw, foot - bands.height_px[band], axis + hw + 1, foot])
    alike = _nms(box.astype(np.float64), SAME_PERSON_IOU, len(box), True)
    band, col, axis, hw, foot = band[alike], col[alike], axis[alike], hw[alike], foot[alike]

    # 4. refinement with the road plane, then the constraints
    h = bands.height_px[band]
    gap = np.maximum(np.round(params.gap_fraction * h), 2).astype(np.int64)
    rows = stop - first
    start = np.clip(foot - np.round(START_FRACTION * h).astype(np.int64) - first, 0, rows - 1)
    col0 = np.maximum(np.floor(axis - hw), 0).astype(np.int64)
    col1 = np.minimum(np.ceil(axis + hw) + 1, width).astype(np.int64)
    axis2 = np.round(2 * axis).astype(np.int64)
    tolerance = np.maximum(bands.bin_px[band] // 2, MIRROR_TOLERANCE_PX).astype(np.int64)
    found = _feet(
        edges,
        start,
        np.minimum(foot + np.round(FEET_BELOW_FRACTION * h).astype(np.int64) - first, rows),
        col0,
        col1,
        axis2,
        gap,
        np.maximum(np.round(FEET_GAP_FRACTION * gap), 2).astype(np.int64),
        params.row_symmetry_fraction,
        tolerance,
    )
    feet_bottom = found[:, 0] + first + 1
    sym_bottom = found[:, 1] + first + 1
    extended = feet_bottom > sym_bottom + gap
    bottom = np.where(extended, feet_bottom, sym_bottom)
    # the tallest person's head where the box stands (or where its band's person would)
    base, px_per_m = foot, bands.px_per_m[band]
    if params.head_row_at_base:
        base, px_per_m = bottom, _px_per_m(bands, bottom)
    head = base - np.ceil(params.max_height_m * px_per_m).astype(np.int64)
    topped = _top(
        edges,
        start,
        np.clip(head - gap - first, 0, rows - 1),
        col0,
        col1,
        axis2,
        gap,
        params.row_symmetry_fraction,
        tolerance,
    )
    top = topped[:, 0] + first
    no_top = (topped[:, 1] == 1) | (top < head)
    u0, u1 = axis - hw, axis + hw + 1
    boxes = np.column_stack([u0, top, u1, sym_bottom]).astype(np.float64)
    extended_boxes = np.column_stack([u0, top, u1, bottom]).astype(np.float64)
    world = _world(camera, extended_boxes, axis) if len(axis) else np.zeros((0, 4))
    verdicts, off_band = _constraints(no_top, bands.distance_m[band], world, params)
    # one candidate per person: those that passed first (those at their band's distance
    # before the others), each strongest first; the others framing the same person, passed,
    # are its alternatives in step 6
    passed = np.array([v is None for v in verdicts], dtype=bool)
    order = np.argsort(np.where(passed, off_band.astype(np.int64), 2), kind="stable")
    group = _groups(
        extended_boxes[order], params.nms_overlap_fraction, params.max_candidates, False
    )
    leaders = np.flatnonzero(group == np.arange(len(order)))
    chosen = order[leaders]
    alternatives = [
        [int(order[j]) for j in np.flatnonzero(group == g) if j != g and passed[order[j]]]
        if params.verify_with_hog and params.hog_alternatives
        else []
        for g in leaders.tolist()
    ]

    # 5. fusion, in the paper's order, then radar (beyond the paper); a box motion stereo
    # did not mark goes on to step 6 when there is one, as the SVM may keep it (beyond)
    moving_m = _moving_targets_m(radar_targets, ego_speed_mps, params)

    def fused(i: int) -> PedestrianCandidate:
        ext_box = tuple(extended_boxes[i].tolist())
        d, y, width_m, height_m = world[i].tolist()
        fraction = math.nan
        verdict = verdicts[i]
        if verdict is None:
            fraction = _obstacle_fraction(ext_box, obstacle_mask, mask_first_row_px)
            marked = fraction >= params.min_obstacle_fraction
            if not (marked or params.verify_with_hog):
                verdict = "motion_stereo"
            elif _inside_vehicle(ext_box, vehicle_boxes_px, params.vehicle_overlap_fraction):
                verdict = "vehicle" if marked else "motion_stereo"
            elif _on_moving_target(d, y, moving_m, params):
                verdict = "radar" if marked else "motion_stereo"
            elif _moves_with_car(image, previous, camera, ext_box, d, y, ego, params):
                verdict = "image_motion" if marked else "motion_stereo"
            else:
                verdict = "pedestrian"
        b, c = int(band[i]), int(col[i])
        return PedestrianCandidate(
            band=b,
            axis_px=float(axis[i]),
            half_width_px=float(hw[i]),
            score=float(score[b, c]),
            edge_symmetry=float(s_edge[b, c]),
            grey_symmetry=float(s_grey[b, c]),
            edge_density=float(density[b, c]),
            box_px=tuple(boxes[i].tolist()),
            extended_box_px=ext_box,
            extended=bool(extended[i]),
            distance_m=d,
            lateral_m=y,
            height_m=height_m,
            width_m=width_m,
            obstacle_fraction=fraction,
            verdict=verdict,
        )

    candidates = [fused(i) for i in chosen.tolist()]
    # 6. verification (beyond the paper): a person's box that ends rejected gives way to the
    # first of its alternatives that passes steps 5-6
    if params.verify_with_hog:
        candidates = _verified(image, camera, candidates, params)
        for k in range(params.hog_alternatives):
            retry = [
                (slot, alternatives[slot][k])
                for slot, c in enumerate(candidates)
                if c.verdict != "pedestrian" and k < len(alternatives[slot])
            ]
            if not retry:
                break
            tried = _verified(image, camera, [fused(i) for _, i in retry], params)
            for (slot, _), c in zip(retry, tried, strict=True):
                if c.verdict == "pedestrian":
                    candidates[slot] = c
    score.flags.writeable = False
    half_px.flags.writeable = False
    return PedestrianResult((first, stop), bands, score, half_px, tuple(candidates))
