"""The control loop on the simulated robot: compliance finds the surface, the safety stop."""

import numpy as np
import pytest

from wipelab.control import ComplianceParams
from wipelab.sim.path import PathGenerator, place_model
from wipelab.sim.session import SafetyStop
from wipelab.sim.surfaces import flat_surface
from wipelab.sim.task import CALIBRATION_LIFT, TaskOptions, build_task

from sim_models import circle_model


def _task(compliance: ComplianceParams):
    surface = flat_surface()
    model = place_model(circle_model(), surface.wipe_center)
    task = build_task(model, surface, TaskOptions(compliance=compliance))
    start = np.array([*surface.wipe_center, task.start_height])
    task.session.move_to(start + [0.0, 0.0, CALIBRATION_LIFT], 0.5)
    task.session.calibrate()
    task.session.move_to(start, 0.5)
    return task, start


def test_compliance_moves_down_until_it_presses_with_f0():
    task, start = _task(ComplianceParams(target_force=8.0, feedback="fz"))
    try:
        first = len(task.session.trace)
        for _ in range(240):
            task.session.tick(start[:2], start[2], compliance_on=True)
        trace = {k: v[first:] for k, v in task.session.trace.arrays().items()}
        last = slice(-60, None)
        assert np.abs(trace["vz"]).max() <= 0.12 + 1e-12
        assert trace["vz"][trace["sponge_force"] < 0.5].max() < 0       # free: moving down
        assert trace["force"][last, 2].mean() == pytest.approx(8.0, abs=1.0)
        assert trace["sponge_force"][last].min() > 5.0
        assert trace["tcp_cmd"][-1, 2] < start[2] - 0.02
        # q: torso (held) then the arm, as measured at the end of each period
        assert trace["q"].shape == trace["q_cmd"].shape == (240, 10)
        assert np.all(trace["q_cmd"][:, :3] == task.session.torso)
        assert trace["q"][-1, 3:] == pytest.approx(task.session.q_arm, abs=0.01)
    finally:
        task.close()


def test_calibration_touching_the_surface_is_refused():
    surface = flat_surface()
    task = build_task(place_model(circle_model(), surface.wipe_center), surface, TaskOptions())
    try:
        task.session.move_to([*surface.wipe_center, task.start_height - 0.02], 0.5)
        with pytest.raises(RuntimeError, match="F/T calibration failed"):
            task.session.calibrate()
    finally:
        task.close()


def test_safety_stop_retracts_when_the_force_exceeds_the_limit():
    task, start = _task(ComplianceParams(target_force=8.0, safety_force=25.0))
    try:
        with pytest.raises(SafetyStop, match="exceeded the safety limit of 25 N"):
            for k in range(480):   # push 8 cm down without compliance
                task.session.tick(start[:2], start[2] - 0.08 * k / 480, compliance_on=False)
        trace = task.session.trace.arrays()
        stop = int(np.argmax(np.linalg.norm(trace["force"], axis=1) > 25.0))
        assert stop > 0
        assert trace["tcp_cmd"][-1, 2] > trace["tcp_cmd"][stop, 2] + 0.05   # retracted
        assert trace["sponge_force"][-1] < 1.0                               # free again
        assert trace["sponge_force"].max() < 60.0
    finally:
        task.close()


def test_fast_motion_in_free_air_reads_almost_no_force():
    """The inertia of the hand and sponge is compensated with the measured motion of the
    payload's centre of mass: a 10 cm circle at 1.5 Hz (0.94 m/s, 8.9 m/s^2) in free air."""
    task, start = _task(ComplianceParams())
    try:
        session = task.session
        path = PathGenerator(task.model, ("x", "y"))
        omega = 2 * np.pi * 1.5
        task.world.set_tool_speed(path.max_speed(omega))
        air = start[2] + 0.05
        session.move_to([*path.position, air], 0.5)
        first = len(session.trace)
        for _ in range(240):
            xy, velocity = path.step(omega, session.dt)
            session.tick(xy, air, compliance_on=False, velocity=np.append(velocity, 0.0))
        force = np.linalg.norm(session.trace.arrays()["force"][first + 60:], axis=1)
        assert np.sqrt(np.mean(force ** 2)) < 0.6 and force.max() < 1.5
    finally:
        task.close()
