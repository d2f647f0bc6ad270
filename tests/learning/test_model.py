"""model.json: exact JSON round trip, clear errors, modulation of the rollout, adding a DOF."""

import json

import numpy as np
import pytest

from wipelab.learning import MODEL_FORMAT, PeriodicModel


def _model(**changes):
    rng = np.random.default_rng(7)
    fields = dict(frequency_hz=0.8, dofs=("x", "y"), kernels=25, width=62.5, alpha_s=12.0,
                  beta_s=3.0, goal=np.array([0.55, 0.1]), amplitude=np.array([0.1, 0.06]),
                  weights=30 * rng.standard_normal((2, 25)), phase_offset=1.2,
                  source={"sha256": "ab", "parameters": {"kernels": 25}})
    fields.update(changes)
    return PeriodicModel(**fields)


def test_json_round_trip_is_exact_and_deterministic():
    model = _model()
    text = json.dumps(model.to_dict(), indent=2, sort_keys=True)
    again = PeriodicModel.from_dict(json.loads(text))
    assert json.dumps(again.to_dict(), indent=2, sort_keys=True) == text
    np.testing.assert_array_equal(again.weights, model.weights)
    assert again.dofs == ("x", "y") and again.surface is None
    data = json.loads(text)
    assert data["format"] == MODEL_FORMAT and isinstance(data["weights"][0], list)


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(format="wipelab.other/2"), r"format is 'wipelab.other/2', expected"),
    (lambda d: d.pop("weights"), r"missing key\(s\) weights"),
    (lambda d: d.update(weights=[[1.0] * 24] * 2), r"weights must have shape \(2, 25\)"),
    (lambda d: d.update(goal=[0.1]), r"goal must have shape \(2,\)"),
    (lambda d: d.update(frequency_hz=-1), r"frequency_hz must be > 0"),
    (lambda d: d.update(amplitude=[float("nan"), 1.0]), r"amplitude holds NaN or inf"),
    (lambda d: d.update(dofs=["x", "x"]), r"dofs must be distinct"),
])
def test_from_dict_names_what_is_wrong(change, message):
    data = _model().to_dict()
    change(data)
    with pytest.raises(ValueError, match=message):
        PeriodicModel.from_dict(data)
    with pytest.raises(ValueError, match="expected a JSON object"):
        PeriodicModel.from_dict([1, 2])


def test_rollout_starts_on_the_limit_cycle_and_lines_up_with_the_phase():
    model = _model()
    t, y = model.rollout(3.0, 250.0)
    assert t.size == 750 and t[1] == pytest.approx(1 / 250)
    expected = model.waveform(model.phase_offset + model.omega * t)
    assert np.abs(y - expected).max() < 1e-5 * np.ptp(expected)


def test_modulation_of_frequency_amplitude_and_goal():
    model = _model()
    t1, y1 = model.rollout(1 / 0.8, 400.0)
    t2, y2 = model.rollout(1 / 1.6, 800.0, frequency_hz=1.6)            # same samples per period
    np.testing.assert_allclose(y2, y1, atol=1e-6 * np.ptp(y1))
    goal = np.array([0.3, -0.2])
    _, y3 = model.rollout(1 / 0.8, 400.0, amplitude=1.5 * model.amplitude, goal=goal)
    np.testing.assert_allclose(y3 - goal, 1.5 * (y1 - model.goal), atol=1e-9)


def test_with_dof_adds_or_replaces():
    model = _model()
    added = model.with_dof("z", np.ones(25), goal=0.8, amplitude=1.0)
    assert added.dofs == ("x", "y", "z") and added.weights.shape == (3, 25)
    assert added.goal[2] == 0.8 and added.amplitude[2] == 1.0
    replaced = added.with_dof("x", np.zeros(25), goal=0.0, amplitude=2.0)
    assert replaced.dofs == ("x", "y", "z") and not replaced.weights[0].any()
    np.testing.assert_array_equal(replaced.weights[1], model.weights[1])
