"""The still-thing background: a cloth of the sponge's colour that the sponge and the arm
keep passing over stays known as a still thing; a resting sponge becomes a ghost that is
forgotten once it lies under the tracked region. Drawn frames, no video."""

import cv2
import numpy as np

from wipelab.vision.colour_model import NAMED_COLOURS
from wipelab.vision.colour_regions import find_blobs, prior_model
from wipelab.vision.static_background import StaticBackground
from wipelab.vision.undistortion import Undistorter

SIZE = (160, 120)
GHOST = 2 * 16 ** 2  # canvas pixels: twice the drawn sponge's area
TABLE, CLOTH, SPONGE, ARM = (150, 160, 170), (200, 190, 60), (150, 140, 30), (120, 150, 200)


def _background() -> StaticBackground:
    K = np.array([[150.0, 0, 80], [0, 150.0, 60], [0, 0, 1]])
    return StaticBackground(Undistorter(K, np.zeros(5), SIZE), scale=1.0)


def _frame(t: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """A table with a cyan cloth (x 40-120, y 40-100) that a darker cyan sponge (16 px)
    wipes across while an arm (skin) reaches over it from the top: frame and the sponge's
    mask."""
    frame = np.empty((SIZE[1], SIZE[0], 3), np.uint8)
    frame[:] = TABLE
    frame[40:100, 40:120] = CLOTH
    x = int(80 + 45 * np.sin(2 * np.pi * t / 30))
    cv2.rectangle(frame, (x - 10, 0), (x + 10, 50), ARM, -1)   # the arm over the cloth
    sponge = np.zeros(frame.shape[:2], bool)
    sponge[48:64, x - 8:x + 8] = True
    frame[sponge] = SPONGE
    noise = rng.normal(0, 3, frame.shape)
    return np.clip(frame + noise, 0, 255).astype(np.uint8), sponge


def _canvas(background: StaticBackground, mask: np.ndarray) -> np.ndarray:
    """A frame's mask in the background's canvas pixels."""
    return background.canvas_image(np.repeat(mask[..., None], 3, 2).astype(np.uint8)
                                   * 255)[..., 0] > 127


def _region_of(background: StaticBackground, mask: np.ndarray):
    return [(_canvas(background, mask), np.zeros(2), 1)]


def _tracked_region(background: StaticBackground, frame: np.ndarray, sponge: np.ndarray,
                    model) -> np.ndarray:
    """What the tracker keeps out of the background: the sponge's colour region, without
    what the background knows as still, connected to the sponge (a cloth not yet known
    merges with it)."""
    image = background.canvas_image(frame)
    colour = model.back_project(image) > 0.5
    still = background.still_in_canvas_image(image)
    if still is not None:
        colour &= ~still
    _, labels = cv2.connectedComponents(colour.astype(np.uint8))
    ids = np.unique(labels[_canvas(background, sponge) & colour])
    return np.isin(labels, ids[ids > 0])


def test_a_cloth_passed_over_stays_a_still_thing_and_the_sponge_on_it_is_not_one():
    rng = np.random.default_rng(0)
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    frames = [_frame(t, rng) for t in range(0, 60, 2)]
    images = np.stack([background.canvas_image(f) for f, _ in frames])
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    for t in range(60, 400, 3):
        frame, sponge = _frame(t, rng)
        region = _tracked_region(background, frame, sponge, model)
        background.update(frame, (model,), [(region, np.zeros(2), 1)], GHOST)
    cloth = np.zeros(SIZE[::-1], bool)
    cloth[42:98, 42:118] = True
    cloth = _canvas(background, cloth)
    # the whole cloth, also the strip the sponge wipes and the arm keeps covering
    assert background.still[cloth].mean() > 0.97
    assert background.still[:38].sum() == 0 and background.still[:, :38].sum() == 0
    frame, sponge = _frame(400, rng)
    sponge = _canvas(background, sponge)
    still_now = background.still_in_canvas_image(background.canvas_image(frame))
    assert still_now[sponge].mean() < 0.05          # the sponge is not taken for the cloth
    assert still_now[cloth & ~sponge].mean() > 0.9  # the cloth beside it is


def _shaded(frame: np.ndarray, t: int, width: int = 14, dim: float = 0.55) -> np.ndarray:
    """``frame`` (of :func:`_frame` at ``t``) with the arm's shadow: a band ``width`` pixels
    wide beside the arm, from the table's edge down to the cloth's lower half, darker by
    ``dim``."""
    x = int(80 + 45 * np.sin(2 * np.pi * t / 30))
    shaded = frame.copy()
    band = shaded[0:80, x + 10:x + 10 + width].astype(np.float64) * dim
    shaded[0:80, x + 10:x + 10 + width] = band.astype(np.uint8)
    return shaded


def test_the_arms_shadow_on_a_cloth_leaves_the_cloth_a_still_thing_but_not_the_sponge():
    """The arm shades the cloth beside it as it wipes: the shaded part of the cloth, which
    moves with the arm, is still the cloth (the same hue and saturation, darker), while the
    sponge on the cloth (the cloth's hue, more saturated) is not."""
    rng = np.random.default_rng(4)
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    frames = [(_shaded(f, t), m) for t, (f, m) in
              ((t, _frame(t, rng)) for t in range(0, 60, 2))]
    images = np.stack([background.canvas_image(f) for f, _ in frames])
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    for t in range(60, 400, 3):
        frame, sponge = _frame(t, rng)
        frame = _shaded(frame, t)
        region = _tracked_region(background, frame, sponge, model)
        background.update(frame, (model,), [(region, np.zeros(2), 1)], GHOST)
    t = 407  # the arm right of the middle, its shadow on the cloth
    frame, sponge = _frame(t, rng)
    frame = _shaded(frame, t)
    x = int(80 + 45 * np.sin(2 * np.pi * t / 30))
    shadow = np.zeros(SIZE[::-1], bool)
    shadow[42:80, x + 11:x + 23] = True
    shadow &= ~sponge
    still_now = background.still_in_canvas_image(background.canvas_image(frame))
    assert still_now[_canvas(background, shadow)].mean() > 0.9  # the shaded cloth
    assert still_now[_canvas(background, sponge)].mean() < 0.05  # the sponge on it


def test_a_still_thing_of_the_sponges_size_in_a_shadow_is_not_taken_for_itself():
    """A still thing no larger than the sponge may be the sponge's own ghost (a sponge that
    rested there): a darker thing of its colour there is the sponge's shaded side, not it."""
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    frame = np.full((SIZE[1], SIZE[0], 3), TABLE, np.uint8)
    frame[50:66, 70:86] = CLOTH                     # a small still thing of the colour
    images = np.stack([background.canvas_image(frame)] * 5)
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    background.update(frame, (model,), [], GHOST)
    darker = frame.copy()
    darker[50:66, 70:86] = (np.array(CLOTH) * 0.55).astype(np.uint8)
    thing = _canvas(background, np.pad(np.ones((16, 16), bool), ((50, 54), (70, 74))))
    assert background.still[thing].mean() > 0.9
    assert background.still_in_canvas_image(background.canvas_image(darker))[thing].mean() \
        < 0.05


def test_a_resting_sponge_becomes_a_ghost_and_is_forgotten_under_the_region():
    rng = np.random.default_rng(1)
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    frame = np.full((SIZE[1], SIZE[0], 3), TABLE, np.uint8)
    sponge = np.zeros(frame.shape[:2], bool)
    sponge[50:66, 70:86] = True
    frame[sponge] = SPONGE
    keep_out = _region_of(background, sponge)
    sponge = _canvas(background, sponge)
    images = np.stack([background.canvas_image(frame)] * 5)
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    assert background.still[sponge].mean() > 0.9     # resting: it looks like a still thing
    background.update(frame, (model,), keep_out, GHOST)
    assert background.still.sum() == 0               # under the region: a ghost, forgotten
    assert background.ghosts[sponge].all()
    # once it is gone, the table shows through and the ghost ends
    table = np.full_like(frame, TABLE)
    for _ in range(40):
        background.update(table, (model,), [], GHOST)
    assert not background.ghosts.any() and background.still.sum() == 0


def test_where_the_sponge_has_been_a_still_thing_of_its_size_is_a_ghost_a_cloth_is_not():
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    frame = np.full((SIZE[1], SIZE[0], 3), TABLE, np.uint8)
    frame[50:66, 20:36] = SPONGE            # where the sponge rested before it wiped
    frame[30:110, 80:150] = CLOTH           # a cloth it wiped across
    images = np.stack([background.canvas_image(frame)] * 5)
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    rest = _canvas(background, np.pad(np.ones((16, 16), bool), ((50, 54), (20, 124))))
    cloth = _canvas(background, np.pad(np.ones((80, 70), bool), ((30, 10), (80, 10))))
    assert background.still[rest].mean() > 0.9 and background.still[cloth].mean() > 0.9
    path = np.array([[28.0, 58.0], [60.0, 60.0], [100.0, 70.0], [120.0, 60.0]]) + 1  # canvas
    background.release_visited(path, GHOST)
    assert background.still[rest].sum() == 0              # the sponge's own ghost
    assert background.still[cloth].mean() > 0.9          # too large to be the sponge


def _gingham(shift: float, rng, sponge_at: tuple[int, int] | None = None) -> np.ndarray:
    """A pink and white gingham tablecloth (12 px squares), shifted by ``shift`` pixels, JPEG
    compressed, with an optional vivid magenta sponge (24 x 16 px) at ``sponge_at``."""
    y, x = np.mgrid[0:SIZE[1], 0:SIZE[0]].astype(np.float64)
    stripes = (((x + shift) // 12) % 2) + (((y + 0.5 * shift) // 12) % 2)  # 0, 1 or 2 pink
    white, pink = np.array([238, 238, 239.0]), np.array([115, 66, 153.0])
    frame = white + (pink - white) * (stripes[..., None] / 2.0)
    if sponge_at is not None:
        u, v = sponge_at
        frame[v:v + 16, u:u + 24] = (150, 59, 196)
    frame = np.clip(cv2.GaussianBlur(frame, (0, 0), 0.7) + rng.normal(0, 2, frame.shape), 0,
                    255).astype(np.uint8)
    return cv2.imdecode(cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, 60])[1],
                        cv2.IMREAD_COLOR)


def test_a_tablecloth_checkered_in_the_sponges_colour_leaves_only_the_sponge_to_find():
    """A low-resolution background places the edges of a checkered still thing a pixel off
    (compression, noise, sub-pixel shifts): without what the background explains, the blob
    finder sees the vivid sponge on the tablecloth and nothing else, in the search's
    low-resolution image and in a full-resolution measurement window alike."""
    rng = np.random.default_rng(3)
    K = np.array([[150.0, 0, 80], [0, 150.0, 60], [0, 0, 1]])
    background = StaticBackground(Undistorter(K, np.zeros(5), SIZE), scale=0.5)
    model = prior_model(NAMED_COLOURS["pink"])
    images = np.stack([background.canvas_image(_gingham(rng.uniform(-0.4, 0.4), rng))
                       for _ in range(12)])
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    frame = _gingham(0.6, rng, sponge_at=(60, 50))
    sponge_centre = np.array([71.5, 57.5])  # canvas pixels
    image = background.canvas_image(frame)
    for name, image, still, scale in (
            ("search", image, background.still_in_canvas_image(image), background.scale),
            ("window", frame, background.still_colour(frame, np.zeros(2), 1), 1.0)):
        probability = model.back_project(image)
        assert probability[still].size > 0.3 * probability.size, name  # the cloth is still
        probability[still] = 0.0
        blobs = find_blobs(probability, min_area=6)
        assert len(blobs) == 1, (name, [b.centroid for b in blobs])
        centre = (blobs[0].centroid + 0.5) / scale - 0.5
        assert np.linalg.norm(centre - sponge_centre) < 1.5, name
        assert blobs[0].area / scale ** 2 > 0.8 * 24 * 16, name  # none of it taken for still


def test_a_pixel_shows_its_background_at_its_place_or_a_pixel_away_and_only_near_a_still_thing():
    K = np.array([[10.0, 0, 4], [0, 10.0, 4], [0, 0, 1]])
    background = StaticBackground(Undistorter(K, np.zeros(5), (9, 9)), scale=1.0)
    height, width = background.image.shape[:2]  # the canvas: the frame and a margin
    scene = np.zeros((height, width, 3), np.uint8)
    scene[6, 5] = (200, 100, 50)
    scene[2, 5] = (60, 160, 90)              # outside the still thing and its margin
    of_its_colour = np.zeros((height, width), bool)
    of_its_colour[4:, :] = True              # a still thing from row 4 down
    background.initialise(scene[None], of_its_colour[None])
    image = np.full((height, width, 3), 150, np.uint8)  # far from every colour above
    image[6, 4] = (210, 110, 40)             # within 23 grey levels of scene[6, 5]
    image[6, 2] = (200, 100, 50)             # three pixels from it: too far
    image[3, 5] = (60, 160, 90)              # next to the still thing, shows [2, 5]
    image[1, 1] = (0, 0, 0)                  # the background's, but no still thing near
    found = background.still_in_canvas_image(image)
    assert found[6, 4] and found[3, 5]
    assert not found[6, 2] and not found[1, 1]
    assert found.sum() == 2


def test_a_background_started_again_shows_its_new_frames():
    """Started twice, the background's median is the second start's (it was once left
    cached from the first)."""
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    for colour in (TABLE, CLOTH):
        frame = np.full((SIZE[1], SIZE[0], 3), colour, np.uint8)
        images = np.stack([background.canvas_image(frame)] * 3)
        background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
        inside = background.in_frame
        assert np.abs(background.mean[inside].astype(int) - colour).max() <= 1


def test_until_the_sponge_is_tracked_a_still_thing_must_look_as_the_scene_first_did():
    """A sponge that wipes slowly sits where it is in most of the last seconds' frames: the
    median of a later start shows it, but the scene did not when the background was first
    learnt, so the search still sees it. Once tracked, the running median is the
    reference."""
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    table = np.full((SIZE[1], SIZE[0], 3), TABLE, np.uint8)
    resting = table.copy()
    resting[50:66, 70:86] = SPONGE
    sponge = _canvas(background, np.pad(np.ones((16, 16), bool), ((50, 54), (70, 74))))
    for frame in (table, resting):   # the first start, then a later one
        images = np.stack([background.canvas_image(frame)] * 5)
        background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    assert background.still[sponge].mean() > 0.9      # of the colour in the later median
    still_now = background.still_in_canvas_image(background.canvas_image(resting))
    assert still_now[sponge].mean() < 0.05           # but not how the scene first looked
    background.update(resting, (model,), [], GHOST)
    still_now = background.still_in_canvas_image(background.canvas_image(resting))
    assert still_now[sponge].mean() > 0.9            # tracked: the running median


def test_the_still_scene_near_a_point_is_the_median_without_the_sponge_that_passed():
    """:meth:`median_near` gives the still scene in a square round a point: the cloth there,
    not the sponge that wiped over it; at the canvas's edge only the pixels inside it."""
    rng = np.random.default_rng(3)
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    images = np.stack([background.canvas_image(_frame(t, rng)[0]) for t in range(30)])
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    on_the_cloth = background.median_near(np.array([80.0, 70.0]), 20.0)
    assert on_the_cloth.shape == (40 * 40, 1, 3)
    assert np.abs(on_the_cloth.astype(int) - CLOTH).max() <= 6
    corner = background.in_frame[:10, :10]   # the canvas's rim sees no frame pixel
    assert 0 < np.count_nonzero(corner) < corner.size
    assert len(background.median_near(np.array([0.0, 0.0]), 10.0)) == np.count_nonzero(corner)


def test_a_sponge_of_nearly_the_cloths_shade_on_it_is_not_taken_for_the_cloth():
    """A sponge within the still-thing test's grey levels of the cloth it wipes on: once the
    background has seen the sponge (in its region), its pixels are more like it than like
    the cloth, and stay the sponge's."""
    rng = np.random.default_rng(3)
    background = _background()
    model = prior_model(NAMED_COLOURS["cyan"])
    near_shade = (184, 174, 46)  # 16 grey levels from the cloth at most: under the threshold

    def frame_at(t):
        frame = np.full((SIZE[1], SIZE[0], 3), TABLE, np.uint8)
        frame[30:110, 30:150] = CLOTH
        x = int(90 + 40 * np.sin(2 * np.pi * t / 40))
        sponge = np.zeros(frame.shape[:2], bool)
        sponge[60:76, x - 8:x + 8] = True
        frame[sponge] = near_shade
        return np.clip(frame + rng.normal(0, 3, frame.shape), 0, 255).astype(np.uint8), sponge

    images = np.stack([background.canvas_image(frame_at(t)[0]) for t in range(0, 40, 2)])
    background.initialise(images, np.stack([model.back_project(i) > 0.5 for i in images]))
    frame, sponge = frame_at(41)
    before = background.still_in_canvas_image(background.canvas_image(frame))
    assert before[_canvas(background, sponge)].mean() > 0.9  # unseen: like the cloth
    for t in range(42, 80, 3):
        frame, sponge = frame_at(t)
        background.update(frame, (model,), _region_of(background, sponge), GHOST)
    assert background.sponge_bgr is not None
    assert np.abs(background.sponge_bgr.astype(int) - near_shade).max() <= 4
    frame, sponge = frame_at(81)
    sponge = _canvas(background, sponge)
    still_now = background.still_in_canvas_image(background.canvas_image(frame))
    cloth = _canvas(background, np.pad(np.ones((76, 116), bool), ((32, 12), (32, 12))))
    assert still_now[sponge].mean() < 0.1
    assert still_now[cloth & ~sponge].mean() > 0.9
