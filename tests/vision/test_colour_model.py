import cv2
import numpy as np
import pytest

from wipelab.vision.colour_model import (NAMED_COLOURS, ColourModel, ColourSource, HsvRange,
                                         LinearColourFeature, largest_blob, parse_hsv_range,
                                         vivid_part)
from wipelab.vision.colour_regions import prior_model

SPONGE, WOOD, SKIN = (40, 205, 240), (150, 188, 214), (122, 152, 208)


def _scene(rng):
    """A textured wooden frame with a yellow sponge (rows 40-80, cols 60-120) and a skin patch."""
    image = np.clip(np.array(WOOD, float) + rng.normal(0, 6, (120, 200, 3)), 0, 255)
    image[40:80, 60:120] = SPONGE
    image[10:30, 130:180] = SKIN
    mask = np.zeros((120, 200), np.uint8)
    mask[40:80, 60:120] = 255
    return image.astype(np.uint8), mask


def test_red_range_wraps_through_hue_zero():
    hsv = np.array([[[175, 200, 200], [3, 200, 200], [90, 200, 200]]], np.uint8)
    assert NAMED_COLOURS["red"].mask(hsv).ravel().tolist() == [255, 255, 0]


def test_named_yellow_finds_the_sponge_not_wood_or_skin():
    image, mask = _scene(np.random.default_rng(0))
    found = largest_blob(NAMED_COLOURS["yellow"].mask(cv2.cvtColor(image, cv2.COLOR_BGR2HSV)), 50)
    assert found is not None
    assert np.array_equal(found > 0, mask > 0)


def test_histogram_model_separates_sponge_from_background():
    rng = np.random.default_rng(1)
    image, mask = _scene(rng)
    model = ColourModel.fit([image], [mask])
    other, _ = _scene(rng)  # a new frame of the same scene
    probability = model.back_project(other)
    assert probability[45:75, 65:115].mean() > 0.95
    assert probability[mask == 0].mean() < 0.02


def test_likely_is_the_probability_above_one_half_for_every_model_and_colour():
    """``likely`` (bytes, one HSV conversion for several models) marks exactly the pixels
    where ``back_project`` exceeds 0.5, on every colour an image can hold."""
    rng = np.random.default_rng(3)
    image, mask = _scene(rng)
    every_colour = rng.integers(0, 256, (256, 256, 3), dtype=np.uint8)
    models = [ColourModel.fit([image], [mask]), prior_model(NAMED_COLOURS["yellow"]),
              prior_model(NAMED_COLOURS["red"])]
    for model in models:
        for frame in (image, every_colour):
            likely = model.likely(cv2.cvtColor(frame, cv2.COLOR_BGR2HSV))
            assert np.array_equal(likely, model.back_project(frame) > 0.5)
    assert models[0].likely(cv2.cvtColor(image, cv2.COLOR_BGR2HSV))[45:75, 65:115].all()


def test_linear_feature_is_linear_in_the_mixing_of_sponge_and_background():
    image, mask = _scene(np.random.default_rng(2))
    feature = LinearColourFeature.fit([image], [mask])
    sponge = feature.apply(np.array([[SPONGE]], np.uint8))[0, 0]
    wood = feature.apply(np.array([[WOOD]], np.uint8))[0, 0]
    assert sponge == pytest.approx(1.0, abs=0.1) and wood == pytest.approx(0.0, abs=0.1)
    for alpha in (0.25, 0.5, 0.75):
        mixed = np.round(alpha * np.array(SPONGE) + (1 - alpha) * np.array(WOOD))
        value = feature.apply(mixed.reshape(1, 1, 3).astype(np.uint8))[0, 0]
        assert value == pytest.approx(wood + alpha * (sponge - wood), abs=0.01)


def test_parse_hsv_range_and_its_errors():
    assert parse_hsv_range("20,100,80,35,255,255") == HsvRange((20, 100, 80), (35, 255, 255))
    with pytest.raises(ValueError, match="six integers"):
        parse_hsv_range("20,100,80")
    with pytest.raises(ValueError, match="0-179"):
        parse_hsv_range("200,100,80,35,255,255")


def test_colour_source_needs_exactly_one_description():
    with pytest.raises(ValueError, match="exactly one"):
        ColourSource(name="yellow", roi=(0, 0, 5, 5))
    with pytest.raises(ValueError, match="unknown colour 'mauve'"):
        ColourSource(name="mauve")
    assert ColourSource(roi=(1, 2, 3, 4)).option == "--roi 1,2,3,4"


def _orange_sponge_and_arm(rng, arm_bgr):
    """An orange sponge (rows 20-50, cols 20-70) held by an arm of ``arm_bgr`` (rows 35-60,
    cols 70-190), both inside one region mask, on a grey table."""
    image = np.clip(np.full((80, 200, 3), 120.0) + rng.normal(0, 3, (80, 200, 3)), 0, 255)
    image[20:50, 20:70] = (8, 110, 204)     # H 12, S 235, V 204
    image[35:60, 70:190] = arm_bgr
    mask = np.zeros((80, 200), np.uint8)
    mask[20:50, 20:70] = 255
    mask[35:60, 70:190] = 255
    return image.astype(np.uint8), mask


def test_vivid_part_keeps_the_sponge_body_and_drops_a_dull_arm_of_its_hue():
    # brown skin of the same hue as the sponge, but duller (H 11, S 150, V 116): the prior
    # of "orange" takes in both; the body is the vivid group
    image, mask = _orange_sponge_and_arm(np.random.default_rng(1), (48, 79, 116))
    vivid = vivid_part(image, mask)
    assert vivid[20:50, 20:70].all()
    assert not vivid[35:60, 75:190].any()


def test_a_model_learnt_from_the_vivid_part_reads_the_sponge_but_not_the_arm():
    image, mask = _orange_sponge_and_arm(np.random.default_rng(3), (48, 79, 116))
    model = ColourModel.fit([image], [vivid_part(image, mask)], unsure=[mask])
    probability = model.back_project(image)
    assert probability[22:48, 22:68].mean() > 0.9
    assert probability[37:58, 75:190].mean() < 0.05


def test_vivid_part_leaves_a_region_of_one_colour_whole():
    image, mask = _orange_sponge_and_arm(np.random.default_rng(2), (8, 110, 204))
    assert np.array_equal(vivid_part(image, mask), mask)


def test_a_learnt_model_bounded_by_the_named_colour_leaves_out_a_neighbouring_hue_it_never_saw():
    """A purple sponge (hue 140) learnt on a grey table; a tablecloth of hue 152, just outside
    purple's box, was not in the window: the histogram's smoothed tail reads it as sponge,
    the model bounded by the named colour's prior does not."""
    rng = np.random.default_rng(3)
    image = np.clip(np.array((128, 128, 128), float) + rng.normal(0, 4, (120, 200, 3)), 0, 255)
    # the sponge's pixels scatter (shading, noise, compression)
    image[40:80, 60:120] = np.clip((241, 23, 168) + rng.normal(0, 10, (40, 60, 3)), 0, 255)
    mask = np.zeros((120, 200), np.uint8)
    mask[40:80, 60:120] = 255
    learnt = ColourModel.fit([image.astype(np.uint8)], [mask])
    cloth = np.full((10, 10, 3), (200, 40, 210), np.uint8)  # hue 152
    prior = prior_model(NAMED_COLOURS["purple"])
    assert learnt.back_project(cloth).mean() > 0.9
    bounded = learnt.at_most(prior)
    assert bounded.back_project(cloth).mean() < 0.5
    assert bounded.back_project(image.astype(np.uint8))[45:75, 65:115].mean() > 0.95
