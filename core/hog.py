"""OpenCV's HOG people detector (Dalal and Triggs' linear SVM on 64x128 px HOG windows,
`cv2.HOGDescriptor_getDefaultPeopleDetector`), shared by the pedestrian verification
(`core.pedestrian`, step 6, beyond the papers) and the HOG baseline (`core.baselines`).

`people_scores(image, boxes)` scores given person boxes instead of searching the image:
for each box, the window that frames it as the SVM's training windows frame a person (96 of
its 128 rows, centred), is resampled to 64x128 px (bilinear, border replicated);
its score is the SVM's decision value, the HOG descriptor dotted with the SVM's weights plus
its bias. The detector's own threshold is 0 (`HOGDescriptor.detectMultiScale`'s
hitThreshold); the verification's is `PedestrianParams.hog_min_score`.

Coordinates: full-image pixels, (u0, v0, u1, v1) box bounds as `core.pedestrian` gives
them.

Notes:
    - OpenCV 5 moved `HOGDescriptor` out of the main package (objdetect) into the contrib
      module xobjdetect: `opencv-python-headless` 5.x has no HOG, while
      `opencv-contrib-python-headless` 5.x (this project's dependency) and every 4.x wheel
      have it. `hog_available()` says whether this OpenCV has it; `people_scores` raises
      `HogUnavailableError` with that advice when it does not.
    - The window's width follows from its height (1:2), not from the box's width: the
      symmetry detector's box is the body's width, which the SVM's window does not fix.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from core.checks import require_grey_image
from core.resample import box_to_grid

Box = tuple[float, float, float, float]

# OpenCV's default people detector: a 64x128 px window, 8 px block stride (a window stride
# must be a multiple of it).
HOG_WINDOW_PX = (64, 128)
HOG_BLOCK_STRIDE_PX = 8
# OpenCV samples/cpp/peopledetect.cpp: "the HOG detector returns slightly larger rectangles
# than the real objects, so we slightly shrink the rectangles": x + 10 % of the width, 80 %
# of the width; y + 7 % of the height, 80 % of the height.
HOG_PERSON_LEFT = 0.10
HOG_PERSON_TOP = 0.07
HOG_PERSON_WIDTH = 0.80
HOG_PERSON_HEIGHT = 0.80
# The SVM was trained on INRIA's 64x128 windows, a person about 96 px tall centred in each
# (Dalal and Triggs 2005, section 3: "a margin of about 16 pixels around the person on all
# four sides").
TRAINING_PERSON_PX = 96


class HogUnavailableError(RuntimeError):
    """The installed OpenCV has no HOG; the message says what to install."""


def hog_available() -> bool:
    """Whether this OpenCV has the HOG people detector (OpenCV 5's main package has not)."""
    return hasattr(cv2, "HOGDescriptor") and hasattr(cv2, "HOGDescriptor_getDefaultPeopleDetector")


def require_hog(who: str) -> None:
    """HogUnavailableError naming `who` unless this OpenCV has HOG."""
    if not hog_available():
        raise HogUnavailableError(
            f"{who}: OpenCV {cv2.__version__} has no cv2.HOGDescriptor (OpenCV 5 moved it to "
            "the contrib module xobjdetect); install opencv-contrib-python-headless instead "
            "of opencv-python-headless, or opencv-python-headless<5"
        )


@functools.cache
def _descriptor_and_svm() -> tuple[Any, npt.NDArray[np.float32], float]:
    # Any: OpenCV 5's own type stubs have no HOG (the module Notes)
    opencv: Any = cv2
    svm = np.asarray(opencv.HOGDescriptor_getDefaultPeopleDetector(), np.float32).ravel()
    return opencv.HOGDescriptor(), svm[:-1], float(svm[-1])


def window_for(box: Box) -> Box:
    """The 64x128 detector window (u0, v0, u1, v1) that frames person box `box` as the SVM's
    training windows frame a person: `TRAINING_PERSON_PX` of its 128 rows, centred."""
    u0, v0, u1, v1 = box
    height = (v1 - v0) * HOG_WINDOW_PX[1] / TRAINING_PERSON_PX
    width = height * HOG_WINDOW_PX[0] / HOG_WINDOW_PX[1]
    u, v = (u0 + u1) / 2, (v0 + v1) / 2
    return (u - width / 2, v - height / 2, u + width / 2, v + height / 2)


def people_scores(image: npt.NDArray[np.uint8], boxes_px: Sequence[Box]) -> tuple[float, ...]:
    """The SVM's decision value for each person box of `image` ((H, W) uint8 grey): positive
    is a person by the detector's own threshold. Boxes must have a positive height."""
    require_grey_image("image", image)
    require_hog("people_scores")
    if not boxes_px:
        return ()
    hog, weights, bias = _descriptor_and_svm()
    scores = []
    for box in boxes_px:
        if not box[3] > box[1]:
            raise ValueError(f"boxes_px: expected boxes with v1 > v0, got {box!r}")
        window = box_to_grid(image, window_for(box), HOG_WINDOW_PX)
        scores.append(float(np.dot(hog.compute(window).ravel(), weights)) + bias)
    return tuple(scores)
