import numpy as np
import pytest

from wipelab.vision.particle_filter import (align_yaw, effective_sample_size,
                                            normalised_weights, systematic_resample,
                                            weighted_pose_mean, wrap_half_turn)


def test_systematic_resampling_keeps_particles_in_proportion_to_weight():
    weights = np.array([0.5, 0.25, 0.125, 0.125, 0.0])
    counts = np.bincount(systematic_resample(weights, np.random.default_rng(0)), minlength=5)
    assert counts.tolist() == [2, 1, 1, 1, 0] or counts.sum() == 5
    big = np.bincount(systematic_resample(np.repeat(weights, 200) / 200,
                                          np.random.default_rng(1)), minlength=1000)
    per_group = big.reshape(5, 200).sum(axis=1)
    np.testing.assert_allclose(per_group / 1000, weights, atol=0.002)


def test_weights_and_effective_sample_size():
    w = normalised_weights(np.array([0.0, 0.0, np.log(2.0)]))
    np.testing.assert_allclose(w, [0.25, 0.25, 0.5])
    assert effective_sample_size(np.full(8, 1 / 8)) == pytest.approx(8)
    assert effective_sample_size(np.array([1.0, 0, 0])) == pytest.approx(1)


def test_mean_yaw_of_a_box_is_taken_modulo_pi():
    poses = np.array([[0, 0, 0, np.pi / 2 - 0.05], [0.02, 0, 0, -np.pi / 2 + 0.05]])
    mean = weighted_pose_mean(poses, np.array([0.5, 0.5]))
    np.testing.assert_allclose(mean[:3], [0.01, 0, 0])
    assert abs(wrap_half_turn(mean[3] - np.pi / 2)) < 1e-9  # not 0, the naive mean


def test_align_yaw_picks_the_equivalent_angle_nearest_the_reference():
    aligned = align_yaw(np.array([[0, 0, 0, -1.5], [0, 0, 0, 1.4]]), 1.5)
    np.testing.assert_allclose(aligned[:, 3], [-1.5 + np.pi, 1.4])
