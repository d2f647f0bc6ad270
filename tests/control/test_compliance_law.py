"""The velocity-resolved compliance law of eqs. 9-12: dead zone, cap, sign, feedback, safety."""

import numpy as np
import pytest

from wipelab.control import (ComplianceIntegrator, ComplianceParams, compliance_velocity,
                             safety_tripped)

PARAMS = ComplianceParams(force_gain=0.02, target_force=10.0, dead_zone=1.0, max_speed=0.12,
                          feedback="fz", safety_force=60.0)


def test_no_contact_moves_down_at_the_cap():
    assert compliance_velocity(np.zeros(3), PARAMS) == pytest.approx(-0.12)


def test_pressing_harder_than_f0_moves_up_proportionally():
    # eq. 11 with the shifted dead zone: k_F (F - F0 - dead zone)
    assert compliance_velocity(np.array([0.0, 0.0, 13.0]), PARAMS) == pytest.approx(0.02 * 2.0)
    assert compliance_velocity(np.array([0.0, 0.0, 7.0]), PARAMS) == pytest.approx(-0.02 * 2.0)


@pytest.mark.parametrize("fz", [9.0, 9.5, 10.0, 10.7, 11.0])
def test_dead_zone_gives_no_motion(fz):
    assert compliance_velocity(np.array([0.0, 0.0, fz]), PARAMS) == 0.0


def test_response_is_continuous_at_the_dead_zone_edge():
    just_out = compliance_velocity(np.array([0.0, 0.0, 11.001]), PARAMS)
    assert 0.0 < just_out < 1e-4


def test_velocity_never_exceeds_the_cap():
    rng = np.random.default_rng(1)
    forces = rng.normal(scale=200.0, size=(2000, 3))
    for mode in ("fz", "norm"):
        params = ComplianceParams(feedback=mode)
        speeds = np.array([compliance_velocity(f, params) for f in forces])
        assert np.max(np.abs(speeds)) <= params.max_speed + 1e-15
        assert np.isclose(np.abs(speeds).max(), params.max_speed)


def test_norm_feedback_climbs_on_a_side_push_but_fz_does_not():
    side_push = np.array([0.0, 25.0, 2.0])   # e.g. the edge of a sink
    assert compliance_velocity(side_push, ComplianceParams(feedback="norm")) > 0.1
    assert compliance_velocity(side_push, ComplianceParams(feedback="fz")) < 0.0


def test_safety_limit_on_the_force_length():
    assert safety_tripped(np.array([0.0, 45.0, 45.0]), PARAMS)      # |F| = 63.6 N
    assert not safety_tripped(np.array([0.0, 0.0, 59.9]), PARAMS)


def test_integrator_is_eq_10():
    integrator = ComplianceIntegrator(PARAMS, offset=0.5)
    for _ in range(10):
        integrator.update(np.zeros(3), 0.01)
    assert integrator.offset_ == pytest.approx(0.5 - 10 * 0.12 * 0.01)
    assert integrator.velocity_ == pytest.approx(-0.12)


def test_invalid_parameters_are_refused():
    with pytest.raises(ValueError, match="feedback must be one of fz, norm"):
        ComplianceParams(feedback="fx")
    with pytest.raises(ValueError, match="target force must be in"):
        ComplianceParams(target_force=80.0)
