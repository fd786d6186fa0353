"""Radar-guided vehicle detection by vertical symmetry (paper 001 section II, paper 000
section II-C).

For each radar target's search area (`core.search_area`: mapped on the object's base with
the frame's pitch, W wide (wider for a moving target), W/2 high, cropped at the image
border, resampled to at most `resampled_width_px` without enlarging), steps 4-8 run in
`core.symmetry`, compiled. Beyond the papers, an area with fewer than `min_image_px_per_m`
image pixels per metre across is not searched ("too_far", Notes).

4. binarised vertical edges with their sign: horizontal Sobel derivative (3x3) of the
   resampled area, +1 where it exceeds `edge_threshold` (darker to brighter, left to
   right), -1 where it is below -`edge_threshold`;
5. the symmetry matrix: for every axis (every column, and every border between two
   columns) and every half-width w from 1 to `max_half_width_px`, the window is w pixels
   either side of the axis over the whole area height; s counts the pairs of edges
   mirrored about the axis within the window (same row) whose signs are opposite, n all
   edges in the window, chi = s^2 / n (0 when n = 0). Rows of the matrix are half-widths
   1 .. max_half_width_px, columns axes at half-column steps;
6. an axis is a candidate when chi stays below the threshold for windows narrower than
   `narrow_width_m` (fig. 3: "low for narrow area widths") and reaches it at the vehicle's
   half-width, taken as the half-width between those of the narrowest and the widest
   vehicle (`min_width_m`, `max_width_m`) with the most mirrored pairs: where the
   vehicle's two borders pair up; beyond the papers, those pairs (at that half-width, give
   or take a column) number at least `min_border_pairs_per_row` per row of the area (Notes),
   and in the area of a tracked vehicle a qualified axis takes instead the half-width within
   `track_width_tolerance_m` of the track's width with the most pairs, when chi reaches the
   threshold there with those border pairs (Notes).
   Of each run of neighbouring candidate axes the one with the highest chi is kept.
   Beyond the papers, a target where the tracker expects a vehicle whose area holds no
   candidate is searched again, given the frame's image, in its area made
   `tracked_taller_area_factor` times as high (bottom and sides kept), and that search's
   box is taken when it finds one (Notes);
7. the bottom: the lowest row where the vertical Sobel derivative says darker above and
   brighter below (the shadow under the vehicle ending on the road) across at least
   `bottom_edge_fraction` of the box's columns, beyond the papers no higher than
   `max_base_height_m` above the road at the target's distance (Notes); a candidate
   without a bottom is dropped. The top: the highest row at least `min_height_ratio` of
   the width above the bottom with horizontal edges of either sign across
   `top_edge_fraction` of the columns; without one, the box is `default_height_ratio` of
   its width high (paper 001 fig. 7.b);
8. one vehicle per radar target: the candidate whose axis is nearest the radar point's
   column (fig. 4, the most central box);
9. boxes back in full-image pixels; the world-size filter drops boxes narrower than
   `min_width_m` or wider than `max_width_m`; boxes from several targets are merged: where
   two overlap by more than `merge_overlap_fraction` of the smaller one, the larger is kept,
   unless they are of similar size (width ratio >= `similar_size_ratio`) with their bases
   at the same height (within `same_base_fraction` of the box height), which are averaged;
   boxes whose targets lie more than `merge_max_gap_m` apart in distance are never merged
   (beyond the papers, Notes);
10. world position: distance from the radar (the nearest of the vehicle's targets; the
   papers' preset: their mean, Notes), lateral position and width from vision: the box's
   bottom corners' rays crossing the vertical plane at that distance.
   The bird's-eye distance of the box base (its ground point) is kept as `vision_distance_m`.
   Beyond the papers, a vehicle partly hidden behind a nearer one: a box whose side lies
   within HIDDEN_SIDE_PX of the facing side of a nearer vehicle's box (its face or its body,
   step 12; nearer by more than HIDDEN_GAP_M, their rows overlapping) ends where that
   vehicle hides it, not at its own border. Its width is then `hidden_side_width_m` (or the
   visible width when wider) and its lateral position is measured from its free side (Notes).
11. beyond the papers, given the frame's image: each vehicle's top rises to where its two
   side borders end: from the top of step 7 up, a row holds both borders when each has a
   vertical edge (|horizontal Sobel| > `edge_threshold`) within BORDER_TOLERANCE_PX of its
   column; the top is the highest such row before a gap of more than `top_gap_ratio` x the
   box width, looked for up to `top_search_ratio` x the width above the base, and never
   below the top of step 7 (Notes). A box at least `truck_width_m` wide (a truck or a bus)
   rises to `truck_height_ratio` x its width above its base when one of its side borders has
   an edge on at least TRUCK_BORDER_SHARE of the rows in between (Notes).
12. beyond the papers, the body: the box shown and scored for a vehicle (`outline_px`)
   holds its rear face (`box_px`) and the same face `body_length_m` farther, where a
   vehicle that long, aligned with the car's axis, shows it: the face's image scaled by
   distance / (distance + body_length_m) about the vanishing point straight ahead
   (`CameraModel.ahead_px`). A vehicle beside the car's path shows its side next to the
   face, one lower than the camera its roof above it (Notes); steps 4-11 and the
   measurements keep the face.

Coordinates: areas and their matrices in resampled-area pixels (`SearchArea.patch`); boxes
in full-image pixels with pixel centres at integers, (u0, v0, u1, v1) pixel edges; world in
the vehicle frame (x forward, y left, metres).

Notes:
    - chi = s^2 / n grows with the number of edge rows, so a fixed threshold would mean more
      for a short area (a far target, not enlarged) than for a tall one. The threshold is
      per row of the area: an axis qualifies when chi >= `symmetry_threshold` x area rows.
      A perfectly symmetric pair of 1-px borders over a fraction f of the rows gives
      chi / rows = f / 2.
    - Step 5: the paper takes every column as an axis. A border at a pixel edge gives
      Sobel edge pixels on both its sides, so a vehicle an odd number of pixels wide has
      two mirrored pairs per row about a column and one an even number of pixels wide only
      one, a third of the chi: axes also lie between columns, where the even ones get their
      two pairs (the bundled drives' refined share rose from 66 to 75 % on the highway).
    - Step 6, the width: the paper takes the first width at which chi exceeds the
      threshold. On the bundled drives that width was most often that of a part of the
      vehicle (rear lights, plate, a van's windows), which is symmetric about the same axis
      and raises chi before the borders do. Taking instead the half-width where the most
      mirrored pairs lie (the borders) raised the refined share of the radar-seen vehicles
      inside a search area from 45 to 66 % (highway), 52 to 54 % (exurban) and 32 to 35 %
      (stop and go). "Low for narrow widths" is checked below `narrow_width_m` (poles,
      posts, gaps), not up to the narrowest vehicle, for the same reason.
    - Step 6, the borders (beyond the papers): chi counts every mirrored pair inside the
      window, so a window centred on something symmetric and wider than `narrow_width_m`
      (a tree trunk, a post, a sign's legs) reaches the threshold at any width, and the
      "borders" are wherever the background happens to pair. Of the chosen boxes on drives
      of seed 1414 (three scenarios), those whose target lay on a vehicle had 1.15 mirrored
      pairs per area row at their half-width (median; 10th percentile 0.65, 0.8 % below
      0.3: a step edge is two Sobel columns, so a border seen on every row gives 2), the
      false ones 0.6 (26 % below 0.3; mostly boxes on exurban's tree trunks). With
      `min_border_pairs_per_row` 0.3 (the papers' preset: 0), on drives of new seeds (20 s
      each), highway / exurban / stop_and_go, seeds 1414 + 1717 / held out 1818-2525:
      vehicle FP per frame 0.158 / 0.152 / 0.113 -> 0.135 / 0.110 / 0.090 and 0.154 /
      0.203 / 0.111 -> 0.138 / 0.156 / 0.096; RD / (RD + FN) 0.860 / 0.766 / 0.670 -> 0.863
      / 0.765 / 0.664 and 0.901 / 0.770 / 0.671 -> 0.902 / 0.767 / 0.657; radar-seen MOTA
      0.662 / 0.529 / 0.337 -> 0.665 / 0.535 / 0.358 and 0.624 / 0.566 / 0.387 -> 0.629 /
      0.557 / 0.394; nuScenes FP 0.17 -> 0.15 and aiMotive 0.06 -> 0.04 at the same RD.
      0.4 removed more FP (exurban 0.102) and more RD (stop_and_go 0.654), 0.2-0.25 less FP
      for the same RD.
    - Step 6, the tracked width (beyond the papers): a car in the next lane showed its side
      beside its face, and the face's borders were faint against a dark car behind it: the
      most pairs lay between the side's front edge and the background beyond the face's
      other border, a box 2.6 m wide on a 1.64 m car (FN "across", frames 29-52 of
      highway seed 4242), while the car's track held its width from earlier frames. Taking
      the half-width near the track's width only for an axis that qualifies anyway keeps
      an axis that qualifies only at that width from pulling the track-centred area and
      the track sideways (restricting the half-widths to the range did: a track drifted
      2 m into the next lane and took over another vehicle; stop_and_go MOTA 0.557 ->
      0.509 on seeds 5151 + 5252). `track_width_tolerance_m` 0.4 (refined_error_m; 0.25
      and 0.6 measured no better), on drives of new seeds (20 s each), highway / exurban /
      stop_and_go, RD / (RD + FN) and radar-seen MOTA, before -> after: seeds 1818-2121
      (tuning) 0.907 / 0.778 / 0.655 -> 0.912 / 0.789 / 0.674 and 0.862 / 0.590 / 0.535
      -> 0.849 / 0.594 / 0.553; seeds 4242 + 4343 0.867 / 0.750 / 0.749 -> 0.893 / 0.754
      / 0.748 and 0.822 / 0.628 / 0.638 -> 0.842 / 0.633 / 0.620; seeds 5151 + 5252 0.897
      / 0.777 / 0.686 -> 0.915 / 0.776 / 0.702 and 0.785 / 0.628 / 0.557 -> 0.825 / 0.620
      / 0.572; vehicle FP per frame within 0.001; nuScenes and aiMotive the same. Checked
      afterwards on seeds 6161 + 6262: 0.921 / 0.799 / 0.651 -> 0.922 / 0.796 / 0.654 and
      0.852 / 0.678 / 0.491 -> 0.843 / 0.674 / 0.487 (with the pedestrian change of the same
      day): no gain there. The track search (`core.track_search`) prefers its track's width
      too.
    - Step 6, still targets (beyond the papers): of the boxes on exurban drives of seeds
      1313-2727 (eight, 20 s each) whose target was still (not moving over ground faster
      than `moving_speed_mps`) and where no confirmed vehicle track was expected, 51 were
      false (posts, trunks, a rail's returns, pedestrians) and 118 on vehicles (parked
      cars); the false ones' chi over the threshold was 1.55 (median; 25th percentile 1.11),
      the vehicles' 1.98 (1.53), and below 1.2 lay 21 of the false and 17 of the vehicles'.
      Moving or tracked targets' false boxes are few (20 of 2,640). Such still, untracked
      targets need `still_symmetry_factor` x the threshold (1.2; the papers' preset 1).
      Measured on drives of new seeds, highway / exurban / stop_and_go, vehicle FP per
      frame, RD / (RD + FN) and radar-seen MOTA: held out 1818-2525 0.033 / 0.064 / 0.049
      -> 0.029 / 0.046 / 0.043, 0.902 / 0.760 / 0.657 -> 0.903 / 0.758 / 0.656, 0.619 /
      0.552 / 0.453 -> 0.619 / 0.548 / 0.445; seeds 1313-1717 + 2727: 0.029 / 0.050 / 0.048
      -> 0.028 / 0.039 / 0.046, RD the same within 0.003, MOTA within 0.002; seeds
      2929-3131: 0.035 / 0.045 / 0.042 -> 0.028 / 0.038 / 0.042, RD within 0.003, MOTA
      0.676 / 0.539 / 0.364 -> 0.676 / 0.537 / 0.367. nuScenes FP per frame 0.125 -> 0.050
      at the same RD; aiMotive the same. Vehicles labelled guard rail on exurban held out
      53 -> 57: a parked car boxed later is tracked later, and its returns are checked for
      a rail meanwhile. 1.1 removed fewer (exurban held out 0.051), 1.3 a few more RD.
      Checked afterwards on seeds not used before (3232, 3333): vehicle FP per frame 0.033
      / 0.068 / 0.052 -> 0.030 / 0.065 / 0.050, RD / (RD + FN) exurban 0.774 -> 0.769, the
      others the same: a smaller gain than on the seeds it was measured on.
    - Step 6, the taller area (beyond the papers): paper 001 names trucks taller than the
      area among its limits. The area reaches 0.875 m above the road, and what it holds of
      a van or truck in a queue (a dark bumper beside dark neighbours) often has no border
      pairs: stop_and_go's framed vehicles ending "no symmetry" in an area were vans 82
      times out of 129 (seeds 1818, 2020 and 2525). A target where the tracker expects a vehicle
      (`SearchArea.tracked`) whose area holds no candidate axis is searched again in the
      area made `tracked_taller_area_factor` (2.5) times as high, its bottom and sides
      kept, and that search's box is taken when it finds one. Only tracked targets: the
      same search for every moving target found boxes from returns beside a car (exurban
      vehicle FP per frame 0.046 -> 0.056 held out), for every target 0.116. Measured on
      drives of new seeds, highway / exurban / stop_and_go, RD / (RD + FN), vehicle FP per
      frame and radar-seen MOTA, off -> on: held out 1818-2525 0.903 / 0.758 / 0.656 ->
      0.911 / 0.764 / 0.676, FP the same (0.029 / 0.046 / 0.043), 0.688 / 0.561 / 0.459 ->
      0.679 / 0.581 / 0.499; seeds 1313-1717 + 2727 0.875 / 0.769 / 0.624 -> 0.879 / 0.772
      / 0.648, FP within 0.001, 0.713 / 0.631 / 0.397 -> 0.716 / 0.634 / 0.427; seeds
      2929-3333 0.891 / 0.745 / 0.646 -> 0.896 / 0.749 / 0.663, FP the same, 0.680 / 0.584
      / 0.386 -> 0.687 / 0.585 / 0.399. Factors 2.0 and 3.0 did the same within 0.01.
      nuScenes and aiMotive: the same figures. The second search ran 0.13-0.18 times a
      frame (one area search, about 0.05 ms). The papers' preset: 1 (no second search).
    - Step 12, the body (beyond the papers): symmetry finds a vehicle's rear face, and the
      papers' box is that face. A vehicle seen from the side of its path also shows its
      side, and one lower than the camera its roof: a truth box (the visible vehicle) of a
      car in the next lane 15-40 m ahead was a third wider than its face, so a box on the
      right face overlapped it by IoU 0.3-0.5, a miss and a false track at once for
      CLEAR-MOT (144 of the 333 false tracks on highway and exurban seeds 1818 + 2020 were
      such boxes, the detection's box as poor). The body is the box of the face and of the
      same face `body_length_m` farther, a length the vision cannot measure: one for every
      vehicle, aligned with the car (no heading is measured). Radar-seen MOTA, highway /
      exurban / stop_and_go, held out (seeds 1818-2525), rear face -> 3 / 4 / 4.5 / 6 m:
      0.619 / 0.548 / 0.445 -> 0.660 / 0.568 / 0.459, 0.688 / 0.561 / 0.459, 0.696 / 0.557
      / 0.459, 0.701 / 0.537 / 0.456; nuScenes 0.207 the same up to 4 m, 0.193 at 4.5 m,
      0.152 at 6 m (longer bodies overshoot cars on curves and in car parks; trucks want
      longer). At 4 m, seeds 1313-1717, 2727 and 2929-3131: 0.685 / 0.561 / 0.382 ->
      0.710 / 0.603 / 0.383; RD box IoU median 0.80 / 0.81 / 0.77 -> 0.86 / 0.80 / 0.83
      held out, 0.82 / 0.82 / 0.75 -> 0.87 / 0.82 / 0.85 on the others; tracked FP per
      frame 0.305 / 0.323 / 0.141 -> 0.216 / 0.295 / 0.125 held out. Checked afterwards on
      seeds not used before (3232, 3333): 0.550 / 0.563 / 0.441 -> 0.643 / 0.612 / 0.419;
      stop_and_go lost on seed 3333 (0.402 -> 0.362; 3232: 0.483 -> 0.478), where bodies
      overshot vehicles whose sides nearer ones hide in the queues. The detections and
      their distance, lateral position and width are the face's, unchanged. Pedestrian
      boxes inside a vehicle's body are the ones `core.pedestrian` removes (step 5), and
      pitch leaves the bodies out: pedestrian precision exurban 0.98 -> 0.99, stop_and_go
      0.99 -> 1.00, recall and pitch the same.
    - Steps 6 and 9, the narrowest vehicle: the paper gives no figure for its "too small
      boxes". At 1.2 m (the papers' preset) the pair of rear lights of a dark car or van
      against a dark background, 1.2-1.3 m apart, was taken for the vehicle: most refined
      widths that missed by more than 0.4 m were those. `min_width_m` is 1.5 m, below the
      narrowest cars sold (about 1.55 m): half-widths below it are not candidates and
      narrower boxes are dropped. Measured, 1.2 -> 1.5 m, on drives of new seeds (20 s
      each), RD / (RD + FN), vehicle FP per frame and radar-seen tracked MOTA: seeds
      404-606 highway 0.81 / 0.41 / 0.35 -> 0.84 / 0.35 / 0.41, exurban 0.69 / 0.23 / 0.39
      -> 0.71 / 0.15 / 0.42, stop_and_go 0.55 / 0.27 / 0.15 -> 0.57 / 0.19 / 0.15; seeds
      101-303 and 707-909: highway 0.85 / 0.40 / 0.53 -> 0.85 / 0.35 / 0.53, exurban 0.70 /
      0.29 / 0.38 -> 0.71 / 0.20 / 0.40, stop_and_go 0.57 / 0.26 / 0.16 -> 0.58 / 0.17 /
      0.16; nuScenes RD one fewer (0.57 -> 0.56), FP 1.63 -> 1.00, MOTA 0.14 -> 0.15;
      aiMotive FP 0.92 -> 0.82. 1.4 m did less on FP and the same on RD.
    - Step 7: with the paper's area (W/2 high, 30 % below the radar point) the area reaches
      0.35 W above a vehicle's base, lower than the roof of any car, so the top is found only
      for low objects and the fixed ratio is the rule, as the paper says for trucks. The
      world-size filter therefore checks the width only.
    - Step 7, the bottom: the paper looks for the vehicle's shadow and gives no share of
      the box it must span. A vehicle's shadow and wheels end on the road across its whole
      width; a rail post, a sign's foot or the gap between two cars end on it across part
      of a box. `bottom_edge_fraction` is 0.8 (the papers' preset: 0.5, chosen when the
      project began). Measured, 0.5 -> 0.8, with the 1.5 m narrowest vehicle, RD / (RD + FN),
      vehicle FP per frame and radar-seen tracked MOTA: seeds 404-606 highway 0.84 / 0.35 /
      0.41 -> 0.84 / 0.18 / 0.46, exurban 0.71 / 0.15 / 0.42 -> 0.70 / 0.09 / 0.41,
      stop_and_go 0.57 / 0.19 / 0.15 -> 0.57 / 0.08 / 0.20; seeds 101-303 and 707-909
      highway 0.85 / 0.35 / 0.53 -> 0.86 / 0.21 / 0.55, exurban 0.71 / 0.20 / 0.40 -> 0.70 /
      0.10 / 0.42, stop_and_go 0.58 / 0.17 / 0.16 -> 0.56 / 0.07 / 0.24; nuScenes RD 0.56 ->
      0.54 (one vehicle), FP 1.00 -> 0.55, MOTA 0.15 -> 0.21; aiMotive FP 0.82 -> 0.62.
      0.7 kept more FP for the same RD; 0.9 lost more RD (stop_and_go 0.55).
    - Step 7, the base's height (beyond the papers): the area reaches 0.7 of its height
      above the radar point's road row, and a dark region ending on a brighter one there
      passed for a shadow: the rear window of a nearer car that hides a guard-rail return
      beyond it, a roof, the lower edge of a sign. Of the chosen boxes on drives of seed
      1414 (three scenarios), those whose target lay on a vehicle had their base 0.07 m
      below the target's road row (median; 3.5 % more than 0.3 m above it), the false
      ones 0.00 m (37 % more than 0.3 m above); nuScenes' 0.08 m below (none above 0.3
      m). With `max_base_height_m` 0.3 (the papers' preset: 1000, anywhere), on drives of
      new seeds, highway / exurban / stop_and_go, seeds 1414 + 1717 / held out 1818-2525:
      vehicle FP per frame 0.135 / 0.110 / 0.090 -> 0.085 / 0.095 / 0.062 and 0.138 /
      0.156 / 0.096 -> 0.077 / 0.131 / 0.084; RD / (RD + FN) within 0.005; radar-seen
      MOTA 0.665 / 0.535 / 0.358 -> 0.666 / 0.541 / 0.428 and 0.629 / 0.557 / 0.394 ->
      0.629 / 0.569 / 0.424, track FP per frame on stop_and_go 0.242 -> 0.107 and 0.223 ->
      0.142; nuScenes FP 0.15 -> 0.12 and aiMotive 0.04 -> 0.02 at the same RD. 0.5 m
      removed less FP for the same RD.
    - Step 9, beyond the papers: merging by overlap alone made one "vehicle" 6.5-8.4 m
      wide of a van's box at 35 m and boxes of targets at 80-100 m seen above it (the
      aiMotive night motorway); boxes now merge only when their targets lie within
      `merge_max_gap_m` (5 m) of each other in distance, a chain of them for a truck's
      returns along its length. Step 10: the distance is the nearest target's, not the mean:
      the nearest return is the one nearest the vehicle's near face (real radars return
      points all along a vehicle: 0.55 m beyond the labelled rear face on nuScenes, 1.09 m on
      aiMotive, median). Both together, measured on drives of new seeds (20 s each, seeds
      101 and 202) and the real drives, RD / (RD + FN): stop_and_go 0.54 -> 0.63 and 0.56 ->
      0.62, exurban 0.72 -> 0.75 and 0.65 -> 0.66, highway 0.91 -> 0.92 and 0.91, nuScenes
      scene-0523 0.34 -> 0.40, with the same FP; the same within one vehicle for gaps of
      1.5 to 5 m. The papers' preset keeps both off (a gap of 1000 m, the mean).
    - Step 11, beyond the papers: paper 001 names trucks taller than the area (its fig.
      7.b) and gives them a box of a fixed ratio; with the 4 m areas of moving targets
      (`core.search_area`) many more trucks were refined, each boxed to about half its
      height, and the tracked boxes missed IoU 0.5 with the truth: tracked-vehicle MOTA on
      the bundled highway fell to -0.15. A vehicle's sides are vertical edges from its base
      to its roof, which the area (1.25 m high) does not reach. Measured box IoU of the
      refined vehicles (median, share >= 0.6) and tracked MOTA, fixed ratio -> step 11:
      bundled highway 0.46 / 0.44 / -0.08 -> 0.71 / 0.77 / 0.25; highway seed 202 0.71 /
      0.60 / 0.01 -> 0.82 / 0.76 / 0.20 (2.0 x width, gap 0.15); exurban seed 202 0.87 /
      0.79 / 0.21 -> 0.83 / 0.90 / 0.33; stop_and_go seed 101 0.74 / 0.80 / 0.18 -> 0.71 /
      0.80 / 0.18; nuScenes 0.68 / 0.84 -> 0.71 / 0.81, MOTA 0.15 both. A search up to
      1.8 x the width or with gaps of 0.1 x the width stopped trucks short; 2.2 did no
      better than 2.0. Distance, lateral position and width do not change. A side as
      bright as what lies behind it (a white trailer against the sky) ends the top there.
      The rows are followed from step 7's top, not from the base: a truck's rear above a
      dark underride has no border at its sides for its lowest rows, more than the gap
      allows, and the search used to stop there. Tracked MOTA, from the base -> from step
      7's top, seeds 404-606 (three each): highway 0.30 -> 0.36, exurban 0.31 -> 0.37,
      stop_and_go 0.10 -> 0.11; seeds 101-303: 0.35 -> 0.48, 0.32 -> 0.36, 0.11 -> 0.14;
      nuScenes 0.11 -> 0.10; RD, FN and FP do not change.
    - Step 11, trucks (beyond the papers): a white trailer against a bright sky shows no
      border on the side away from its own side panel, so the top where both borders end
      stopped at about 0.8-1.0 x the width, half a truck's height: highway's tracked trucks
      overlapped their truth boxes by IoU 0.3-0.5, a miss and a false track at once. Trucks
      are 2.45-2.6 m wide and 3.6-4.0 m tall (cars 1.6-1.95 m wide, vans 1.9-2.1 m; the
      synthetic drives' measured widths reach 2.3 m for 98 % of the trucks' frames, 1-2.5 %
      of the cars' and 4-15 % of the vans', whose boxes then hold face and side). The box
      rises to 1.4 x its width where one border goes on up to there. Measured on drives of
      new seeds (seeds 1818-2525, 20 s each), off -> on: radar-seen MOTA highway / exurban /
      stop_and_go 0.654 / 0.607 / 0.479 -> 0.834 / 0.581 / 0.478, RD box IoU >= 0.6 on
      highway 0.85 -> 0.99, RD the same within 0.003. Exurban loses on its van that the
      detector boxes 2.4-2.9 m wide with something beside it (IoU 0.51-0.61 before, 0.4
      after); requiring both a wider box (2.4 m) and a border on 90 % of the rows kept less
      of highway's gain (0.794) for less of exurban's loss (0.583). nuScenes and aiMotive
      the same. The papers' preset: 0 (off).
    - Too far, beyond the papers: at 10 image pixels per metre the narrowest vehicle
      (1.5 m) is 15 px wide and a 2.5 m area 25 px; below it the symmetry of a few pixels'
      noise picked out boxes on trees, signs and rail posts 60-170 m away, where no vehicle
      could be refined within the 0.4 m tolerance. On the real drives (a 640 px camera
      reaches 10 px/m at about 59 m): vehicle FP per frame nuScenes 0.525 -> 0.175,
      aiMotive 0.52 -> 0.06 (its false tracks 27 -> 0), RD the same; at 15 px/m nuScenes
      lost 5 of 29 RD. The synthetic drives' areas all have more than 12 px/m, and nothing
      changed on them. The papers' preset: 0 (every area is searched).
    - Step 10: the paper maps the box base to the world by inverse perspective mapping and
      takes the distance from the radar; here lateral position and width come from the
      rays at the radar's distance, so a bottom found a few rows off (pitch, shadow) moves
      neither.
    - Step 10, a vehicle hidden on one side (beyond the papers): of the framed vehicles radar
      gave vision that vision did not refine, on drives of new seeds (20 s each, seeds
      1818-2121), a third had a box whose lateral position or width was more than 0.4 m off,
      and on exurban most of them were one van, driving 26 m behind the lead car in its lane
      and partly hidden by it on the curves (63-82 frames of each drive; vans' RD / (RD + FN)
      0.29-0.47 against cars' 0.90-0.92). Its box runs from its own outer side to the lead
      car's side, which symmetry pairs with it. Such a box (its side within HIDDEN_SIDE_PX of
      the facing side of a nearer vehicle's face or body, rows in common) has only one of its
      borders: it gets `hidden_side_width_m` = 1.85 m, the middle of cars' and vans' widths
      (1.6-2.1 m, each then within the 0.4 m tolerance), or its visible width when wider, and
      its lateral position from its free side. RD / (RD + FN), exurban / stop_and_go, off ->
      on: seeds 1818-2121 0.762 / 0.654 -> 0.778 / 0.655, vehicle FP per frame 0.051 / 0.046
      -> 0.049 / 0.045, tracked RD 0.760 / 0.727 -> 0.771 / 0.731; held out, seeds 4242 +
      4343: 0.743 / 0.749 -> 0.750 / 0.749, radar-seen MOTA 0.618 / 0.638 -> 0.628 / 0.638;
      seeds never used before (5151 + 5252): 0.766 / 0.689 -> 0.777 / 0.686, FP per frame
      0.043 / 0.048 -> 0.045 / 0.052, MOTA 0.618 / 0.532 -> 0.628 / 0.557. Highway (seeds
      1818-2121, 4242, 4343), nuScenes and aiMotive: the same figures. The width is what
      decides (1.75 / 1.95 m: exurban 0.768 / 0.788 on seeds 1818-2121, whose van is 1.9-2.1
      m wide); it is not tuned to that van. Measured and not adopted: the tracker measuring
      such a vehicle's free side with its own width and not its width (tracked RD on exurban
      0.771 -> 0.786 on seeds 1818-2121 but 0.736 -> 0.712 held out, MOTA 0.628 -> 0.585).
      Most of stop_and_go's hidden vehicles, in the queue, are not boxed at all (no symmetry
      or no bottom where their lower part is hidden), which this step does not reach. The
      papers' preset: 0 (off).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np
import numpy.typing as npt

from core import symmetry
from core.camera import CameraModel
from core.io.frame import RadarTarget
from core.params import VehicleParams
from core.search_area import SearchArea, intersection_area, rect_area, taller

F32Array = npt.NDArray[np.float32]
I8Array = npt.NDArray[np.int8]

# Why a radar target has no vehicle of its own.
Verdict = Literal[
    "vehicle",  # its box is (part of) a final vehicle
    "outside_image",  # its radar point is not in the image
    "guard_rail",  # the guard-rail filter labelled it: not searched
    "too_far",  # its area has fewer image pixels per metre than min_image_px_per_m
    "no_symmetry",  # no axis qualifies
    "no_bottom",  # axes, but no box with a bottom
    "size_filter",  # the chosen box is too narrow or too wide for a vehicle
]

Box = tuple[float, float, float, float]
# The side of a box a nearer vehicle hides (step 10)
Side = Literal["left", "right"]
U8Array = npt.NDArray[np.uint8]

# Step 11: a border's vertical edge may lie this many columns off the box's side.
BORDER_TOLERANCE_PX = 2
# Step 10: a box's side this close to the facing side of a nearer vehicle's box ends on it
HIDDEN_SIDE_PX = 3.0
# Step 10: a vehicle nearer than another by more than this may hide a part of it
HIDDEN_GAP_M = 2.0
# Step 11: the share of rows above a truck-wide box's top where one of its borders goes on,
# for its top to rise to a truck's height (a white trailer against a bright sky shows only
# the border with its own side)
TRUCK_BORDER_SHARE = 0.5


@dataclass(frozen=True)
class Candidate:
    """One candidate box in resampled-area pixels.

    axis_px: axis column (whole or half); half_width_row: the symmetry matrix's half-width
    w (row w - 1) taken as the vehicle's; half_width_px: the borders' distance from the
    axis's centre (sub-pixel); chi: the matrix value at (w, axis); bottom_px / top_px:
    pixel-edge rows of the box base and top (None when not found); box_px: (u0, v0, u1, v1)
    in the full image (None without a bottom).
    """

    axis_px: float
    half_width_row: int
    half_width_px: float
    chi: float
    bottom_px: int | None
    top_px: int | None
    box_px: Box | None


@dataclass(frozen=True, eq=False)
class TargetResult:
    """What the detector did with one radar target.

    area: its search area (None when outside the image); edges: (h, w) int8 signed vertical
    edges of the resampled area; symmetry: (max_half_width_px, 2 w - 1) float32 chi, row k is
    half-width k + 1; threshold: the chi an axis had to reach; candidates: the axes that
    qualified, with their boxes; chosen: index into candidates of the most central box with
    a bottom; box_px (property): the chosen box in full-image pixels; verdict: see
    `Verdict`; vehicle_index: the final vehicle it is part of; taller: the area is the
    target's search area made taller (step 6, `tracked_taller_area_factor`), searched after
    the area itself held no candidate axis.
    """

    target_index: int
    target: RadarTarget
    area: SearchArea | None
    edges: I8Array
    symmetry: F32Array
    threshold: float
    candidates: tuple[Candidate, ...]
    chosen: int | None
    verdict: Verdict
    vehicle_index: int | None
    taller: bool = False

    @property
    def box_px(self) -> Box | None:
        return None if self.chosen is None else self.candidates[self.chosen].box_px


@dataclass(frozen=True)
class Vehicle:
    """A detected vehicle: box_px (u0, v0, u1, v1) in the full image, its rear face;
    distance_m from the radar, lateral_m (positive left) and width_m from vision;
    vision_distance_m: where the box base meets the road; target_indices: the radar targets
    it came from; body_px: the box of its body (step 12, `body_box`; None: the face's);
    hidden_side: "left" or "right" when a nearer vehicle hides that side (step 10), its
    width then not measured but `hidden_side_width_m`; None when both borders are seen."""

    box_px: Box
    distance_m: float
    lateral_m: float
    width_m: float
    vision_distance_m: float
    target_indices: tuple[int, ...]
    body_px: Box | None = None
    hidden_side: Side | None = None

    @property
    def outline_px(self) -> Box:
        """The box shown and scored: the body's, else the face's."""
        return self.box_px if self.body_px is None else self.body_px


@dataclass(frozen=True, eq=False)
class VehicleResult:
    targets: tuple[TargetResult, ...]  # one per radar target, in radar order
    vehicles: tuple[Vehicle, ...]


# --- steps 4-8 ------------------------------------------------------------------------------


def _search(area: SearchArea, params: VehicleParams, image: U8Array | None) -> TargetResult:
    """Steps 4-8 on one area, and on the taller area of a tracked target whose own holds
    no candidate axis when the image is given (step 6): the taller one's result when it
    gives a box."""
    result = _search_area(area, params)
    factor = params.tracked_taller_area_factor
    if result.candidates or not area.tracked or factor == 1 or image is None:
        return result
    tall = taller(area, image, factor, params)
    if tall is None:
        return result
    again = _search_area(tall, params)
    return result if again.box_px is None else dataclasses.replace(again, taller=True)


def _search_area(area: SearchArea, params: VehicleParams) -> TargetResult:
    """Steps 4-8 on one area (`core.symmetry.search`); the verdict says only whether an
    axis or a box was found (`detect_vehicles` settles it)."""
    h = area.patch.shape[0]
    threshold = params.symmetry_threshold * h
    if not (area.moving or area.tracked):
        threshold *= params.still_symmetry_factor
    base_col, base_row = area.to_patch_px(*area.base_px)  # the radar point's base
    # the half-widths near a tracked vehicle's width, preferred (0, 0: none; candidate_axes
    # keeps them within the vehicles' widths)
    preferred = (0, 0)
    tolerance_m, track_width_m = params.track_width_tolerance_m, area.tracked_width_m
    if tolerance_m > 0 and track_width_m > 0:  # False on NaN: not tracked
        preferred = (
            math.ceil((track_width_m - tolerance_m) / 2 * area.px_per_m),
            math.floor((track_width_m + tolerance_m) / 2 * area.px_per_m),
        )
    edges, chi, found, chosen = symmetry.search(
        area.patch,
        base_col,  # the area's centre column
        float(params.edge_threshold),
        params.max_half_width_px,
        threshold,
        math.ceil(params.narrow_width_m / 2 * area.px_per_m),
        math.ceil(params.min_width_m / 2 * area.px_per_m),
        math.floor(params.max_width_m / 2 * area.px_per_m),
        params.bottom_edge_fraction,
        params.top_edge_fraction,
        params.min_height_ratio,
        math.ceil(params.min_border_pairs_per_row * h),
        math.floor(base_row - params.max_base_height_m * area.px_per_m),
        *preferred,
    )
    candidates = _candidates(area, found, params)
    return TargetResult(
        target_index=area.target_index,
        target=area.target,
        area=area,
        edges=edges,
        symmetry=chi,
        threshold=threshold,
        candidates=candidates,
        chosen=None if chosen < 0 else chosen,
        verdict="no_bottom" if candidates else "no_symmetry",
        vehicle_index=None,
    )


def _candidates(
    area: SearchArea, found: npt.NDArray[np.float64], params: VehicleParams
) -> tuple[Candidate, ...]:
    """The candidates of `core.symmetry.search` with their boxes in the full image."""
    if len(found) == 0:
        return ()
    centre = found[:, symmetry.AXIS] / 2 + 0.5  # pixel c spans the pixel-edge columns c .. c + 1
    half_px = found[:, symmetry.HALF_PX]
    (u0, u1), (v_bottom, v_top) = area.to_image_px(
        [centre - half_px, centre + half_px], [found[:, symmetry.BOTTOM], found[:, symmetry.TOP]]
    )
    v_top = np.where(
        found[:, symmetry.TOP] >= 0, v_top, v_bottom - params.default_height_ratio * (u1 - u0)
    )
    rows = zip(found.tolist(), np.stack([u0, v_top, u1, v_bottom], axis=1).tolist(), strict=True)
    return tuple(
        Candidate(
            axis_px=f[symmetry.AXIS] / 2,
            half_width_row=int(f[symmetry.ROW]) + 1,
            half_width_px=f[symmetry.HALF_PX],
            chi=f[symmetry.CHI],
            bottom_px=None if f[symmetry.BOTTOM] < 0 else int(f[symmetry.BOTTOM]),
            top_px=None if f[symmetry.TOP] < 0 else int(f[symmetry.TOP]),
            box_px=None if f[symmetry.BOTTOM] < 0 else tuple(box),
        )
        for f, box in rows
    )


# --- steps 9-10 ------------------------------------------------------------------------------


def world_extents(
    boxes_px: Sequence[Box], distances_m: Sequence[float], camera: CameraModel
) -> tuple[list[float], list[float], list[float]]:
    """(lateral_m, width_m, vision_distance_m) of each box: where its bottom corners' rays
    cross the vertical plane x = its distance; vision_distance_m: x where the base centre
    meets the road (NaN at or above the horizon)."""
    if not boxes_px:
        return [], [], []
    n = len(boxes_px)
    bases = [(u0, v1) for u0, _, _, v1 in boxes_px]  # left, right and middle of the bases
    bases += [(u1, v1) for _, _, u1, v1 in boxes_px]
    bases += [((u0 + u1) / 2, v1) for u0, _, u1, v1 in boxes_px]
    rays = camera.rays_vehicle(bases).tolist()
    ox, oy, oz = camera.position_vehicle_m.tolist()
    lateral, width, vision = [], [], []
    for (lx, ly, _), (rx, ry, _), (mx, _, mz), x_m in zip(
        rays[:n], rays[n : 2 * n], rays[2 * n :], distances_m, strict=True
    ):
        # forward rays only: those of image points always are
        y_left = oy + ly * (x_m - ox) / lx if lx > 0 else math.nan
        y_right = oy + ry * (x_m - ox) / rx if rx > 0 else math.nan
        lateral.append((y_left + y_right) / 2)
        width.append(y_left - y_right)
        vision.append(ox - oz / mz * mx if mz < 0 else math.nan)  # the ray descends to z = 0
    return lateral, width, vision


def world_size_ok(
    box_px: Box, distance_m: float, camera: CameraModel, params: VehicleParams
) -> bool:
    """The world-size filter: is the box as wide as a vehicle (`min_width_m` .. `max_width_m`)
    at the radar's distance?"""
    (width_m,) = world_extents([box_px], [distance_m], camera)[1]
    return _vehicle_wide(width_m, params)


def _vehicle_wide(width_m: float, params: VehicleParams) -> bool:
    return params.min_width_m <= width_m <= params.max_width_m


def overlap_of_smaller(a: Box, b: Box) -> float:
    """The share of the smaller of two image boxes that the other covers."""
    return intersection_area(a, b) / max(min(rect_area(a), rect_area(b)), 1e-9)


def merge_boxes(
    boxes: list[tuple[Box, int]], params: VehicleParams, distances_m: Sequence[float] = ()
) -> list[tuple[Box, list[int]]]:
    """Merge (box, target_index) pairs from several targets (paper 001, II).

    Largest first; a box overlapping a kept one by more than `merge_overlap_fraction` of the
    smaller is dropped in its favour, unless the two are of similar width with their bases
    at the same height, when the kept box becomes the mean of the boxes merged into it.
    distances_m: each radar target's distance, by target index; when given, a box joins a
    kept one only when its target lies within `merge_max_gap_m` of one of the kept one's.
    Returns (box, target indices) per kept box, largest first.
    """
    order = sorted(boxes, key=lambda bt: -rect_area(bt[0]))
    kept: list[tuple[list[Box], list[int]]] = []  # the boxes averaged into each, their targets
    for box, target in order:
        for members, targets in kept:
            if distances_m and params.merge_max_gap_m < min(
                abs(distances_m[target] - distances_m[t]) for t in targets
            ):
                continue
            ref = _mean_box(members)
            if overlap_of_smaller(ref, box) <= params.merge_overlap_fraction:
                continue
            w_ref, w_box = ref[2] - ref[0], box[2] - box[0]
            h_ref = ref[3] - ref[1]
            similar = min(w_ref, w_box) / max(w_ref, w_box) >= params.similar_size_ratio
            same_base = abs(ref[3] - box[3]) <= params.same_base_fraction * h_ref
            if similar and same_base:
                members.append(box)
            targets.append(target)
            break
        else:
            kept.append(([box], [target]))
    return [(_mean_box(members), targets) for members, targets in kept]


def _mean_box(boxes: list[Box]) -> Box:
    u0, v0, u1, v1 = (sum(side) / len(boxes) for side in zip(*boxes, strict=True))
    return (u0, v0, u1, v1)


def _border_edges(
    image: U8Array, u0: float, u1: float, row0: int, row1: int, params: VehicleParams
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]] | None:
    """Rows row0 .. row1 - 1 of the image: does each hold a vertical edge (|horizontal
    Sobel| > `edge_threshold`) within BORDER_TOLERANCE_PX of the left border's column, of
    the right one's? None when the columns reach outside the image or no row is asked."""
    h_img, w_img = image.shape
    left, right = round(u0 + 0.5), round(u1 - 0.5)  # the border pixels' columns
    c0, c1 = left - BORDER_TOLERANCE_PX - 1, right + BORDER_TOLERANCE_PX + 2
    if c0 < 0 or c1 > w_img or row0 < 0 or row1 > h_img or row1 <= row0:
        return None
    crop = image[row0 - (row0 > 0) : row1 + (row1 < h_img), c0:c1]
    dx = np.abs(np.asarray(cv2.Sobel(crop, cv2.CV_16S, 1, 0, ksize=3)))
    strong = dx[(row0 > 0) : (row0 > 0) + row1 - row0] > params.edge_threshold
    k = BORDER_TOLERANCE_PX
    on_left = np.asarray(strong[:, 1 : 2 * k + 2].any(axis=1), dtype=np.bool_)
    on_right = np.asarray(strong[:, -2 * k - 2 : -1].any(axis=1), dtype=np.bool_)
    return on_left, on_right


def border_top(image: U8Array, box: Box, params: VehicleParams) -> float:
    """Step 11: the top row edge of `box` (u0, v0, u1, v1 in full-image pixels) where its
    side borders end, at most its own top `v0`; `v0` when the search is off."""
    u0, v0, u1, v1 = box
    width = u1 - u0
    bottom = min(math.floor(v1 + 0.5), image.shape[0])  # rows above the base's pixel-edge row
    highest = max(math.ceil(v1 + 0.5 - params.top_search_ratio * width), 0)
    if params.top_search_ratio == 0 or bottom - highest < 3:
        return v0
    # the rows searched: from step 7's top up (those below it are the symmetric region's)
    stop = min(max(math.floor(v0 + 0.5), highest), bottom)
    edges = _border_edges(image, u0, u1, highest, stop, params)
    if edges is None:
        return v0
    both: list[bool] = np.logical_and(*edges).tolist()
    gap_max = max(2, round(params.top_gap_ratio * width))
    top, gap = None, 0
    for r in range(len(both) - 1, -1, -1):
        if both[r]:
            top, gap = r, 0
        else:
            gap += 1
            if gap > gap_max:
                break
    return v0 if top is None else min(v0, highest + top - 0.5)


def _top(image: U8Array, box: Box, width_m: float, params: VehicleParams) -> float:
    """Step 11: the top where the box's borders end (`border_top`), raised further to a
    truck's height for a box as wide as a truck (`truck_top`)."""
    top = border_top(image, box, params)
    return truck_top(image, (box[0], top, box[2], box[3]), width_m, params)


def truck_top(image: U8Array, box: Box, width_m: float, params: VehicleParams) -> float:
    """Step 11 for a box as wide as a truck (`truck_width_m`): its top row edge rises to
    `truck_height_ratio` x its width above its base when, on at least TRUCK_BORDER_SHARE of
    the rows between there and its top `v0`, one of its side borders has a vertical edge;
    else (and when it is already as tall, or that row lies above the image) it stays `v0`."""
    u0, v0, u1, v1 = box
    if params.truck_height_ratio == 0 or width_m < params.truck_width_m:
        return v0
    top = v1 - params.truck_height_ratio * (u1 - u0)
    edges = _border_edges(image, u0, u1, math.ceil(top + 0.5), math.floor(v0 + 0.5), params)
    if edges is None:
        return v0
    either = np.logical_or(*edges)
    return top if either.mean() >= TRUCK_BORDER_SHARE else v0


def body_box(box_px: Box, distance_m: float, camera: CameraModel, length_m: float) -> Box:
    """Step 12: the image box of a vehicle whose rear face is `box_px` at `distance_m`, with
    the same face `length_m` farther along the car's axis; `box_px` itself when length_m is
    0 or the distance is not positive."""
    if not (length_m > 0 and distance_m > 0):
        return box_px
    u_vp, v_vp = camera.ahead_px
    scale = distance_m / (distance_m + length_m)
    u0, v0, u1, v1 = box_px
    far = (
        u_vp + (u0 - u_vp) * scale,
        v_vp + (v0 - v_vp) * scale,
        u_vp + (u1 - u_vp) * scale,
        v_vp + (v1 - v_vp) * scale,
    )
    return (min(u0, far[0]), min(v0, far[1]), max(u1, far[2]), max(v1, far[3]))


def hidden_sides(vehicles: Sequence[Vehicle]) -> list[Side | None]:
    """Step 10, beyond the papers: for each vehicle, the side of its box that ends on a
    nearer vehicle's box (module docstring), None when neither or both do."""
    out: list[Side | None] = []
    for v in vehicles:
        u0, v0, u1, v1 = v.box_px
        left = right = False
        for n in vehicles:
            if n.distance_m >= v.distance_m - HIDDEN_GAP_M:
                continue
            for b in {n.box_px, n.outline_px}:
                if b[1] >= v1 or b[3] <= v0:  # no row in common
                    continue
                left = left or (abs(b[2] - u0) <= HIDDEN_SIDE_PX and b[0] < u0)
                right = right or (abs(b[0] - u1) <= HIDDEN_SIDE_PX and b[2] > u1)
        out.append("left" if left and not right else "right" if right and not left else None)
    return out


def measured_past_hidden_sides(vehicles: Sequence[Vehicle], width_m: float) -> tuple[Vehicle, ...]:
    """Step 10, beyond the papers: each vehicle that a nearer one hides on one side
    (`hidden_sides`) made `width_m` wide (its visible width when wider), its lateral position
    measured from its other side (positive y is the image's left); the others as they are."""
    out = []
    for v, side in zip(vehicles, hidden_sides(vehicles), strict=True):
        if side is None:
            out.append(v)
            continue
        wide_m = max(width_m, v.width_m)
        if side == "left":  # the image's left, the larger y, is hidden: its right side is seen
            lateral_m = v.lateral_m - v.width_m / 2 + wide_m / 2
        else:
            lateral_m = v.lateral_m + v.width_m / 2 - wide_m / 2
        out.append(dataclasses.replace(v, lateral_m=lateral_m, width_m=wide_m, hidden_side=side))
    return tuple(out)


def detect_vehicles(
    areas: tuple[SearchArea, ...],
    radar: tuple[RadarTarget, ...],
    camera: CameraModel,
    params: VehicleParams,
    guard_rails: frozenset[int] = frozenset(),
    image: U8Array | None = None,
) -> VehicleResult:
    """Vehicles from the search areas of a frame's radar targets.

    areas: `core.search_area.search_areas` of the frame; radar: the frame's targets (those
    without an area are outside the image); camera: the frame's camera model; guard_rails:
    indices of targets the guard-rail filter labelled, which are not searched; image: the
    frame's (H, W) uint8 grey image, for the taller areas of step 6 and for step 11 (None:
    no taller area, and boxes keep the top of step 7).
    """
    by_target = {a.target_index: a for a in areas}
    if len(by_target) != len(areas) or any(not 0 <= i < len(radar) for i in by_target):
        raise ValueError(
            f"areas: expected at most one area per radar target 0..{len(radar) - 1}, "
            f"got target indices {sorted(a.target_index for a in areas)}"
        )
    too_far = {a.target_index for a in areas if a.too_far}
    skipped = guard_rails | too_far
    searched = [a for a in areas if a.target_index not in skipped]
    found = {a.target_index: _search(a, params, image) for a in searched}
    chosen = {i: box for i, f in found.items() if (box := f.box_px) is not None}
    ids = list(chosen)
    _, widths_m, _ = world_extents([chosen[i] for i in ids], [radar[i].x_m for i in ids], camera)
    sized = [
        (chosen[i], i)
        for i, width_m in zip(ids, widths_m, strict=True)
        if _vehicle_wide(width_m, params)
    ]
    merged = merge_boxes(sized, params, [t.x_m for t in radar])
    of_targets = np.min if params.distance_of_nearest_target else np.mean
    distances_m = [float(of_targets([radar[t].x_m for t in ts])) for _, ts in merged]
    lateral_m, width_m, vision_m = world_extents([b for b, _ in merged], distances_m, camera)
    if image is not None:
        merged = [
            ((b[0], _top(image, b, w, params), b[2], b[3]), ts)
            for (b, ts), w in zip(merged, width_m, strict=True)
        ]
    vehicles = tuple(
        Vehicle(
            box,
            distances_m[j],
            lateral_m[j],
            width_m[j],
            vision_m[j],
            tuple(sorted(ts)),
            body_box(box, distances_m[j], camera, params.body_length_m)
            if params.body_length_m > 0
            else None,
        )
        for j, (box, ts) in enumerate(merged)
    )
    if params.hidden_side_width_m > 0:
        vehicles = measured_past_hidden_sides(vehicles, params.hidden_side_width_m)
    vehicle_of = {t: j for j, (_, ts) in enumerate(merged) for t in ts}
    empty_edges = np.zeros((0, 0), dtype=np.int8)
    empty_sym = np.zeros((params.max_half_width_px, 0), dtype=np.float32)
    results = []
    for i, target in enumerate(radar):
        area, f = by_target.get(i), found.get(i)
        if f is None:
            verdict: Verdict = (
                "outside_image" if area is None else "too_far" if i in too_far else "guard_rail"
            )
            results.append(
                TargetResult(i, target, area, empty_edges, empty_sym, 0.0, (), None, verdict, None)
            )
            continue
        if i in vehicle_of:
            f = dataclasses.replace(f, verdict="vehicle", vehicle_index=vehicle_of[i])
        elif i in chosen:
            f = dataclasses.replace(f, verdict="size_filter")
        results.append(f)
    return VehicleResult(tuple(results), vehicles)
