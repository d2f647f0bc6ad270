"""Whole series logged in one go (the recorder's *_series methods the sim logs use) give the
same MCAP messages as one call per time stamp, and the same values in Rerun."""

import numpy as np
import pytest

from wipelab.logs import StageRecorder, read_mcap_topic, rrd_column
from wipelab.sim.kinematics import quaternions_xyzw_from_rotations, rotation_from_quaternion_xyzw

T = np.array([0.0, 0.05, 0.1, 0.15])
RNG = np.random.default_rng(5)
TRANSLATIONS = RNG.normal(size=(4, 3))
QUATERNIONS = RNG.normal(size=(4, 4))
VECTORS = RNG.normal(size=(4, 3))


def _record(directory, batched: bool):
    with StageRecorder(directory, "replay") as rec:
        frames = [("world", "a", TRANSLATIONS, QUATERNIONS), ("a", "b", -TRANSLATIONS, QUATERNIONS)]
        if batched:
            rec.transform_series(T, frames)
            rec.pose_series("/replay/tcp", T, "world", TRANSLATIONS, QUATERNIONS)
            rec.arrow_series("/replay/force_arrow", T, TRANSLATIONS, VECTORS)
        else:
            for k, t in enumerate(T):
                rec.transforms(t, [(p, c, x[k], q[k]) for p, c, x, q in frames])
            for k, t in enumerate(T):
                rec.pose("/replay/tcp", t, "world", TRANSLATIONS[k], QUATERNIONS[k])
            for k, t in enumerate(T):
                rec.arrow3d("/replay/force_arrow", t, TRANSLATIONS[k], VECTORS[k])
    return rec


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    return (_record(tmp_path_factory.mktemp("batched"), True),
            _record(tmp_path_factory.mktemp("per_time"), False))


@pytest.mark.parametrize("topic", ["/tf", "/replay/tcp", "/replay/force_arrow"])
def test_series_write_the_same_mcap_messages(recordings, topic):
    batched, per_time = (read_mcap_topic(r.mcap_path, topic) for r in recordings)
    assert len(batched) == len(T) and batched == per_time


def test_series_reach_rerun_with_their_times(recordings):
    batched = recordings[0].rrd_path
    t, translations = rrd_column(batched, "/tf/b", "Transform3D:translation")
    assert t == pytest.approx(T)
    assert np.array(translations).reshape(-1, 3) == pytest.approx(-TRANSLATIONS, rel=1e-5)
    t, vectors = rrd_column(batched, "/replay/force_arrow", "Arrows3D:vectors")
    assert t == pytest.approx(T)
    assert np.array(vectors).reshape(-1, 3) == pytest.approx(VECTORS, rel=1e-5)


def test_quaternion_conversion_round_trips():
    q = RNG.normal(size=(200, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 3] < 0] *= -1
    q[:3] = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]          # half turns: w = 0
    rotations = np.array([rotation_from_quaternion_xyzw(x) for x in q])
    assert np.abs(quaternions_xyzw_from_rotations(rotations) - q).max() < 1e-12
