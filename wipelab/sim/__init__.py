"""The simulated ARMAR-IIIb wiping surfaces (PyBullet, headless).

Modules: :mod:`~wipelab.sim.armar3` (the sourced robot description, shipped as
``assets/armar3b.urdf``), :mod:`~wipelab.sim.kinematics` (numpy FK and Jacobians from URDF),
:mod:`~wipelab.sim.ik` and :mod:`~wipelab.sim.arm` (IK, posture for a task),
:mod:`~wipelab.sim.reach` (the arm's reach map) and :mod:`~wipelab.sim.placement` (where the
path and the platform go), :mod:`~wipelab.sim.surfaces` (flat, bowl, sink, user heightfields
and meshes),
:mod:`~wipelab.sim.sponge` (passive compliance, unknown grasp), :mod:`~wipelab.sim.ft_sensor`
(wrist F/T: noise, gravity compensation, low-pass), :mod:`~wipelab.sim.world` (the PyBullet
scene), :mod:`~wipelab.sim.session` (the control loop), :mod:`~wipelab.sim.path` (placing and
executing a model), :mod:`~wipelab.sim.task` (setting a task up),
:mod:`~wipelab.sim.adaptation` (the adapt algorithm, stepped one control period at a time),
:mod:`~wipelab.sim.metrics` and :mod:`~wipelab.sim.recording` (results and logs).

Frames: world after REP-103 (x forward, y left, z up), ``base_link`` on the floor under the
platform centre; PyBullet quaternions are (x, y, z, w). SI units.
"""

from wipelab.sim.armar3 import armar3b_urdf, armar3b_urdf_path
from wipelab.sim.surfaces import BUILTIN_SURFACES, Surface, load_surface
from wipelab.sim.task import TaskOptions, WipingTask, build_task
from wipelab.sim.world import BasePose, SimConfig, SimWorld

__all__ = ["BUILTIN_SURFACES", "BasePose", "SimConfig", "SimWorld", "Surface", "TaskOptions",
           "WipingTask", "armar3b_urdf", "armar3b_urdf_path", "build_task", "load_surface"]
