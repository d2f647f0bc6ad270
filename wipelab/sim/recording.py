"""Logging a wiping run to MCAP and Rerun (through :class:`wipelab.logs.StageRecorder`).

Topics (``<stage>`` is ``adapt`` or ``replay``; all times are simulated seconds). The
controller's series (wrench, force, height, force_norm, contact) are logged at
``SERIES_RATE_HZ`` (every second control period at 120 Hz: the force the controller uses is
low-passed at 25 Hz, below that rate's Nyquist frequency; the metrics use every period);
what is for looking at (the 3D scene, joint states, segment, phase) has ``POSE_RATE_HZ``.
Each series is written in one go (:meth:`~wipelab.logs.StageRecorder.scalars`,
``transform_series``, ``pose_series``, ``arrow_series``), not per time stamp: an MCAP
message costs ~20 us to write, as much as a tenth of a simulated control period.

- ``/tf``: every URDF joint as a frame transform (parent link -> child link): fixed and held
  joints once, the 10 moving joints at ``POSE_RATE_HZ``; plus ``world -> sponge``.
- ``/robot/joint_states/position``, ``/robot/joint_states/command``: torso + right arm (rad),
  at ``POSE_RATE_HZ``.
- ``/<stage>/wrench``: raw F/T reading (sensor frame ``hand_r``, N and N m).
- ``/<stage>/force``: contact force as the controller sees it (world, N) and its length;
  ``/<stage>/force_arrow``: that force drawn at the sponge (1 cm per N).
- ``/<stage>/height``: commanded, actual and reference TCP z (m).
- ``/<stage>/force_norm``: |F|, F_0 and the true normal force on the sponge (N) - with
  ``/<stage>/height`` the paper's Figs. 6-7.
- ``/<stage>/contact``: contact (0/1), sponge compression (m), compliance velocity (m/s).
- ``/<stage>/segment``, ``/<stage>/phase``: the segment label (learning 1 -> 2 marks the end
  of learning) and the phase (rad), at ``POSE_RATE_HZ``; ``/<stage>/events``: one JSON
  message per segment start, at its exact time.
- ``/<stage>/tcp_commanded``, ``/<stage>/tcp_actual``: TCP poses (``PoseInFrame``).
- ``/adapt/learned_profile``: the learned z along the path after each period (3D line) and
  ``/adapt/profile`` (JSON: period, waveform) - how the profile converges.
- ``/scene/surface``: the surface's grid points; Rerun also gets the robot model from the URDF
  (``/armar3b``), the sponge box and the surface as a mesh.
- ``/<stage>/placement`` (JSON), ``/scene/platform_footprint``, ``/scene/path_center``: where
  the path went and how the platform stood (:func:`log_placement`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.urdf import UrdfTree

from wipelab.control.force_profile import COMPARISON_PHASES
from wipelab.learning import PeriodicModel
from wipelab.logs import StageRecorder
from wipelab.sim.armar3 import PLATFORM_SIZE, RIGHT_ARM_JOINTS, TORSO_JOINTS, armar3b_urdf_path
from wipelab.sim.kinematics import (parse_urdf_joints, quaternion_xyzw_from_rotation,
                                    quaternions_xyzw_from_rotations)
from wipelab.sim.path import PATH_PHASES, dof_waveform

#: Rate (Hz) of the 3D scene in the logs (poses, /tf, force arrow).
POSE_RATE_HZ = 15.0
#: Rate (Hz) of the controller's series in the logs (at most the control rate).
SERIES_RATE_HZ = 60.0
#: Length of the force arrow per newton (m/N).
ARROW_SCALE = 0.01


@dataclass(frozen=True)
class Segment:
    """A part of a run: its name, the trace mode label and its start time (s)."""

    name: str
    mode: int
    start: float


def wiping_blueprint(stage: str) -> rrb.Blueprint:
    """The default Rerun layout: the scene beside height, force and joint plots."""
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="/", name="robot and surface"),
            rrb.Vertical(
                rrb.TimeSeriesView(origin=f"/{stage}/height", name="height (m)"),
                rrb.TimeSeriesView(origin=f"/{stage}/force_norm", name="|F| (N)"),
                rrb.TimeSeriesView(origin=f"/{stage}/segment", name="segment"),
                rrb.TimeSeriesView(origin="/robot/joint_states", name="joints (rad)"),
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=True,
    )


def _transform(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return pose[:3, 3], quaternion_xyzw_from_rotation(pose[:3, :3])


def _log_static_scene(rec: StageRecorder, task, t0: float) -> None:
    urdf_path = armar3b_urdf_path()
    rec.attach("armar3b.urdf", urdf_path.read_bytes(), "application/xml")
    UrdfTree.from_file_path(urdf_path).log_urdf_to_recording(rec.rerun)
    rec.rerun.log("/tf/world", rr.Transform3D(parent_frame="tf#/", child_frame="world"),
                  static=True)
    joints = parse_urdf_joints(urdf_path.read_text())
    held = dict(task.options.base.joint_values())
    transforms = []
    for joint in joints.values():
        if joint.name in TORSO_JOINTS or joint.name in RIGHT_ARM_JOINTS:
            continue
        translation, quaternion = _transform(joint.transform(held.get(joint.name, 0.0)))
        transforms.append((joint.parent, joint.child, translation, quaternion))
    rec.transforms(t0, transforms)
    size = np.asarray(task.options.sponge.size)
    rec.rerun.log("/robot/sponge", rr.CoordinateFrame("sponge"),
                  rr.Boxes3D(half_sizes=[size / 2], colors=[(240, 200, 30)], fill_mode="solid"),
                  static=True)
    grid = task.surface.grid_points()
    step = max(1, int(round(0.02 / task.surface.cell)))
    rec.points3d("/scene/surface", t0, grid[::step, ::step].reshape(-1, 3),
                 colors=(170, 140, 110), radii=0.002)
    nx, ny = grid.shape[:2]
    index = np.arange(nx * ny).reshape(nx, ny)
    a, b, c, d = (index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(),
                  index[:-1, 1:].ravel())
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    rec.rerun.log("/scene/surface_mesh", rr.Mesh3D(vertex_positions=grid.reshape(-1, 3),
                                                   triangle_indices=triangles,
                                                   albedo_factor=(180, 150, 120, 255)),
                  static=True)


def _log_poses(rec: StageRecorder, stage: str, task, trace: dict) -> None:
    """The 3D scene at :data:`POSE_RATE_HZ`: /tf of the moving joints and the sponge, the TCP
    poses and the force arrow, each as one series."""
    urdf_joints = parse_urdf_joints(armar3b_urdf_path().read_text())
    pick = _samples(task, trace, POSE_RATE_HZ)
    t = trace["t"][pick]
    frames = []
    for name, values in zip(TORSO_JOINTS + RIGHT_ARM_JOINTS, trace["q"][pick].T):
        joint = urdf_joints[name]
        poses = joint.transforms(values)
        frames.append((joint.parent, joint.child, poses[:, :3, 3],
                       quaternions_xyzw_from_rotations(poses[:, :3, :3])))
    frames.append(("world", "sponge", trace["sponge_pos"][pick], trace["sponge_quat"][pick]))
    rec.transform_series(t, frames)
    tcp_quaternions = quaternions_xyzw_from_rotations(trace["tcp_rot"][pick])
    rec.pose_series(f"/{stage}/tcp_commanded", t, "world", trace["tcp_cmd"][pick],
                    tcp_quaternions)
    rec.pose_series(f"/{stage}/tcp_actual", t, "world", trace["tcp"][pick], tcp_quaternions)
    rec.arrow_series(f"/{stage}/force_arrow", t, trace["sponge_pos"][pick],
                     ARROW_SCALE * trace["force"][pick])


def _samples(task, trace: dict, rate_hz: float) -> slice:
    """The control periods logged at ``rate_hz``: every k-th, k = control rate / rate_hz
    rounded (at least 1)."""
    every = max(1, int(round(1.0 / (rate_hz * task.world.config.dt))))
    return slice(0, len(trace["t"]), every)


def _log_series(rec: StageRecorder, stage: str, task, trace: dict, segments) -> None:
    t = trace["t"]
    pick = _samples(task, trace, POSE_RATE_HZ)
    names = list(TORSO_JOINTS + RIGHT_ARM_JOINTS)
    rec.scalars("/robot/joint_states/position", t[pick], trace["q"][pick], names=names)
    rec.scalars("/robot/joint_states/command", t[pick], trace["q_cmd"][pick], names=names)
    rec.scalars(f"/{stage}/segment", t[pick], trace["mode"][pick].astype(float),
                names=["segment"])
    rec.scalars(f"/{stage}/phase", t[pick],
                np.mod(np.nan_to_num(trace["phase"][pick]), 2 * np.pi), names=["phase"])
    every = _samples(task, trace, SERIES_RATE_HZ)
    series = {key: trace[key][every] for key in ("t", "wrench", "force", "tcp_cmd", "tcp",
                                                 "z_ref", "sponge_force", "compression", "vz")}
    rec.scalars(f"/{stage}/wrench", series["t"], series["wrench"],
                names=["fx", "fy", "fz", "tx", "ty", "tz"])
    norm = np.linalg.norm(series["force"], axis=1)
    rec.scalars(f"/{stage}/force", series["t"], np.column_stack([series["force"], norm]),
                names=["fx", "fy", "fz", "norm"])
    rec.scalars(f"/{stage}/height", series["t"],
                np.column_stack([series["tcp_cmd"][:, 2], series["tcp"][:, 2], series["z_ref"]]),
                names=["commanded", "actual", "reference"])
    target = np.full(len(norm), task.options.compliance.target_force)
    rec.scalars(f"/{stage}/force_norm", series["t"],
                np.column_stack([norm, target, series["sponge_force"]]),
                names=["measured |F|", "F0", "true contact"])
    contact = (series["sponge_force"] > 1.0).astype(float)
    rec.scalars(f"/{stage}/contact", series["t"],
                np.column_stack([contact, series["compression"], series["vz"]]),
                names=["contact", "compression_m", "compliance_velocity"])
    for segment in segments:
        rec.json(f"/{stage}/events", max(segment.start, float(t[0])),
                 {"event": segment.name, "mode": segment.mode}, "wipelab.Event",
                 {"type": "object", "properties": {"event": {"type": "string"},
                                                   "mode": {"type": "integer"}}})


def _log_profiles(rec: StageRecorder, model: PeriodicModel, profiles) -> None:
    xy = dof_waveform(model, ("x", "y"), COMPARISON_PHASES)
    schema = {"type": "object", "properties": {"period": {"type": "integer"},
                                               "phase": {"type": "array"},
                                               "z": {"type": "array"}}}
    for period, (time, z) in enumerate(profiles, start=1):
        rec.line_strip3d("/adapt/learned_profile", time, np.column_stack([xy, z]),
                         color=(40, 160, 255))
        rec.json("/adapt/profile", time, {"period": period, "phase": COMPARISON_PHASES.tolist(),
                                          "z": np.asarray(z).tolist()}, "wipelab.Profile", schema)


def log_run(rec: StageRecorder, stage: str, task, trace: dict, segments, profiles=(),
            model: PeriodicModel | None = None) -> None:
    """Log one run's trace (see the module docstring for the topics)."""
    t0 = float(trace["t"][0])
    _log_static_scene(rec, task, t0)
    if model is not None:
        path = dof_waveform(model, ("x", "y"), PATH_PHASES)
        z = task.start_height if "z" not in model.dofs else dof_waveform(model, ("z",))[:, 0]
        rec.line_strip3d(f"/{stage}/path", t0, np.column_stack([path, np.broadcast_to(
            z, len(path))]), color=(255, 255, 255))
    _log_series(rec, stage, task, trace, segments)
    _log_poses(rec, stage, task, trace)
    if profiles:
        _log_profiles(rec, model, profiles)


def log_placement(rec: StageRecorder, stage: str, t: float, placement: dict) -> None:
    """The placement the stage ran with (:func:`~wipelab.sim.task.place_task`'s record):
    ``/<stage>/placement`` (JSON) and, in the 3D view, ``/scene/platform_footprint`` (the
    platform's outline on the floor) and ``/scene/path_center`` (where the path's centre
    went, on the floor under it)."""
    rec.json(f"/{stage}/placement", t, placement, "wipelab.Placement")
    x, y, yaw = placement["base"]
    half = PLATFORM_SIZE[0] / 2
    corners = np.array([[-half, -half], [half, -half], [half, half], [-half, half],
                        [-half, -half]])
    c, s = np.cos(yaw), np.sin(yaw)
    outline = corners @ np.array([[c, s], [-s, c]]) + [x, y]
    rec.line_strip3d("/scene/platform_footprint", t,
                     np.column_stack([outline, np.full(len(outline), 0.002)]),
                     color=(90, 200, 255), thickness=0.01)
    rec.points3d("/scene/path_center", t, [[*placement["center"], 0.002]],
                 colors=(90, 200, 255), radii=0.02)
