"""Logging a wiping run to MCAP and Rerun (through :class:`wipelab.logs.StageRecorder`).

Topics (``<stage>`` is ``adapt`` or ``replay``; all times are simulated seconds). The
controller's series (wrench, force, height, force_norm, contact) are logged at
``SERIES_RATE_HZ`` (every second control period at 120 Hz: the force the controller uses is
low-passed at 25 Hz, below that rate's Nyquist frequency; the metrics use every period);
what is for looking at (the 3D scene, joint states, phase) has ``POSE_RATE_HZ``. Each series
is written in one go (:meth:`~wipelab.logs.StageRecorder.scalars`, ``transform_series``,
``pose_series``, ``arrow_series``), not per time stamp: an MCAP message costs ~20 us to
write, as much as a tenth of a simulated control period. While the F/T sensor is calibrated
the control loop records nothing; the series have a gap there (a null row), not a bridge.

- ``/tf``: every URDF joint as a frame transform (parent link -> child link): fixed and held
  joints once, the 10 moving joints at ``POSE_RATE_HZ``; plus ``world -> sponge``.
- ``/robot/body``: the URDF's visual solids, one frame-locked ``foxglove.SceneUpdate`` entity
  per link (Foxglove cannot read the URDF; Rerun draws the URDF itself, ``/armar3b``);
  ``/robot/sponge``: the sponge as a box on the frame ``sponge``.
- ``/robot/joint_states/position``, ``/robot/joint_states/command``: torso + right arm (rad),
  at ``POSE_RATE_HZ``.
- ``/<stage>/wrench``: raw F/T reading (sensor frame ``hand_r``, N and N m).
- ``/<stage>/force``: contact force as the controller sees it (world, N) and its length;
  ``/<stage>/force_arrow``: that force drawn at the sponge (1 cm per N).
- ``/<stage>/height``: world z (m) of the tool centre point (TCP: commanded, actual, and the
  reference Y_r of eq. 10), of the contact point (the sponge's lowest point) and of the
  surface under it.
- ``/<stage>/force_norm``: |F| as measured, F_0 and the true normal force on the sponge (N)
  - with ``/<stage>/height`` the paper's Figs. 6-7.
- ``/<stage>/contact``: contact (0/1), sponge compression (m), compliance velocity (m/s).
- ``/<stage>/segment``: what the robot is doing (``wipelab.State``: approach, F/T
  calibration, learning, ..., for replay "<scale>x (<Hz>) <mode>"); ``/<stage>/events``: the
  same as ``foxglove.Log`` messages; ``/<stage>/phase``: the phase (rad), at ``POSE_RATE_HZ``.
- ``/<stage>/tcp_commanded``, ``/<stage>/tcp_actual``: TCP poses (``PoseInFrame``).
- ``/<stage>/path``: the x-y path at the start height (3D line).
- ``/adapt/learned_profile``: the learned z along the path after each period (3D line);
  ``/adapt/profile``: the same over the phase against the true surface (TCP height in contact
  at F_0), in mm from the latter's mean, one message per period (``wipelab.PhaseCurves``).
- ``/replay/force_by_phase/<mode>``: |F| over the phase, the mean over the scored periods of
  each run, one message per speed (``wipelab.PhaseCurves``).
- ``/scene/surface``: the surface's grid points; Rerun also gets the surface as a mesh.
- ``/<stage>/placement`` (JSON), ``/scene/platform_footprint``, ``/scene/path_center``: where
  the path went and how the platform stood (:func:`log_placement`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.urdf import UrdfTree

from wipelab.control.force_profile import COMPARISON_PHASES
from wipelab.learning import PeriodicModel
from wipelab.logs import StageRecorder, stage_panels, whole_run
from wipelab.logs.palette import (INPUT_COLOUR, LEARNED_COLOUR, REFERENCE_COLOUR, segment_colour,
                                  speed_colours)
from wipelab.logs.phase_chart import PhaseChart
from wipelab.sim.armar3 import PLATFORM_SIZE, RIGHT_ARM_JOINTS, TORSO_JOINTS, armar3b_urdf_path
from wipelab.rotations import (quaternion_xyzw_from_rotation, quaternions_xyzw_from_rotations,
                               rotations_from_quaternions_xyzw)
from wipelab.sim.kinematics import parse_urdf_joints
from wipelab.sim.path import PATH_PHASES, dof_waveform
from wipelab.sim.sponge import bottom_points
from wipelab.sim.urdf_visuals import urdf_visuals

#: Rate (Hz) of the 3D scene in the logs (poses, /tf, force arrow).
POSE_RATE_HZ = 15.0
#: Rate (Hz) of the controller's series in the logs (at most the control rate).
SERIES_RATE_HZ = 60.0
#: Length of the force arrow per newton (m/N).
ARROW_SCALE = 0.01
#: Phase bins of the replay's |F| over the phase.
PHASE_BINS = 64
#: A time step longer than this many control periods is a gap in the trace (F/T calibration).
GAP_PERIODS = 3
#: Name of the stretch the trace skips while the F/T sensor is calibrated.
CALIBRATION = "F/T calibration"
#: Colours of the TCP height commanded, actual and its reference Y_r; the commanded one
#: (the actual one plus a tracking error) is hidden in the layouts, a click on the legend away.
TCP_COLOURS, TCP_SHOWN = ((150, 150, 150), INPUT_COLOUR, LEARNED_COLOUR), (False, True, True)
#: Colours of the contact point's height and the surface's under it.
CONTACT_COLOURS = ((240, 200, 30), REFERENCE_COLOUR)
#: Colours of |F| measured, F_0, and the true contact force.
FORCE_COLOURS = (INPUT_COLOUR, REFERENCE_COLOUR, (150, 110, 200))
#: Roots of the entities drawn as 2D charts (kept out of the 3D view).
CHARTS = ("/adapt/profile", "/replay/force_by_phase")
#: Colours of the learned profile period after period (light to dark) in ``/adapt/profile``.
PERIOD_RAMP = ((250, 195, 175), LEARNED_COLOUR)


@dataclass(frozen=True)
class Segment:
    """A part of a run: its name (a replay run's ends with its mode), the trace mode label
    and its start time (s)."""

    name: str
    mode: int
    start: float


@dataclass(frozen=True)
class ReplayRun:
    """One replay run as logged: its mode, frequency scale and frequency (Hz), and the scored
    window (start, end] (s) whose |F| is drawn over the phase."""

    mode: str
    scale: float
    frequency_hz: float
    start: float
    end: float


def mode_entity(mode: str) -> str:
    """Entity-path part of a replay mode (``learned+compliance`` -> ``learned_compliance``)."""
    return mode.replace("+", "_")


def speed_label(scale: float, frequency_hz: float) -> str:
    """``"2x (0.50 Hz)"``."""
    return f"{scale:g}x ({frequency_hz:.2f} Hz)"


def _chart_view(origin: str, name: str) -> rrb.Spatial2DView:
    """A 2D view of a :class:`PhaseChart` showing what was logged at any time."""
    return rrb.Spatial2DView(
        origin=origin, name=name, visual_bounds=PhaseChart.bounds(),
        time_ranges=[rrb.VisibleTimeRange("time", start=rrb.TimeRangeBoundary.infinite(),
                                          end=rrb.TimeRangeBoundary.infinite())])


def _scene_view(trace: dict) -> rrb.Spatial3DView:
    """The robot, the sponge and the surface, seen from the front left of the wiped area."""
    contact = trace["sponge_force"] > 1.0
    target = np.median(trace["sponge_pos"][contact if contact.any() else slice(None)], axis=0)
    return rrb.Spatial3DView(origin="/", contents=["+ /**", *(f"- {chart}/**" for chart in CHARTS)],
                             name="robot, sponge and surface", eye_controls=rrb.EyeControls3D(
        position=target + np.array([0.35, -0.95, 0.45]), look_target=target - [0.15, 0.0, 0.0],
        eye_up=[0.0, 0.0, 1.0]))


def _series_view(origin: str, name: str, **options) -> rrb.TimeSeriesView:
    """Series over the whole run, the legend in the top right corner."""
    return rrb.TimeSeriesView(origin=origin, name=name, axis_x=whole_run(),
                              plot_legend=rrb.PlotLegend("RightTop"), **options)


def _state_view(origin: str, name: str) -> rrb.StateTimelineView:
    return rrb.StateTimelineView(origin=origin, name=name, time_view=whole_run())


def _height_views(stage: str) -> list[rrb.TimeSeriesView]:
    """The TCP's height (what the controller commands) and the contact point's (where the
    sponge touches) with the surface under it."""
    tcp = f"/{stage}/tcp_height"
    return [_series_view(tcp, "TCP (tool centre point) z (m)", overrides={
                tcp: rr.SeriesLines.from_fields(visible_series=TCP_SHOWN)}),
            _series_view(f"/{stage}/contact_height",
                         "contact point (sponge bottom) and surface z (m)")]


def adapt_blueprint(trace: dict) -> rrb.Blueprint:
    """Adapt: the robot; the learned profile against the true surface over the phase, one
    curve per period; the TCP's and the contact point's height and |F| over time; what the
    robot is doing (approach, F/T calibration, learning, the learned profile)."""
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Vertical(_scene_view(trace),
                             _chart_view("/adapt/profile", "learned profile vs true surface "
                                                           "over the phase (rad), per period"),
                             row_shares=[3, 2]),
                rrb.Vertical(*_height_views("adapt"),
                             _series_view("/adapt/force_norm", "|F| and F0 (N)")),
                column_shares=[1, 1]),
            _state_view("/adapt/segment", "what the robot does"),
            row_shares=[7, 1]),
        *stage_panels())


def replay_blueprint(trace: dict, modes) -> rrb.Blueprint:
    """Replay: the robot and |F| over time; per mode, |F| over the phase with every speed
    overlaid; which run (speed and mode) the robot is in."""
    charts = [_chart_view(f"/replay/force_by_phase/{mode_entity(m)}",
                          f"{m}: |F| over the phase (rad), per speed") for m in modes]
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                rrb.Vertical(_scene_view(trace),
                             _series_view("/replay/force_norm", "|F| and F0 (N)")),
                rrb.Grid(*charts, grid_columns=2 if len(charts) > 1 else 1),
                column_shares=[2, 3]),
            _state_view("/replay/segment", "run: speed (frequency) and mode"),
            row_shares=[7, 1]),
        *stage_panels())


def _transform(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return pose[:3, 3], quaternion_xyzw_from_rotation(pose[:3, :3])


def log_scene(rec: StageRecorder, task, t0: float) -> None:
    """What does not move: the robot (URDF, fixed and held joints), the sponge, the surface."""
    urdf_path = armar3b_urdf_path()
    urdf_text = urdf_path.read_text()
    rec.attach("armar3b.urdf", urdf_path.read_bytes(), "application/xml")
    UrdfTree.from_file_path(urdf_path).log_urdf_to_recording(rec.rerun)
    rec.rerun.log("/tf/world", rr.Transform3D(parent_frame="tf#/", child_frame="world"),
                  static=True)
    joints = parse_urdf_joints(urdf_text)
    held = dict(task.options.base.joint_values())
    transforms = []
    for joint in joints.values():
        if joint.name in TORSO_JOINTS or joint.name in RIGHT_ARM_JOINTS:
            continue
        translation, quaternion = _transform(joint.transform(held.get(joint.name, 0.0)))
        transforms.append((joint.parent, joint.child, translation, quaternion))
    rec.transforms(t0, transforms)
    rec.shapes("/robot/body", t0, [(f"armar3b/{link}", link, shapes)
                                   for link, shapes in urdf_visuals(urdf_text).items()])
    rec.box3d("/robot/sponge", t0, task.options.sponge.size, np.zeros(3), frame_id="sponge")
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


def _gaps(task, t: np.ndarray) -> list[tuple[float, float]]:
    """Stretches (start, end) s with no trace rows: the F/T calibration."""
    dt = task.world.config.dt
    jumps = np.flatnonzero(np.diff(t) > GAP_PERIODS * dt)
    return [(float(t[k] + dt), float(t[k + 1])) for k in jumps]


def _with_gaps(t: np.ndarray, values: np.ndarray, gaps) -> tuple[np.ndarray, np.ndarray]:
    """``t``, ``values`` with a row of NaN at the start of each gap (a plot breaks there)."""
    values = np.asarray(values, dtype=float)
    if not gaps:
        return t, values
    at = np.searchsorted(t, [start for start, _ in gaps])
    nan_row = np.full((len(gaps),) + values.shape[1:], np.nan)
    return (np.insert(t, at, [start for start, _ in gaps]),
            np.insert(values, at, nan_row, axis=0))


@lru_cache(maxsize=1)
def _robot_joints() -> dict:
    """The shipped URDF's joints (parsed once: ``wipelab live`` logs its trace in slices)."""
    return parse_urdf_joints(armar3b_urdf_path().read_text())


def _log_poses(rec: StageRecorder, stage: str, task, trace: dict) -> None:
    """The 3D scene at :data:`POSE_RATE_HZ`: /tf of the moving joints and the sponge, the TCP
    poses and the force arrow, each as one series."""
    urdf_joints = _robot_joints()
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


def contact_heights(task, sponge_pos: np.ndarray, sponge_quat: np.ndarray) -> np.ndarray:
    """World z (n, 2) of the contact point (the lowest point of the sponge's bottom face)
    and of the surface under it, for sponge poses (n, 3) and (n, 4) (x, y, z, w)."""
    bottom = bottom_points(task.options.sponge.size)                       # (m, 3) sponge frame
    rotations = rotations_from_quaternions_xyzw(sponge_quat)             # (n, 3, 3)
    points = np.einsum("nij,mj->nmi", rotations, bottom) + sponge_pos[:, None, :]
    lowest = points[np.arange(len(points)), np.argmin(points[:, :, 2], axis=1)]
    return np.column_stack([lowest[:, 2], task.surface.height_at(lowest[:, :2])])


def _log_series(rec: StageRecorder, stage: str, task, trace: dict, gaps) -> None:
    t = trace["t"]
    pick = _samples(task, trace, POSE_RATE_HZ)
    names = list(TORSO_JOINTS + RIGHT_ARM_JOINTS)
    for topic, key in (("position", "q"), ("command", "q_cmd")):
        rec.scalars(f"/robot/joint_states/{topic}", *_with_gaps(t[pick], trace[key][pick], gaps),
                    names=names)
    rec.scalars(f"/{stage}/phase", *_with_gaps(
        t[pick], np.mod(np.nan_to_num(trace["phase"][pick]), 2 * np.pi), gaps), names=["phase"])
    every = _samples(task, trace, SERIES_RATE_HZ)
    series = {key: trace[key][every] for key in ("t", "wrench", "force", "tcp_cmd", "tcp",
                                                 "z_ref", "sponge_force", "compression", "vz",
                                                 "sponge_pos", "sponge_quat")}
    ts = series["t"]
    rec.scalars(f"/{stage}/wrench", *_with_gaps(ts, series["wrench"], gaps),
                names=["fx", "fy", "fz", "tx", "ty", "tz"])
    norm = np.linalg.norm(series["force"], axis=1)
    rec.scalars(f"/{stage}/force", *_with_gaps(ts, np.column_stack([series["force"], norm]), gaps),
                names=["fx", "fy", "fz", "norm"])
    tcp = np.column_stack([series["tcp_cmd"][:, 2], series["tcp"][:, 2], series["z_ref"]])
    rec.scalars(f"/{stage}/tcp_height", *_with_gaps(ts, tcp, gaps),
                names=["commanded", "actual", "reference"], colors=np.array(TCP_COLOURS))
    rec.scalars(f"/{stage}/contact_height", *_with_gaps(
        ts, contact_heights(task, series["sponge_pos"], series["sponge_quat"]), gaps),
        names=["contact_point", "surface"], colors=np.array(CONTACT_COLOURS))
    target = np.full(len(norm), task.options.compliance.target_force)
    rec.scalars(f"/{stage}/force_norm", *_with_gaps(
        ts, np.column_stack([norm, target, series["sponge_force"]]), gaps),
        names=["measured", "F0", "true_contact"], colors=np.array(FORCE_COLOURS))
    contact = (series["sponge_force"] > 1.0).astype(float)
    rec.scalars(f"/{stage}/contact", *_with_gaps(
        ts, np.column_stack([contact, series["compression"], series["vz"]]), gaps),
        names=["contact", "compression_m", "compliance_velocity"])


def _log_segments(rec: StageRecorder, stage: str, trace: dict, segments, gaps) -> None:
    """What the robot is doing (a state per segment, the calibration gaps included) and the
    same as log events."""
    t0 = float(trace["t"][0])
    changes = [(max(s.start, t0), s) for s in segments]
    for start, end in gaps:
        after = [s for time, s in changes if time <= end][-1]
        changes = [(time, s) for time, s in changes if not start <= time <= end]
        changes += [(start, Segment(CALIBRATION, -1, start)), (end, after)]
    changes.sort(key=lambda change: change[0])
    palette = {s.name: segment_colour(s.name) for _, s in changes}
    times = [time for time, _ in changes]
    rec.states(f"/{stage}/segment", times, [s.name for _, s in changes], palette)
    rec.events(f"/{stage}/events", times, [s.name for _, s in changes])


def _log_profiles(rec: StageRecorder, task, trace: dict, model: PeriodicModel,
                  profiles) -> None:
    """The learned z after each period, along the path in 3D and over the phase against the
    true surface: the TCP height at which the sponge presses with F_0, where the TCP was
    (x-y and orientation) at each phase."""
    xy = dof_waveform(model, ("x", "y"), COMPARISON_PHASES)
    moving = np.isfinite(trace["phase"])
    expected = task.expected_contact_height(trace["tcp"][moving, :2], trace["tcp_rot"][moving])
    surface = mean_over_phase(trace["phase"][moving], expected, len(COMPARISON_PHASES))
    reference = float(np.nanmean(surface))
    surface_mm = 1000.0 * (surface - reference)
    learned = [1000.0 * (np.asarray(z) - reference) for _, z in profiles]
    chart = PhaseChart.fitting(np.concatenate([surface_mm, *learned]), "height - mean (mm)")
    rec.phase_chart("/adapt/profile", chart)
    ramp = np.array(PERIOD_RAMP, dtype=float)
    shades = np.linspace(0.0, 1.0, len(profiles)) if len(profiles) > 1 else np.ones(1)
    colours = [tuple(int(c) for c in np.round(ramp[0] + shade * (ramp[1] - ramp[0])))
               for shade in shades]
    periods = "period 1" if len(profiles) == 1 else f"periods 1 .. {len(profiles)}"
    rec.phase_legend("/adapt/profile", chart, {
        "true surface (TCP z at F0)": REFERENCE_COLOUR, f"learned, {periods}": colours[-1]})
    for period, ((time, z), z_mm, colour) in enumerate(zip(profiles, learned, colours), start=1):
        rec.line_strip3d("/adapt/learned_profile", time, np.column_stack([xy, z]),
                         color=(40, 160, 255))
        rec.phase_curves("/adapt/profile", time, chart, COMPARISON_PHASES,
                         {"learned_mm": z_mm, "surface_mm": surface_mm},
                         {"learned_mm": colour, "surface_mm": REFERENCE_COLOUR},
                         extra={"period": period, "reference_z_m": reference})


def mean_over_phase(phase: np.ndarray, values: np.ndarray, bins: int) -> np.ndarray:
    """Mean of ``values`` (n,) per phase bin: (bins,) at the phases ``2 pi k / bins``
    (each sample goes to the nearest), NaN where no sample fell."""
    index = np.mod(np.round(np.asarray(phase) / (2.0 * math.pi) * bins).astype(int), bins)
    total = np.bincount(index, weights=values, minlength=bins)
    count = np.bincount(index, minlength=bins)
    return np.divide(total, count, out=np.full(bins, np.nan), where=count > 0)


def force_over_phase(trace: dict, start: float, end: float,
                     bins: int = PHASE_BINS) -> tuple[np.ndarray, np.ndarray]:
    """Mean |F| (N) over the window (start, end] s in ``bins`` phase bins: phases (bins + 1,)
    rad from 0 to 2 pi (the first bin repeated at 2 pi to close the period) and mean |F|
    (bins + 1,), NaN in a bin the window never reached."""
    window = (trace["t"] > start) & (trace["t"] <= end) & np.isfinite(trace["phase"])
    mean = mean_over_phase(trace["phase"][window],
                           np.linalg.norm(trace["force"][window], axis=1), bins)
    phases = np.arange(bins + 1) / bins * 2.0 * math.pi
    return phases, np.append(mean, mean[0])


def _log_force_by_phase(rec: StageRecorder, trace: dict, runs, target_force: float) -> None:
    """Per mode, |F| over the phase of each speed's run, in one chart per mode."""
    curves = {run: force_over_phase(trace, run.start, run.end) for run in runs}
    colours = speed_colours([run.scale for run in runs])
    for mode in dict.fromkeys(run.mode for run in runs):
        ours = [run for run in runs if run.mode == mode]
        topic = f"/replay/force_by_phase/{mode_entity(mode)}"
        chart = PhaseChart.fitting(np.concatenate([[0.0, target_force]]
                                                  + [curves[run][1] for run in ours]), "|F| (N)")
        rec.phase_chart(topic, chart, {f"F0 = {target_force:g} N": target_force})
        rec.phase_legend(topic, chart, {speed_label(run.scale, run.frequency_hz):
                                        colours[run.scale] for run in ours})
        for run in ours:
            phase, force = curves[run]
            rec.phase_curves(topic, run.end, chart, phase, {"force_n": force},
                             {"force_n": colours[run.scale]},
                             extra={"mode": run.mode, "scale": run.scale,
                                    "frequency_hz": run.frequency_hz})


def log_run(rec: StageRecorder, stage: str, task, trace: dict, segments, profiles=(),
            model: PeriodicModel | None = None, runs=()) -> None:
    """Log one run's trace (see the module docstring for the topics): ``profiles`` (time s,
    learned z at ``COMPARISON_PHASES``) per adapt period, ``runs`` the :class:`ReplayRun`
    of a replay."""
    t0 = float(trace["t"][0])
    gaps = _gaps(task, trace["t"])
    log_scene(rec, task, t0)
    if model is not None:
        path = dof_waveform(model, ("x", "y"), PATH_PHASES)
        z = task.start_height if "z" not in model.dofs else dof_waveform(model, ("z",))[:, 0]
        rec.line_strip3d(f"/{stage}/path", t0, np.column_stack([path, np.broadcast_to(
            z, len(path))]), color=(255, 255, 255))
    log_trace(rec, stage, task, trace, gaps)
    _log_segments(rec, stage, trace, segments, gaps)
    if profiles:
        _log_profiles(rec, task, trace, model, profiles)
    if runs:
        _log_force_by_phase(rec, trace, runs, task.options.compliance.target_force)


def log_trace(rec: StageRecorder, stage: str, task, trace: dict, gaps=()) -> None:
    """The controller's series and the 3D scene of ``trace`` (arrays, a whole run or a slice
    of one whose length is a multiple of the pose stride: ``wipelab live`` logs its run as it
    goes); ``gaps`` (start, end) s where the trace has no rows."""
    _log_series(rec, stage, task, trace, list(gaps))
    _log_poses(rec, stage, task, trace)


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
