"""The still-thing background: a cloth of the sponge's colour that the sponge and the arm
keep passing over stays known as a still thing; a resting sponge becomes a ghost that is
forgotten once it lies under the tracked region. Drawn frames, no video."""

import cv2
import numpy as np

from wipelab.vision.colour_model import NAMED_COLOURS
from wipelab.vision.colour_regions import prior_model
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
