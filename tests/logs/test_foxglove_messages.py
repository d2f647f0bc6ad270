"""Pure conversions from arrays to Foxglove messages and data time."""

import numpy as np
import pytest

from wipelab.logs.foxglove_messages import image_format, rgba_uint8, rotation_x_to, unit_quaternion
from wipelab.logs.timebase import seconds_array_to_ns, seconds_to_ns


def _rotate(q, v):
    u, w = q[:3], q[3]
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


@pytest.mark.parametrize("vector", [[1, 0, 0], [-1, 0, 0], [0, 0, -2], [0.3, -0.4, 1.2]])
def test_rotation_x_to_points_x_along_the_vector(vector):
    q = rotation_x_to(np.array(vector, float))
    assert np.isclose(np.linalg.norm(q), 1.0)
    direction = np.array(vector, float) / np.linalg.norm(vector)
    np.testing.assert_allclose(_rotate(q, np.array([1.0, 0, 0])), direction, atol=1e-12)


def test_unit_quaternion_normalises_and_rejects_zero():
    np.testing.assert_allclose(unit_quaternion([0, 0, 2, 0]), [0, 0, 1, 0])
    with pytest.raises(ValueError, match="non-zero"):
        unit_quaternion([0, 0, 0, 0])


def test_rgba_accepts_float_and_integer_colours():
    assert rgba_uint8((1.0, 0.5, 0.0), 2).tolist() == [[255, 128, 0, 255]] * 2
    assert rgba_uint8(np.array([[1, 2, 3, 4]], np.uint8), 1).tolist() == [[1, 2, 3, 4]]


def test_image_format_from_magic_bytes():
    assert image_format(b"\xff\xd8\xff\xe0rest") == "jpeg"
    assert image_format(b"\x89PNG\r\n\x1a\nrest") == "png"
    assert image_format(b"RIFF\x00\x00\x00\x00WEBPVP8 ") == "webp"


def test_seconds_to_ns_rounds_to_the_nearest_nanosecond():
    assert seconds_to_ns(0.1) == 100_000_000
    assert seconds_array_to_ns(np.array([0.0, 1 / 3, 2.5e-10])).tolist() == [0, 333_333_333, 0]
    with pytest.raises(ValueError, match="1-D"):
        seconds_array_to_ns(np.zeros((2, 2)))
