"""The simulated world: what is simulated, where it stands, how fast the physics steps."""

import subprocess
import sys

import numpy as np
import pytest

from wipelab.sim.path import place_model
from wipelab.sim.surfaces import flat_surface
from wipelab.sim.task import TaskOptions, build_task
from wipelab.sim.world import BasePose, SimConfig

from sim_models import circle_model


def test_physics_rate_keeps_the_travel_per_step_small():
    config = SimConfig(physics_hz=240.0, max_travel=0.00075, control_hz=120.0)
    assert config.substeps(0.0) == 2                 # never below physics_hz
    assert config.substeps(0.5) == 6                 # 0.5 m/s: 0.69 mm per step at 720 Hz
    assert 0.5 / (config.substeps(0.5) * config.control_hz) <= config.max_travel
    with pytest.raises(ValueError, match="integer multiple"):
        SimConfig(physics_hz=250.0)


def test_only_the_arm_is_simulated_and_it_stands_where_the_kinematics_say():
    surface = flat_surface()
    model = place_model(circle_model(), surface.wipe_center)
    task = build_task(model, surface, TaskOptions(base=BasePose(-0.05, 0.03, 0.1)))
    try:
        world = task.world
        assert len(world.joint_ids) == 7
        position, rotation = world.tcp_pose()
        expected = task.session.tracker.chain.forward(task.session.q_arm)
        assert position == pytest.approx(expected[:3, 3], abs=1e-6)
        assert np.abs(rotation - expected[:3, :3]).max() < 1e-6
        world.set_tool_speed(0.5)
        assert world.substeps == 6 and world.physics_hz == 720.0
    finally:
        task.close()


def test_importing_the_simulator_prints_nothing():
    banner = subprocess.run([sys.executable, "-c", "import pybullet"], capture_output=True,
                            text=True, check=True)
    assert "pybullet build time" in banner.stdout + banner.stderr
    done = subprocess.run([sys.executable, "-c", "import wipelab.sim.world; print('ok')"],
                          capture_output=True, text=True, check=True)
    assert (done.stdout, done.stderr) == ("ok\n", "")
