"""OpenCV's HOG people SVM scoring given boxes (core/hog.py): known answers."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from core.hog import HOG_WINDOW_PX, TRAINING_PERSON_PX, people_scores, window_for
from core.io.drive import Drive
from core.resample import box_to_grid
from tests.conftest import REPO_ROOT
from tests.core.roadscenes import standing_person


def _person_image() -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """A standing person 12 m ahead on a plain road, and their box from the labels."""
    return standing_person(12.0, 1.5)


def test_the_window_frames_the_box_as_the_training_windows_frame_a_person() -> None:
    u0, v0, u1, v1 = window_for((100.0, 50.0, 120.0, 146.0))  # 96 px tall, axis at 110
    assert (v1 - v0) == pytest.approx(96.0 * HOG_WINDOW_PX[1] / TRAINING_PERSON_PX)  # 128
    assert (u1 - u0) == pytest.approx((v1 - v0) / 2)
    assert (u0 + u1) / 2 == pytest.approx(110.0)
    assert (v0 + v1) / 2 == pytest.approx(98.0)  # centred: 16 px above and below


def test_a_person_scores_above_the_svms_threshold_and_what_is_beside_them_below() -> None:
    image, box = _person_image()
    person, road, shifted = people_scores(
        image,
        [box, (box[0], box[3] + 5, box[2], box[3] + 5 + (box[3] - box[1])), _beside(box)],
    )
    assert person > 0.0  # OpenCV's hitThreshold
    assert road < 0.0 and shifted < person


def _beside(box: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    width = box[2] - box[0]
    return (box[0] + 3 * width, box[1], box[2] + 3 * width, box[3])


def test_scores_equal_those_of_opencvs_own_window_descriptor() -> None:
    """The resampled window is what the SVM sees: the same image cut and resized by hand,
    scored by OpenCV's compute and the detector's weights, gives the same value."""
    image, _ = _person_image()
    box = (200.0, 100.0, 232.0, 196.0)  # 96 px tall: the window is 64x128 px, no resampling
    u0, v0, _, _ = window_for(box)
    window = np.ascontiguousarray(image[int(v0) : int(v0) + 128, int(u0) : int(u0) + 64])
    svm = np.asarray(cv2.HOGDescriptor_getDefaultPeopleDetector(), np.float32).ravel()  # type: ignore[attr-defined]
    expected = float(cv2.HOGDescriptor().compute(window).ravel() @ svm[:-1]) + float(svm[-1])  # type: ignore[attr-defined]
    (score,) = people_scores(image, [box])
    assert score == pytest.approx(expected, abs=1e-3)


def _opencv_score(window: np.ndarray) -> float:
    svm = np.asarray(cv2.HOGDescriptor_getDefaultPeopleDetector(), np.float32).ravel()  # type: ignore[attr-defined]
    return float(cv2.HOGDescriptor().compute(window).ravel() @ svm[:-1]) + float(svm[-1])  # type: ignore[attr-defined]


def test_the_compiled_descriptor_scores_every_window_as_opencvs_compute() -> None:
    """core.hog computes the descriptor itself (the module Notes): on textures of every
    sharpness, flat and saturated windows and the windows of the people and vehicles of a
    bundled drive, its score equals OpenCV's within 1e-4."""
    rng = np.random.default_rng(7)
    windows = [
        cv2.GaussianBlur(rng.integers(0, 256, (128, 64), dtype=np.uint8), (5, 5), sigma)
        for sigma in (0.3, 0.8, 1.5, 3.0)
        for _ in range(5)
    ]
    windows += [np.zeros((128, 64), np.uint8), np.full((128, 64), 255, np.uint8)]
    across = np.tile(np.arange(64, dtype=np.uint8) * 4, (128, 1))
    down = np.tile((np.arange(128, dtype=np.uint8) * 2)[:, None], (1, 64))
    windows += [across, across[:, ::-1].copy(), down]
    with Drive(REPO_ROOT / "recordings" / "stop_and_go") as drive:
        for i in range(0, len(drive), 15):
            image = drive.frame(i).image
            for o in drive.truth(i).objects:
                windows.append(box_to_grid(image, window_for(o.box_px), HOG_WINDOW_PX))
    assert len(windows) > 60
    for window in windows:
        (score,) = people_scores(window, [(16.0, 16.0, 48.0, 112.0)])  # the window itself
        assert score == pytest.approx(_opencv_score(window), abs=1e-4)


def test_no_boxes_no_scores_and_bad_inputs_name_the_argument() -> None:
    image, _ = _person_image()
    assert people_scores(image, []) == ()
    with pytest.raises(ValueError, match=r"boxes_px: expected boxes with v1 > v0"):
        people_scores(image, [(10.0, 20.0, 30.0, 20.0)])
    with pytest.raises(ValueError, match="image"):
        people_scores(image.astype(np.float32), [(10.0, 20.0, 30.0, 60.0)])
