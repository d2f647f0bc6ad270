"""Whole series logged in one go (the recorder's *_series methods the sim logs use) give the
same MCAP messages as one call per time stamp, and the same values in Rerun."""

import numpy as np
import pytest

from wipelab.logs import StageRecorder, read_mcap_topic, rrd_column
from wipelab.rotations import quaternions_xyzw_from_rotations, rotation_from_quaternion_xyzw

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


def test_mean_over_phase_bins_each_sample_to_the_nearest_phase():
    from wipelab.sim.recording import mean_over_phase

    phase = np.array([0.01, 2 * np.pi - 0.01, 4 * np.pi + np.pi / 2, np.pi / 2 + 0.1])
    mean = mean_over_phase(phase, np.array([1.0, 3.0, 5.0, 7.0]), 4)
    np.testing.assert_allclose(mean, [2.0, 6.0, np.nan, np.nan])


def test_force_over_phase_is_the_mean_per_phase_over_the_window():
    from wipelab.sim.recording import force_over_phase

    t = np.arange(0.0, 10.0, 0.001)
    phase = 2 * np.pi * 0.5 * t                           # five periods
    norm = 10.0 + 2.0 * np.cos(phase) + 5.0 * (t < 2.0)  # the first second is not scored
    trace = {"t": t, "phase": phase, "force": np.column_stack([np.zeros_like(t), np.zeros_like(t),
                                                              norm])}
    bins, mean = force_over_phase(trace, 2.0, 10.0, bins=32)
    assert bins[0] == 0.0 and bins[-1] == pytest.approx(2 * np.pi)
    np.testing.assert_allclose(mean, 10.0 + 2.0 * np.cos(bins), atol=0.02)


def test_contact_point_is_the_sponges_lowest_point():
    from types import SimpleNamespace

    from wipelab.sim.recording import contact_heights
    from wipelab.sim.sponge import SpongeParams
    from wipelab.sim.surfaces import load_surface

    surface = load_surface("flat")
    task = SimpleNamespace(options=SimpleNamespace(sponge=SpongeParams()), surface=surface)
    length, _, thickness = SpongeParams().size
    centre = np.array([[*surface.wipe_center, 0.9], [*surface.wipe_center, 0.9]])
    tilt = 0.2                                            # about y: one short edge lower
    quaternions = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, np.sin(tilt / 2), 0.0, np.cos(tilt / 2)]])
    heights = contact_heights(task, centre, quaternions)
    assert heights[0, 0] == pytest.approx(0.9 - thickness / 2)
    lowest = 0.9 - (length / 2 * np.sin(tilt) + thickness / 2 * np.cos(tilt))
    assert heights[1, 0] == pytest.approx(lowest, abs=2e-3)  # on the sampled bottom grid
    np.testing.assert_allclose(heights[:, 1], surface.height_at(centre[:, :2]), atol=1e-12)  # flat
