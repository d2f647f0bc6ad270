"""The wrist F/T sensor: payload identification, and the right force against a known load."""

import numpy as np
import pytest

from wipelab.sim.ft_sensor import GRAVITY, contact_wrench, identify_payload
from wipelab.rotations import rotation_about_axis
from wipelab.sim.surfaces import flat_surface
from wipelab.sim.task import TaskOptions, build_task
from wipelab.sim.path import place_model

from sim_models import circle_model


def test_identification_recovers_mass_com_and_bias():
    mass, com = 1.2, np.array([0.08, 0.01, -0.02])
    bias = np.array([0.5, -0.3, 0.2, 0.01, -0.02, 0.03])
    rng = np.random.default_rng(0)
    rotations = [rotation_about_axis(a / np.linalg.norm(a), rng.uniform(0.2, 1.0))
                 for a in rng.normal(size=(5, 3))]
    readings = []
    for rotation in rotations:
        g_s = rotation.T @ GRAVITY
        readings.append(np.concatenate([-mass * g_s, np.cross(mass * g_s, com)]) + bias)
    payload = identify_payload(np.array(readings), np.array(rotations))
    assert payload.mass == pytest.approx(mass)
    assert payload.com == pytest.approx(com)
    assert payload.force_bias == pytest.approx(bias[:3])
    force, _ = contact_wrench(readings[2], rotations[2], payload)
    assert force == pytest.approx(np.zeros(3), abs=1e-9)


def test_simulated_sensor_reads_a_known_load_on_the_sponge():
    surface = flat_surface(height=0.60)          # far below: the sponge hangs in free air
    model = place_model(circle_model(), surface.wipe_center)
    task = build_task(model, surface, TaskOptions(seed=3))
    try:
        session = task.session
        session.calibrate()
        assert session.payload.mass == pytest.approx(1.08, abs=0.03)   # hand 1 kg + sponge
        load = np.array([3.0, -2.0, 12.0])
        task.world.external_force = load
        hold = task.world.tcp_pose()[0]
        forces = []
        for _ in range(120):
            session.tick(hold[:2], hold[2], compliance_on=False)
            forces.append(session.force)
        measured = np.mean(forces[60:], axis=0)
        assert measured == pytest.approx(load, abs=0.4)
        # the spring took the load along the sponge's axis
        assert task.world.step().compression > 0.005
    finally:
        task.close()
