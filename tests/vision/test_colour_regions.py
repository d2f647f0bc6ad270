"""Colour prior of a named colour and blobs with sub-pixel centroids."""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.colour_model import NAMED_COLOURS
from wipelab.vision.colour_regions import (blob_mask, find_blobs, hue_range, prior_model,
                                           region_moments, spanning_hues, vivid_area,
                                           widened_hues)


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


def test_a_box_spans_the_hues_a_sponge_shows_only_where_they_reach_beyond_it():
    yellow = NAMED_COLOURS["yellow"]  # H 20-34
    assert spanning_hues(yellow, 24, 31, 2.0) == yellow            # inside: as it is
    assert spanning_hues(yellow, 29, 37, 2.0).high[0] == 39        # beyond the top, + 2
    assert spanning_hues(yellow, 29, 37, 2.0).low == yellow.low
    grown = spanning_hues(yellow, 16, 40, 2.0)
    assert grown.low[0] == 14 and grown.high[0] == 42
    red = NAMED_COLOURS["red"]  # H 172-6, through 0
    assert spanning_hues(red, 176, 182, 2.0) == red                # 182 is hue 2: inside
    wrapped = spanning_hues(red, 165, 190, 1.0)
    assert (wrapped.low[0], wrapped.high[0]) == (164, 11)
    assert widened_hues(yellow, 6).low[0] == 14 and widened_hues(yellow, 6).high[0] == 40
    assert widened_hues(red, 6).low[0] == 166 and widened_hues(red, 6).high[0] == 12
    assert widened_hues(yellow, 100).low[0] == 0 and widened_hues(yellow, 100).high[0] == 179
    above, below = widened_hues(yellow, 6, +1), widened_hues(yellow, 6, -1)
    assert (above.low[0], above.high[0]) == (20, 40) and (below.low[0], below.high[0]) == (14, 34)


def test_the_hue_range_of_a_region_is_measured_on_the_hue_circle():
    hues = np.array([[176, 178, 179, 0, 1, 3, 5, 90]], np.uint8)  # the last one is masked out
    image = cv2.cvtColor(np.dstack([hues, np.full_like(hues, 200), np.full_like(hues, 200)]),
                         cv2.COLOR_HSV2BGR)
    mask = np.array([[255] * 7 + [0]], np.uint8)
    low, high = hue_range([image], [mask], near=179.0, share=0.0)
    assert abs(low - 176) <= 1 and abs(high - 185) <= 1            # 176 .. 5 (= 185)
    assert hue_range([image], [np.zeros_like(mask)], near=0.0) is None
    grown = spanning_hues(NAMED_COLOURS["red"], low, high, 0.0)
    assert grown == NAMED_COLOURS["red"]  # hues 176 .. 5 lie inside red (172 .. 6)


def test_a_sponge_between_two_named_colours_reads_as_one_once_the_box_spans_it():
    """A lemon-yellow sponge (hue 37, between yellow 20-34 and green 38-85): the prior of
    yellow hardly reads it; yellow spanned to the hues it shows reads it whole."""
    yellow = NAMED_COLOURS["yellow"]
    lemon = np.array([[_bgr(h, 220, 210) for h in (36, 37, 38, 39)]])
    assert prior_model(yellow).back_project(lemon).max() < 0.5
    assert prior_model(spanning_hues(yellow, 36, 39, 2.0)).back_project(lemon).min() > 0.95


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
    inside = blob_mask(probability, [disc])
    assert inside[50, 40] and not inside[30, 110]
    # the soft moments over the grown outline find the centre to a fiftieth of a pixel
    centroid, area, mass, axis, elongation = region_moments(probability, inside, (0.0, 0.0))
    assert np.linalg.norm(centroid - expected) < 0.02
    assert abs(mass - np.pi * 12 ** 2) < 0.01 * np.pi * 12 ** 2
    assert elongation < 1.05


def test_the_vivid_area_of_a_blob_that_took_in_a_dull_table_of_its_hue_is_the_sponges():
    # an orange sponge (H 13, S 230, V 215) lying against a strip of orange wood (H 14,
    # S 150, V 150) that the named colour also takes in: one blob of both
    rng = np.random.default_rng(4)
    image = np.zeros((60, 90, 3), np.uint8)
    image[20:40, 10:40] = _bgr(13, 230, 215)
    image[24:36, 40:80] = _bgr(14, 150, 150)
    image = np.clip(image + rng.normal(0, 3, image.shape), 0, 255).astype(np.uint8)
    probability = np.zeros((60, 90), np.float32)
    probability[20:40, 10:40] = probability[24:36, 40:80] = 1.0
    (both,) = find_blobs(probability, min_area=20)
    assert both.area > 1000
    assert vivid_area(image, probability, both) == 600
    # a blob of one colour group: all of its pixels
    alone = probability.copy()
    alone[24:36, 40:80] = 0.0
    (body,) = find_blobs(alone, min_area=20)
    assert vivid_area(image, alone, body) == 600
