"""Setting up a wiping task: posture, simulated world, control session, start height.

Shared by adapt and replay so that both put the same robot, holding the sponge the same way,
in front of the same surface for the same path. What the controller may use: the nominal
robot kinematics, the placed x-y path and a rough idea of where the surface is (the operator
puts the hand above it: the start height). What only the simulator knows: the surface itself,
the grasp of the sponge, its stiffness.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from wipelab.control.compliance import ComplianceParams
from wipelab.errors import InputError
from wipelab.learning import PeriodicModel
from wipelab.sim.arm import SPEED_FRACTION, RightArm, TaskPosture, phase_rate_limit
from wipelab.sim.ik import ArmIK
from wipelab.sim.ft_sensor import FTSensorParams
from wipelab.sim.ik import IKParams
from wipelab.sim.path import PATH_PHASES, dof_waveform, place_model
from wipelab.sim.placement import (CENTRE_SCALE, LOOSE_CENTRE_SCALE, NOMINAL_SPONGE_OFFSET,
                                   NOMINAL_TOOL_DROP, REACH_BAND, SPONGE_MARGIN, Placement,
                                   PlacementError, PlacementRequest, choose_placements,
                                   platform_outline, sponge_outline)
from wipelab.sim.session import WipingSession
from wipelab.sim.sponge import Grasp, SpongeParams, touch
from wipelab.sim.surfaces import Surface
from wipelab.sim.world import SPONGE_SPHERE_RADIUS, BasePose, SimConfig, SimWorld

#: Smallest clearance (m) of the torso, the arm and the hand above the surface, with the TCP
#: PRESS_DEPTH below its nominal contact height.
BODY_CLEARANCE = 0.01
#: How far (m) below its nominal contact height the TCP may go: the sponge's lowest corner
#: (it is held a little tilted) compressed to the full (the sponge's 25 mm).
PRESS_DEPTH = 0.02
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


@dataclass
class TaskPlan:
    """The kinematic part of a task (no simulator): posture, IK, how fast the arm can go."""

    model: PeriodicModel
    surface: Surface
    options: TaskOptions
    arm: RightArm
    posture: TaskPosture
    tracker: ArmIK
    path_xy: np.ndarray                  # (n, 2) x-y path at PATH_PHASES
    max_frequency_hz: float


def plan_task(model: PeriodicModel, surface: Surface, options: TaskOptions,
              source: str = "MODEL", first_pitch: float | None = None) -> TaskPlan:
    """Posture and IK for executing the (placed) path of ``model`` with the platform at
    ``options.base``: the path on the surface, the platform off it, every path point reached
    (the torso leaning as little as it can, ``first_pitch`` tried first), the torso, arm and
    hand :data:`BODY_CLEARANCE` above the surface with the sponge pressed.

    Raises
    ------
    InputError
        What of the above fails, in words.
    """
    path_xy = dof_waveform(model, ("x", "y"))
    surface_z = surface.height_at(path_xy)
    if np.any(np.isnan(surface_z)):
        raise InputError(f"{source}: the placed path leaves the surface {surface.name!r} "
                         "(use --center to move it)")
    base = options.base
    if _on_surface(surface, platform_outline(base, clearance=0.0)).any():
        raise InputError(f"{source}: the platform at x, y, yaw = {base.x:.2f}, {base.y:.2f}, "
                         f"{base.yaw:.2f} stands where the surface {surface.name!r} is")
    nominal = surface_z + NOMINAL_TOOL_DROP
    centre = np.array([*(0.5 * (path_xy.min(axis=0) + path_xy.max(axis=0))), nominal.mean()])
    samples = np.linspace(0, len(path_xy), 12, endpoint=False).astype(int)
    points = np.concatenate([np.column_stack([path_xy[samples], nominal[samples] + dz])
                             for dz in (-REACH_BAND, REACH_BAND)])
    arm = RightArm(base.joint_values(), options.ik)
    pressed = np.column_stack([path_xy[samples], nominal[samples] - PRESS_DEPTH])
    closest, problem, fallback = None, None, None
    for candidate in arm.postures(centre, points, first_pitch):
        if closest is None or candidate.error < closest.error:
            closest = candidate
        if candidate.error > REACH_TOLERANCE:
            continue
        tracker = arm.tracker(candidate)
        postures = _along(candidate, tracker, pressed)
        problem = _body_problem(surface, arm, candidate, tracker, postures, base.yaw,
                                options.sponge.size)
        if problem is None:
            fallback = fallback or (candidate, tracker)
            if candidate.reaches():      # margin from the joint limits too: take it
                fallback = (candidate, tracker)
                break
    if fallback is None:
        problem = problem or (f"the arm cannot reach the movement (off by "
                              f"{100 * closest.error:.1f} cm at its worst point with the "
                              "torso leaning up to 40 deg); move it with --center or scale "
                              "it down")
        raise InputError(f"{source}: {problem}")
    posture, tracker = fallback
    check = slice(0, None, SPEED_CHECK_STRIDE)
    dofs = ("x", "y", "z") if "z" in model.dofs else ("x", "y")
    points = np.column_stack([path_xy, nominal])[check]
    velocities = np.zeros((len(points), 3))
    velocities[:, :len(dofs)] = dof_waveform(model, dofs, PATH_PHASES[check], derivative=1)
    if "z" in model.dofs:
        points[:, 2] = dof_waveform(model, ("z",), PATH_PHASES[check])[:, 0]
    max_omega = phase_rate_limit(tracker, posture, points, velocities,
                                 joint_speed_limit(options))
    return TaskPlan(model, surface, options, arm, posture, tracker, path_xy,
                    max_omega / (2.0 * math.pi))


def joint_speed_limit(options: TaskOptions) -> float:
    """rad/s a planned movement may ask of an arm joint (SPEED_FRACTION of the IK's limit)."""
    return SPEED_FRACTION * options.ik.max_step / options.sim.dt


def _on_surface(surface: Surface, points: np.ndarray) -> np.ndarray:
    """Whether world x-y points (..., 2) are over the surface: inside its grid and on a
    covered cell (the nearest)."""
    position = (points - surface.origin[:2]) / surface.cell
    covered = surface.covered()
    inside = np.all((position >= 0) & (position <= np.array(covered.shape) - 1), axis=-1)
    index = np.rint(position).astype(int)
    return inside & covered[np.clip(index[..., 0], 0, covered.shape[0] - 1),
                            np.clip(index[..., 1], 0, covered.shape[1] - 1)]


def _body_problem(surface: Surface, arm: RightArm, posture: TaskPosture, tracker: ArmIK,
                  postures: np.ndarray, yaw: float, size) -> str | None:
    """What is wrong with the arm at ``postures`` (the sponge off the surface, the body too
    low over it), or None."""
    if not _on_surface(surface, _sponge_points(tracker, posture, postures, yaw, size)).all():
        return (f"the sponge would leave the surface {surface.name!r} (the hand turns along "
                "the path); move the movement with --center")
    gap = _clearance(surface, arm, posture, postures)
    if gap < BODY_CLEARANCE:
        return (f"the arm or torso would touch the surface {surface.name!r} "
                f"({100 * (BODY_CLEARANCE - gap):.1f} cm too low); move the movement with "
                "--center or the robot with --base")
    return None


def _along(posture: TaskPosture, tracker: ArmIK, points: np.ndarray) -> np.ndarray:
    """Arm postures (k + 1, 7): the centre one, then the TCP at each of ``points`` (k, 3)."""
    postures, q = [posture.arm], posture.arm
    for point in points:
        q, _ = tracker.solve(q, point, max_iterations=100)
        postures.append(q)
    return np.array(postures)


def _sponge_points(tracker: ArmIK, posture: TaskPosture, postures: np.ndarray, yaw: float,
                   size) -> np.ndarray:
    """World x-y (m) the sponge (its nominal place in the hand, grown by SPONGE_MARGIN)
    covers at the arm ``postures``: the hand's turn from the centre posture turns it."""
    poses = [tracker.chain.forward(q) for q in postures]
    outline = sponge_outline(np.asarray(NOMINAL_SPONGE_OFFSET), np.asarray(size[:2]), yaw,
                             SPONGE_MARGIN)
    drop = np.full(len(outline), size[2] / 2 - NOMINAL_TOOL_DROP)        # the sponge's centre
    local = np.column_stack([outline, drop]) @ posture.tcp_rotation      # R_ref^T, TCP frame
    return np.concatenate([pose[:3, 3][:2] + (local @ pose[:3, :3].T)[:, :2] for pose in poses])


def _clearance(surface: Surface, arm: RightArm, posture: TaskPosture, postures: np.ndarray
               ) -> float:
    """Smallest height (m) of the torso, arm and hand above the surface at the arm
    ``postures`` (inf when none is over it)."""
    body = np.concatenate([arm.body_points(posture.torso, q) for q in postures])
    over = _on_surface(surface, body[:, :2])
    if not over.any():
        return math.inf
    return float(np.min(body[over, 2] - surface.height_at(body[over, :2])))


def build_task(model: PeriodicModel, surface: Surface, options: TaskOptions,
               source: str = "MODEL", plan: TaskPlan | None = None) -> WipingTask:
    """World and session for executing the (placed) path of ``model`` (``plan``: from
    :func:`plan_task`, which runs here if it is not given).

    Raises
    ------
    InputError
        As :func:`plan_task`.
    """
    plan = plan or plan_task(model, surface, options, source)
    posture, tracker, path_xy = plan.posture, plan.tracker, plan.path_xy
    nominal = surface.height_at(path_xy) + NOMINAL_TOOL_DROP
    centre = np.array([*(0.5 * (path_xy.min(axis=0) + path_xy.max(axis=0))), nominal.mean()])
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
                      float(heights.max() + START_CLEARANCE), path_xy, plan.max_frequency_hz)


#: Placements from the search that are checked with the full IK, best first.
PLACEMENT_CANDIDATES = 16


@dataclass(frozen=True)
class PlacedTask:
    """A model placed on a surface with the platform pose to execute it from."""

    model: PeriodicModel           # x-y moved to the chosen centre
    options: TaskOptions           # with the chosen platform pose
    plan: TaskPlan
    record: dict                   # the choice, JSON-ready (metrics, manifest, logs)


def place_task(model: PeriodicModel, surface: Surface, options: TaskOptions,
               source: str = "MODEL", centre=None, base: BasePose | None = None,
               hip_pitch: float | None = None) -> PlacedTask:
    """Where the path of ``model`` (x-y centred anywhere) goes and how the platform stands.

    With both ``centre`` (m, world) and ``base`` given they are used as they are (and the
    torso leans by ``hip_pitch`` if that works: replay keeps adapt's posture); otherwise
    :func:`~wipelab.sim.placement.choose_placements` ranks placements (the missing one
    free) and the best that passes :func:`plan_task` is taken.

    Raises
    ------
    InputError
        No placement works; the message says what limits it.
    """
    from wipelab.sim.reach import load_reach_map

    path = dof_waveform(model, ("x", "y"))
    relative = path - 0.5 * (path.min(axis=0) + path.max(axis=0))
    if centre is not None and base is not None:
        placed, given = place_model(model, centre), replace(options, base=base)
        plan = plan_task(placed, surface, given, source, hip_pitch)
        return PlacedTask(placed, given, plan, _placement_record("given", plan, centre))
    request = PlacementRequest(relative, dof_waveform(model, ("x", "y"), derivative=1),
                               model.frequency_hz, np.asarray(NOMINAL_SPONGE_OFFSET),
                               np.asarray(options.sponge.size[:2]), surface.wipe_center,
                               centre_scale=(CENTRE_SCALE if surface.wipe_center_given
                                             else LOOSE_CENTRE_SCALE),
                               centre=None if centre is None else np.asarray(centre, float),
                               base=base)
    try:
        candidates = choose_placements(request, surface, load_reach_map(),
                                       joint_speed_limit(options), PLACEMENT_CANDIDATES)
    except PlacementError as error:
        raise InputError(f"{source}: {error}") from None
    reasons = []
    for candidate in candidates:
        placed = place_model(model, candidate.centre)
        chosen = replace(options, base=candidate.base)
        try:
            plan = plan_task(placed, surface, chosen, source, candidate.hip_pitch)
        except InputError as error:
            reasons.append(str(error).removeprefix(f"{source}: "))
            continue
        return PlacedTask(placed, chosen, plan,
                          _placement_record("search", plan, candidate.centre, candidate))
    counts = {reason: reasons.count(reason) for reason in reasons}
    raise InputError(f"{source}: none of the {len(candidates)} best placements passed the "
                     f"full check ({'; '.join(f'{n} x {r}' for r, n in counts.items())})")


def _placement_record(how: str, plan: TaskPlan, centre, candidate: Placement | None = None
                      ) -> dict:
    base = plan.options.base
    record = {"chosen_by": how, "center": [float(v) for v in centre],
              "base": [base.x, base.y, base.yaw],
              "torso": [float(v) for v in plan.posture.torso],
              "joint_margin_rad": plan.posture.margin,
              "max_frequency_hz": plan.max_frequency_hz}
    if candidate is not None:
        record["predicted"] = candidate.describe()
    return record
