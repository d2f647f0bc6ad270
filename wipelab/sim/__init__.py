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

import importlib

#: What the package exports, and the module that defines it: imported on first use, so that
#: importing one module of the package (say :mod:`~wipelab.sim.kinematics`) does not start
#: PyBullet and the rest.
_EXPORTS = {"armar3b_urdf": "armar3", "armar3b_urdf_path": "armar3",
            "BUILTIN_SURFACES": "surfaces", "Surface": "surfaces", "load_surface": "surfaces",
            "TaskOptions": "task", "WipingTask": "task", "build_task": "task",
            "BasePose": "world", "SimConfig": "world", "SimWorld": "world"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
