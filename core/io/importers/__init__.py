"""`fusionscope import`: a recording folder from a source, one module per source.

- video: any file OpenCV reads, resampled to a frame rate.
- still: one image at a given time.
- bag: a ROS 1 or ROS 2 bag, copied as is.

Shared by the importers:

- finish: the finishing step -- the folder written under a temporary name and renamed at the
  end, its calibration and manifest, the options every import takes and its result.
- calibration_spec: the camera and radar calibration as given on the command line.
- can_mapping: the CAN mapping file, checked against the DBC files and the CAN frames.
"""
