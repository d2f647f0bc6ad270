"""Setting up a wiping task: posture, simulated world, control session, start height.

Shared by adapt and replay so that both put the same robot, holding the sponge the same way,
in front of the same surface for the same path. What the controller may use: the nominal
robot kinematics, the placed x-y path and a rough idea of where the surface is (the operator
puts the hand above it: the start height). What only the simulator knows: the surface itself,
the grasp of the sponge, its stiffness.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wipelab.control.compliance import ComplianceParams
from wipelab.errors import InputError
from wipelab.learning import PeriodicModel
from wipelab.sim.arm import SPEED_FRACTION, RightArm, TaskPosture, phase_rate_limit
from wipelab.sim.ft_sensor import FTSensorParams
from wipelab.sim.ik import IKParams
from wipelab.sim.path import PATH_PHASES, dof_waveform
from wipelab.sim.session import WipingSession
from wipelab.sim.sponge import Grasp, SpongeParams, touch
from wipelab.sim.surfaces import Surface
from wipelab.sim.world import SPONGE_SPHERE_RADIUS, BasePose, SimConfig, SimWorld

#: How far below the TCP the operator assumes the sponge's bottom to be (m), for choosing the
#: posture; the true grasp is not used.
NOMINAL_TOOL_DROP = 0.11
#: Height band (m) around the nominal contact height that the posture must reach.
REACH_BAND = 0.04
#: Largest acceptable IK error (m) at any sample point of the path.
REACH_TOLERANCE = 0.005
#: Sponge clearance (m) above the highest point of the surface under the path at the start.
START_CLEARANCE = 0.03
#: Height (m) above the start at which the F/T payload is identified.
CALIBRATION_LIFT = 0.08
#: Every how many of the path's PATH_PHASES its joint speeds are checked.
SPEED_CHECK_STRIDE = 4


@dataclass(frozen=True)
class TaskOptions:
    """Everything about the robot and its world that a stage may set."""

    base: BasePose = BasePose()
    sponge: SpongeParams = SpongeParams()
    grasp: Grasp = Grasp()
    sensor: FTSensorParams = FTSensorParams()
    compliance: ComplianceParams = ComplianceParams()
    sim: SimConfig = SimConfig()
    ik: IKParams = IKParams()
    seed: int = 0


@dataclass
class WipingTask:
    """A ready-to-run task: ``session`` drives ``world``; heights in m, world frame."""

    surface: Surface
    model: PeriodicModel
    options: TaskOptions
    posture: TaskPosture
    world: SimWorld
    session: WipingSession
    start_height: float                 # TCP z (m) of the start: sponge clear of the surface
    path_xy: np.ndarray = field(repr=False)   # (n, 2) x-y path at PATH_PHASES
    max_frequency_hz: float = math.inf  # fastest tempo (Hz) at which the arm follows the path

    def executable_frequency(self, frequency_hz: float) -> float:
        """The tempo (Hz) the path is executed at when ``frequency_hz`` is asked for: at most
        :attr:`max_frequency_hz` (the arm's joint speeds)."""
        return min(frequency_hz, self.max_frequency_hz)

    def close(self) -> None:
        self.world.close()

    def expected_contact_height(self, tcp_xy: np.ndarray, tcp_rotation: np.ndarray,
                                ) -> np.ndarray:
        """True TCP height (n,) (m) at which the sponge, sliding along the path, presses with
        F_0, at TCP x-y (n, 2) (consecutive samples of the motion) and orientation (n, 3, 3).

        The touching height (sponge at rest, :func:`~wipelab.sim.sponge.touch`) lowered by
        what compresses the spring (stiffness k along the sponge's axis a) to balance the
        contact force: with n the surface normal where the sponge touches and v the sliding
        direction (the path's, in the tangent plane), the surface pushes with N (n - mu v),
        N = F_0 / sqrt(1 + mu^2) with |F| feedback (friction is part of |F|) or
        F_0 / (n_z - mu v_z) with F_z feedback; the spring is compressed by
        x = (N (n.a - mu v.a) - m_sponge g a_z) / k, for which the TCP moves down by
        x (n.a) / n_z (the contact point stays on the surface).
        """
        compliance, sponge, mu = self.options.compliance, self.options.sponge, \
            self.surface.friction
        tcp_xy, tcp_rotation = np.asarray(tcp_xy, dtype=float), np.asarray(tcp_rotation)
        height, normal = touch(self.surface.height_at, tcp_xy, tcp_rotation,
                               self.world.tcp_from_sponge, sponge.size, SPONGE_SPHERE_RADIUS)
        axis = tcp_rotation @ self.world.tcp_from_sponge[:3, 2]                    # (n, 3)
        motion = np.zeros((len(tcp_xy), 3))
        if len(tcp_xy) > 1:
            motion[:, :2] = np.gradient(tcp_xy, axis=0)
        slide = motion - np.sum(motion * normal, axis=1, keepdims=True) * normal
        length = np.linalg.norm(slide, axis=1, keepdims=True)
        slide = np.divide(slide, length, out=np.zeros_like(slide), where=length > 0)
        if compliance.feedback == "norm":
            pressure = compliance.target_force / math.sqrt(1.0 + mu ** 2)
        else:
            pressure = compliance.target_force / (normal[:, 2] - mu * slide[:, 2])
        along = np.sum(normal * axis, axis=1)
        compression = (pressure * (along - mu * np.sum(slide * axis, axis=1))
                       - sponge.mass * 9.81 * axis[:, 2]) / sponge.stiffness
        return height - compression * along / normal[:, 2]


def build_task(model: PeriodicModel, surface: Surface, options: TaskOptions,
               source: str = "MODEL") -> WipingTask:
    """Posture, world and session for executing the (placed) x-y path of ``model``.

    Raises
    ------
    InputError
        The path leaves the surface, or the arm cannot reach it within its joint limits.
    """
    path_xy = dof_waveform(model, ("x", "y"))
    surface_z = surface.height_at(path_xy)
    if np.any(np.isnan(surface_z)):
        raise InputError(f"{source}: the placed path leaves the surface {surface.name!r} "
                         "(use --center to move it)")
    nominal = surface_z + NOMINAL_TOOL_DROP
    centre = np.array([*(0.5 * (path_xy.min(axis=0) + path_xy.max(axis=0))), nominal.mean()])
    samples = np.linspace(0, len(path_xy), 12, endpoint=False).astype(int)
    points = np.concatenate([np.column_stack([path_xy[samples], nominal[samples] + dz])
                             for dz in (-REACH_BAND, REACH_BAND)])
    arm = RightArm(options.base.joint_values(), options.ik)
    posture = arm.posture_for(centre, points)
    if posture.error > REACH_TOLERANCE:
        raise InputError(f"{source}: the arm cannot reach the movement (off by "
                         f"{100 * posture.error:.1f} cm at its worst point with the torso "
                         f"leaning up to 40 deg); move it with --center or scale it down")
    tracker = arm.tracker(posture)
    check = slice(0, None, SPEED_CHECK_STRIDE)
    dofs = ("x", "y", "z") if "z" in model.dofs else ("x", "y")
    points = np.column_stack([path_xy, nominal])[check]
    velocities = np.zeros((len(points), 3))
    velocities[:, :len(dofs)] = dof_waveform(model, dofs, PATH_PHASES[check], derivative=1)
    if "z" in model.dofs:
        points[:, 2] = dof_waveform(model, ("z",), PATH_PHASES[check])[:, 0]
    joint_speed = SPEED_FRACTION * options.ik.max_step / options.sim.dt
    max_omega = phase_rate_limit(tracker, posture, points, velocities, joint_speed)
    above = centre + np.array([0.0, 0.0, START_CLEARANCE + CALIBRATION_LIFT])
    start_arm, _ = tracker.solve(posture.arm, above)
    world = SimWorld(surface, posture.torso, start_arm, posture.tcp_rotation, options.base,
                     options.sponge, options.grasp, options.sensor, options.sim, options.seed)
    rotations = np.broadcast_to(posture.tcp_rotation, (len(path_xy), 3, 3))
    heights, _ = touch(surface.height_at, path_xy, rotations, world.tcp_from_sponge,
                       options.sponge.size, SPONGE_SPHERE_RADIUS)
    session = WipingSession(world, tracker, posture.torso, options.compliance, options.sensor)
    session.q_arm = start_arm.copy()
    return WipingTask(surface, model, options, posture, world, session,
                      float(heights.max() + START_CLEARANCE), path_xy,
                      max_omega / (2.0 * math.pi))
