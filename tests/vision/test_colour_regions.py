"""Colour prior of a named colour and blobs with sub-pixel centroids."""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.colour_model import NAMED_COLOURS
from wipelab.vision.colour_regions import blob_mask, find_blobs, prior_model, region_moments


def _bgr(h, s, v):
    return cv2.cvtColor(np.uint8([[[h, s, v]]]), cv2.COLOR_HSV2BGR)[0, 0]


def test_prior_is_full_inside_the_named_box_and_fades_outside():
    model = prior_model(NAMED_COLOURS["yellow"])  # H 20-34, S >= 130, V >= 90
    image = np.array([[_bgr(27, 200, 200), _bgr(36, 200, 200), _bgr(45, 200, 200),
                       _bgr(27, 110, 200), _bgr(27, 60, 200), _bgr(27, 200, 40)]])
    p = model.back_project(image)[0]
    assert p[0] > 0.95                 # inside
    assert 0.2 < p[1] < 0.9            # 2 hue units outside: partly
    assert p[2] == 0.0                 # far hue
    assert 0.2 < p[3] < 0.9            # a little less saturated: partly
    assert p[4] == 0.0                 # greyish
    assert p[5] == 0.0                 # too dark


def test_prior_of_red_wraps_through_hue_zero():
    model = prior_model(NAMED_COLOURS["red"])
    image = np.array([[_bgr(176, 220, 200), _bgr(2, 220, 200), _bgr(90, 220, 200)]])
    p = model.back_project(image)[0]
    assert p[0] > 0.9 and p[1] > 0.9 and p[2] == 0.0


def test_blob_centroid_is_sub_pixel_and_regions_are_separated():
    scale = 16
    big = np.zeros((120 * scale, 160 * scale), np.uint8)
    centre = (645, 811)  # (40.3, 50.7) at the small scale, to the nearest big pixel
    cv2.circle(big, centre, 12 * scale, 255, -1)
    cv2.rectangle(big, (100 * scale, 20 * scale), (130 * scale, 40 * scale), 255, -1)
    cv2.circle(big, (150 * scale, 110 * scale), 1 * scale, 255, -1)  # too small to count
    probability = cv2.resize(big, (160, 120), interpolation=cv2.INTER_AREA) / 255.0
    probability = probability.astype(np.float32)
    blobs = find_blobs(probability, min_area=20)
    assert len(blobs) == 2
    disc = min(blobs, key=lambda b: b.centroid[0])
    # pixel centres sit at integer coordinates: big pixel c is small pixel (c + 0.5) / 16 - 0.5
    expected = (np.array(centre) + 0.5) / scale - 0.5
    assert np.linalg.norm(disc.centroid - expected) < 0.1  # the outline's polygon
    assert abs(disc.area - np.pi * 12 ** 2) < 0.03 * np.pi * 12 ** 2
    inside = blob_mask(probability.shape, [disc])
    assert inside[50, 40] and not inside[30, 110]
    # the soft moments over the grown outline find the centre to a fiftieth of a pixel
    centroid, area, mass, axis, elongation = region_moments(probability, inside, (0.0, 0.0))
    assert np.linalg.norm(centroid - expected) < 0.02
    assert abs(mass - np.pi * 12 ** 2) < 0.01 * np.pi * 12 ** 2
    assert elongation < 1.05
