"""Inverse kinematics: reaches targets, respects joint limits, moves smoothly."""

import numpy as np
import pytest

from wipelab.sim.arm import RightArm
from wipelab.sim.armar3 import RIGHT_ARM_JOINTS, TORSO_JOINTS, armar3b_urdf_path
from wipelab.sim.kinematics import KinematicChain
from wipelab.sim.world import BasePose

CENTRE = np.array([0.58, -0.28, 0.91])


@pytest.fixture(scope="module")
def arm():
    return RightArm(BasePose().joint_values())


@pytest.fixture(scope="module")
def posture(arm):
    phases = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    points = np.concatenate([np.column_stack([CENTRE[0] + 0.1 * np.cos(phases),
                                              CENTRE[1] + 0.1 * np.sin(phases),
                                              np.full(8, CENTRE[2] + dz)])
                             for dz in (-0.04, 0.04)])
    return arm.posture_for(CENTRE, points)


def test_jacobian_matches_finite_differences():
    chain = KinematicChain(armar3b_urdf_path().read_text(), "tcp_r",
                           TORSO_JOINTS + RIGHT_ARM_JOINTS)
    q = np.random.default_rng(2).uniform(chain.lower, chain.upper)
    pose, jac = chain.jacobian(q)
    numeric = np.empty((3, q.size))
    for i in range(q.size):
        dq = np.zeros(q.size)
        dq[i] = 1e-7
        numeric[:, i] = (chain.forward(q + dq)[:3, 3] - pose[:3, 3]) / 1e-7
    assert np.abs(numeric - jac[:3]).max() < 1e-5


def test_posture_leans_the_torso_only_as_needed_and_keeps_margin(posture):
    assert posture.error < 2e-3
    assert posture.margin >= np.radians(5.0)
    assert -np.radians(40.0) <= posture.torso[0] <= 0.0


def test_ik_reaches_targets_within_joint_limits(arm, posture):
    tracker = arm.tracker(posture)
    rng = np.random.default_rng(4)
    targets = CENTRE + rng.uniform([-0.1, -0.1, -0.04], [0.1, 0.1, 0.04], size=(12, 3))
    for target in targets:
        q, error = tracker.solve(posture.arm, target, max_iterations=300)
        assert error < 1e-3
        limits = tracker.chain
        assert np.all(q >= limits.lower) and np.all(q <= limits.upper)
        assert np.linalg.norm(tracker.chain.forward(q)[:3, 3] - target) < 1e-3


def test_tracking_steps_are_rate_limited_and_follow_a_circle(arm, posture):
    tracker = arm.tracker(posture)
    q = posture.arm.copy()
    errors = []
    for phase in np.linspace(0, 4 * np.pi, 960):      # 0.25 Hz at 120 Hz, two periods
        target = CENTRE + [0.1 * np.cos(phase), 0.1 * np.sin(phase), 0.0]
        new, _ = tracker.track(q, target, np.zeros(3))
        assert np.max(np.abs(new - q)) <= tracker.params.max_step + 1e-12
        q = new
        errors.append(np.linalg.norm(tracker.chain.forward(q)[:3, 3] - target))
    assert max(errors[480:]) < 1e-3


def test_an_unreachable_target_is_reported_not_faked(arm, posture):
    tracker = arm.tracker(posture)
    _, error = tracker.solve(posture.arm, CENTRE + [0.6, 0.0, 0.0], max_iterations=300)
    assert error > 0.1


def test_joint_velocity_gives_the_tcp_velocity(arm, posture):
    tracker = arm.tracker(posture)
    velocity = np.array([0.12, -0.05, 0.03])
    target = tracker.chain.forward(posture.arm)[:3, 3] + [0.01, 0.0, -0.005]
    q, qdot = tracker.track(posture.arm, target, velocity)
    assert np.abs(q - posture.arm).max() > 1e-4          # velocities at the new targets
    _, jac = tracker.chain.jacobian(q)
    assert jac[:3] @ qdot == pytest.approx(velocity, abs=1e-3)


def test_orientation_weight_turns_the_hand_to_a_target(posture):
    from wipelab.sim.ik import IKParams
    from wipelab.rotations import rotation_about_axis
    from wipelab.sim.kinematics import rotation_error

    arm = RightArm(BasePose().joint_values(), IKParams(orientation_weight=0.3))
    tracker = arm.tracker(posture)
    start = tracker.chain.forward(posture.arm)
    goal = rotation_about_axis(np.array([0.0, 0.0, 1.0]), 0.3) @ start[:3, :3]
    q, error = tracker.solve(posture.arm, start[:3, 3], goal, max_iterations=300)
    reached = tracker.chain.forward(q)
    assert error < 1e-3
    assert np.linalg.norm(rotation_error(reached[:3, :3], goal)) < 0.02
    assert np.linalg.norm(rotation_error(tracker.chain.forward(
        arm.tracker(posture).solve(posture.arm, start[:3, 3])[0])[:3, :3], goal)) > 0.1


@pytest.mark.parametrize("m", [3, 6])
def test_weighted_solution_kernel_matches_numpy(m):
    """The compiled damped least squares (Cholesky in loops) against the formula in numpy."""
    from wipelab.sim.ik import _weighted_solution

    rng = np.random.default_rng(m)
    rows, inv_cost, rhs = rng.normal(size=(m, 7)), rng.uniform(0.1, 1.0, 7), rng.normal(size=m)
    weighted = rows * inv_cost
    expected = weighted.T @ np.linalg.solve(weighted @ rows.T + 1e-4 * np.eye(m), rhs)
    assert _weighted_solution(rows, weighted, rhs, 1e-4) == pytest.approx(expected, rel=1e-9)
