"""Scoring the engine against ground truth, the papers' way and beyond (`fusionscope evaluate`).

- `vehicles`: paper 001's frame-based statistics (RD, FN, RFN, FP, NVO) and its events;
- `objects`: pedestrians per fusion filter (paper 000), guard rails (paper 002), motion
  stereo's obstacle mask and the pitch;
- `mot`: CLEAR-MOT (MOTA, MOTP), IDF1 and id switches of tracked output;
- `evaluate`: one recording played through the engine and scored, and totals;
- `report`: the figures as paper-style tables, markdown, CSV or JSON.
"""
