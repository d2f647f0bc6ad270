"""The simulated world: ARMAR-IIIb with a sponge in its right hand, in front of a surface.

PyBullet (DIRECT, headless) steps the physics at ``physics_hz``; the controller runs at
``control_hz`` and calls :meth:`SimWorld.step` once per control period, which runs the
physics sub-steps and averages the wrist F/T sensor over the period (its anti-aliasing). The
sponge's prismatic joint is a spring-damper (PyBullet's PD control with gains k and c, in N/m
and N s/m, evaluated at every physics step). PyBullet quaternions are (x, y, z, w).

Only what the task moves is simulated: the right arm (7 joints), its hand and the sponge.
The loaded copy of the URDF holds the platform at the configured base pose and the torso at
the task's posture (:func:`~wipelab.sim.urdf_edit.freeze_joints`), starts at the torso
(:func:`~wipelab.sim.urdf_edit.subtree`, placed at its pose in the world) and leaves out the
head, the left arm and the massless TCP frame (:func:`~wipelab.sim.urdf_edit.drop_subtrees`):
a physics step then costs about a third of the whole robot's. The logs show the whole robot.

The physics rate follows the tool's speed (:meth:`SimWorld.set_tool_speed`): at most
``max_travel`` (0.75 mm) of TCP travel per physics step, and at least 240 Hz. The sponge is a
light (80 g) rigid block on a spring that slides over the surface on small spheres; with
longer steps the contact solver's penetration recovery adds a normal force that grows with the
speed (at 240 Hz and 0.47 m/s, 2 mm per step, |F| doubled on a bowl's wall, alternating
between ~70 N and ~1 N from one step to the next; at 0.5 mm per step the force no longer
depends on the speed, at 0.75 mm it changes by less than 0.2 N RMS). Learning at a quarter of
the demonstrated speed then runs at 240 Hz, a replay at 3x at 720 Hz.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass

import numpy as np

from wipelab.sim.armar3 import (PLATFORM_JOINTS, RIGHT_ARM_JOINTS, TCP_OFFSET, TORSO_JOINTS,
                                armar3b_urdf_path)
from wipelab.sim.bullet import pybullet
from wipelab.sim.ft_sensor import FTSensorParams, SensorImperfections
from wipelab.rotations import quaternion_xyzw_from_rotation, rotation_from_quaternion_xyzw
from wipelab.sim.kinematics import link_pose, parse_urdf_joints
from wipelab.sim.sponge import Grasp, SpongeParams, collision_spheres, tcp_to_sponge
from wipelab.sim.surfaces import Surface
from wipelab.sim.urdf_edit import attach_compliant_box, drop_subtrees, freeze_joints, subtree

#: Joints simulated as joints, in the order of the controller's arm q.
SIMULATED_JOINTS = RIGHT_ARM_JOINTS
#: Root link of the simulated part (fixed in the world at its pose).
SIMULATED_ROOT = "torso"
#: Name of the sponge link and of its spring joint in the loaded URDF.
SPONGE_LINK = "sponge"
SPONGE_JOINT = "sponge_compression"
#: Radius (m) of the spheres that make the sponge's collision shape.
SPONGE_SPHERE_RADIUS = 0.008
#: Subtrees below the root left out of the physics: head and left arm (they stand still, far
#: from the task) and the TCP frame (no mass; its pose follows from the hand's).
UNSIMULATED_SUBTREES = ("neck_1_pitch", "shoulder_1_l", "tcp_r_joint")
#: The fixed joint carrying the F/T sensor, and the link it measures (its frame = sensor frame).
FT_JOINT = "ft_sensor_r"
#: The link the sensor measures.
HAND_LINK = "hand_r"
#: Time constant (s) of the joint servos' position loop (PyBullet's position gain is per
#: physics step: gain = 1 / (time constant * physics_hz)).
SERVO_TIME_CONSTANT = 1.0 / 120.0
#: Largest force (N) of the sponge's spring-damper.
SPRING_FORCE_LIMIT = 1000.0


def _matrix(quaternion_xyzw) -> np.ndarray:
    """PyBullet quaternion (x, y, z, w) -> rotation matrix (3, 3), in C."""
    return np.array(pybullet.getMatrixFromQuaternion(quaternion_xyzw)).reshape(3, 3)


@dataclass(frozen=True)
class SimConfig:
    """Rates of the simulation (the physics rate follows the tool's speed, see above)."""

    physics_hz: float = 240.0   # Hz: lowest physics rate (>= 240, a multiple of control_hz)
    max_travel: float = 0.00075  # m: most TCP travel per physics step
    control_hz: float = 120.0   # Hz: controller rate (>= 100)
    solver_iterations: int = 5   # PyBullet constraint solver iterations per step

    def __post_init__(self):
        if self.physics_hz < 240 or self.control_hz < 100:
            raise ValueError("physics_hz must be >= 240 and control_hz >= 100")
        ratio = self.physics_hz / self.control_hz
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError("physics_hz must be an integer multiple of control_hz")
        if not self.max_travel > 0:
            raise ValueError("max_travel must be > 0")

    def substeps(self, speed: float = 0.0) -> int:
        """Physics steps per control period for a TCP moving at up to ``speed`` (m/s): the
        fewest, at least physics_hz / control_hz, with at most ``max_travel`` per step."""
        return max(int(round(self.physics_hz / self.control_hz)),
                   math.ceil(speed / (self.max_travel * self.control_hz) - 1e-9))

    @property
    def dt(self) -> float:
        """Control period (s)."""
        return 1.0 / self.control_hz


@dataclass(frozen=True)
class BasePose:
    """Where the robot's platform stands: x, y (m, world) and yaw (rad)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def joint_values(self) -> dict[str, float]:
        return dict(zip(PLATFORM_JOINTS, (self.x, self.y, self.yaw)))


@dataclass
class StepResult:
    """What one control period produced (true values; the controller only sees ``wrench``)."""

    q: np.ndarray                  # (7,) measured arm joint positions (rad), SIMULATED_JOINTS
    qd: np.ndarray                 # (7,) measured arm joint velocities (rad/s)
    wrench: np.ndarray             # (6,) F/T reading (N, N m), sensor frame, bias + noise
    sensor_rotation: np.ndarray    # (3, 3) sensor orientation in the world (from kinematics)
    sponge_force: float            # N: true total normal force surface -> sponge (period mean)
    hand_force: float              # N: same for any robot link but the sponge
    compression: float             # m: true sponge compression
    tcp: np.ndarray                # (3,) actual TCP position (m, world)
    tcp_rotation: np.ndarray       # (3, 3) actual TCP orientation in the world
    sponge_position: np.ndarray    # (3,) sponge centre (m, world)
    sponge_quaternion: np.ndarray  # (4,) sponge orientation (x, y, z, w)


def surface_body(client: int, surface: Surface) -> int:
    """Create the surface as a static PyBullet body; returns its id."""
    if surface.kind == "flat":
        # a 4 cm thick box whose top face passes through the wipe centre at the table height
        tilt_x, tilt_y = surface.tilt
        half = np.array([(surface.heights.shape[0] - 1) * surface.cell / 2,
                         (surface.heights.shape[1] - 1) * surface.cell / 2, 0.02])
        rotation = pybullet.getQuaternionFromEuler((tilt_x, tilt_y, 0.0))
        normal = rotation_from_quaternion_xyzw(rotation)[:, 2]
        centre_xy = surface.origin[:2] + half[:2]
        top = np.array([*centre_xy, surface.height_at(centre_xy)])
        shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half.tolist(),
                                              physicsClientId=client)
        visual = pybullet.createVisualShape(pybullet.GEOM_BOX, halfExtents=half.tolist(),
                                            rgbaColor=(0.7, 0.55, 0.4, 1), physicsClientId=client)
        return pybullet.createMultiBody(0, shape, visual, (top - normal * half[2]).tolist(),
                                        rotation, physicsClientId=client)
    if surface.kind == "mesh":
        shape = pybullet.createCollisionShape(pybullet.GEOM_MESH, fileName=str(surface.mesh_file),
                                              flags=pybullet.GEOM_FORCE_CONCAVE_TRIMESH,
                                              physicsClientId=client)
        return pybullet.createMultiBody(0, shape, -1, [0, 0, 0], physicsClientId=client)
    # a Bullet heightfield: centred on its body in x-y, and in z between its lowest and
    # highest point; data[i + j nx] = heights[i, j]; internal-edge filtering keeps the sponge
    # from catching on the edges between its triangles
    heights = surface.heights
    nx, ny = heights.shape
    shape = pybullet.createCollisionShape(
        pybullet.GEOM_HEIGHTFIELD, meshScale=[surface.cell, surface.cell, 1.0],
        heightfieldData=heights.ravel(order="F").tolist(), numHeightfieldRows=nx,
        numHeightfieldColumns=ny, flags=pybullet.GEOM_CONCAVE_INTERNAL_EDGE,
        physicsClientId=client)
    centre = surface.origin + np.array([(nx - 1) * surface.cell / 2, (ny - 1) * surface.cell / 2,
                                        (heights.min() + heights.max()) / 2])
    return pybullet.createMultiBody(0, shape, -1, centre.tolist(), physicsClientId=client)


class SimWorld:
    """ARMAR-IIIb, its sponge and a surface in a headless PyBullet client.

    Parameters
    ----------
    surface : Surface
    torso : array, shape (3,)
        Torso joint values (rad), held during the task.
    arm : array, shape (7,)
        Right-arm joint values (rad) at the start.
    reference_rotation : array, shape (3, 3)
        R_ref of the grasp (the TCP orientation at the centre of the task).
    base, sponge, grasp, sensor, config : see their classes.
    seed : int
        Seeds the sensor's bias and noise.
    """

    def __init__(self, surface: Surface, torso, arm, reference_rotation: np.ndarray,
                 base: BasePose = BasePose(), sponge: SpongeParams = SpongeParams(),
                 grasp: Grasp = Grasp(), sensor: FTSensorParams = FTSensorParams(),
                 config: SimConfig = SimConfig(), seed: int = 0):
        self.surface, self.base, self.sponge, self.grasp, self.config = (surface, base, sponge,
                                                                          grasp, config)
        self.urdf_text = armar3b_urdf_path().read_text()
        self.torso = np.asarray(torso, dtype=float).copy()
        self.tcp_from_sponge = tcp_to_sponge(grasp, np.asarray(reference_rotation), base.yaw)
        hand_to_tcp = np.eye(4)
        hand_to_tcp[0, 3] = TCP_OFFSET
        held = {**base.joint_values(), **dict(zip(TORSO_JOINTS, self.torso))}
        text = freeze_joints(self.urdf_text, SIMULATED_JOINTS, held)
        text = drop_subtrees(subtree(text, SIMULATED_ROOT), UNSIMULATED_SUBTREES)
        text = attach_compliant_box(text, HAND_LINK, hand_to_tcp @ self.tcp_from_sponge,
                                    SPONGE_LINK, sponge.size, sponge.mass,
                                    sponge.max_compression,
                                    collision_spheres(sponge.size, SPONGE_SPHERE_RADIUS),
                                    SPONGE_SPHERE_RADIUS)
        root = link_pose(self.urdf_text, SIMULATED_ROOT, held)
        self.client = pybullet.connect(pybullet.DIRECT)
        c = self.client
        pybullet.setGravity(0, 0, -9.81, physicsClientId=c)
        pybullet.setPhysicsEngineParameter(numSolverIterations=config.solver_iterations,
                                           deterministicOverlappingPairs=1,
                                           jointFeedbackMode=pybullet.JOINT_FEEDBACK_IN_JOINT_FRAME,
                                           physicsClientId=c)
        handle, path = tempfile.mkstemp(suffix=".urdf")
        try:
            with os.fdopen(handle, "w") as f:
                f.write(text)
            self.robot = pybullet.loadURDF(
                path, basePosition=root[:3, 3].tolist(),
                baseOrientation=quaternion_xyzw_from_rotation(root[:3, :3]).tolist(),
                useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)
        finally:
            os.unlink(path)
        self.surface_id = surface_body(c, surface)
        by_name = {}
        for j in range(pybullet.getNumJoints(self.robot, physicsClientId=c)):
            info = pybullet.getJointInfo(self.robot, j, physicsClientId=c)
            by_name[info[1].decode()] = j
            by_name["link:" + info[12].decode()] = j
        self.joint_ids = [by_name[n] for n in SIMULATED_JOINTS]
        self.sponge_joint = by_name[SPONGE_JOINT]
        self.sponge_link = by_name["link:" + SPONGE_LINK]
        self.ft_joint = by_name[FT_JOINT]
        self.hand_link = by_name["link:" + HAND_LINK]
        self._pose_links = [self.hand_link, self.sponge_link]
        self._state_joints = self.joint_ids + [self.sponge_joint]
        joints = parse_urdf_joints(self.urdf_text)
        self.effort = np.array([joints[n].effort for n in SIMULATED_JOINTS])
        pybullet.changeDynamics(self.robot, self.sponge_link, lateralFriction=surface.friction,
                                rollingFriction=0.0, spinningFriction=0.0, physicsClientId=c)
        pybullet.changeDynamics(self.surface_id, -1, lateralFriction=1.0, physicsClientId=c)
        pybullet.setJointMotorControl2(self.robot, self.sponge_joint, pybullet.VELOCITY_CONTROL,
                                       force=0.0, physicsClientId=c)
        pybullet.setJointMotorControl2(self.robot, self.sponge_joint, pybullet.PD_CONTROL,
                                       targetPosition=0.0, targetVelocity=0.0,
                                       positionGain=sponge.stiffness, velocityGain=sponge.damping,
                                       force=SPRING_FORCE_LIMIT, physicsClientId=c)
        pybullet.enableJointForceTorqueSensor(self.robot, self.ft_joint, True, physicsClientId=c)
        start = np.asarray(arm, dtype=float)
        for j, value in zip(self.joint_ids, start):
            pybullet.resetJointState(self.robot, j, value, physicsClientId=c)
        self._effort = self.effort.tolist()
        self._velocity_gains = [1.0] * len(start)
        self._hold_velocity = [0.0] * len(start)
        self.set_tool_speed(0.0)
        self.targets = start.copy()
        self.command(start)
        self.imperfections = SensorImperfections(sensor, np.random.default_rng(seed))
        self.time = 0.0
        #: Force (3,) (N, world) applied to the sponge's centre at every physics step (None:
        #: none): a disturbance, or a known load for checking the F/T sensor.
        self.external_force: np.ndarray | None = None

    def close(self) -> None:
        """Disconnect the PyBullet client (idempotent)."""
        if self.client is not None:
            pybullet.disconnect(self.client)
            self.client = None

    def __enter__(self) -> SimWorld:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def set_tool_speed(self, speed: float) -> None:
        """Step the physics fast enough for a TCP moving at up to ``speed`` (m/s) (see
        :meth:`SimConfig.substeps`)."""
        self.substeps = self.config.substeps(speed)
        self.physics_hz = self.substeps * self.config.control_hz
        pybullet.setPhysicsEngineParameter(fixedTimeStep=1.0 / self.physics_hz,
                                           physicsClientId=self.client)
        # position loop: time constant SERVO_TIME_CONSTANT whatever the physics rate
        gains = [1.0 / (SERVO_TIME_CONSTANT * self.physics_hz)] * len(self.joint_ids)
        self._servo = dict(forces=self._effort, positionGains=gains,
                           velocityGains=self._velocity_gains, physicsClientId=self.client)
        self._fractions = np.arange(1, self.substeps + 1)[:, None] / self.substeps

    def command(self, q, velocity=None) -> None:
        """Arm joint position targets (7,) (rad), SIMULATED_JOINTS order, for the end of the
        next control period, and the joint velocities (7,) (rad/s) of the planned motion.

        As a robot's joint controller does, :meth:`step` interpolates from the previous
        targets to these linearly at the physics rate, and the servos get ``velocity`` as
        feed-forward (zero if None): they follow the planned motion without lag, and
        corrections outside it (the force feedback's) through their position loop.
        """
        self._start = self.targets
        self.targets = np.array(q, dtype=float)
        self._velocity = (self._hold_velocity if velocity is None
                          else np.asarray(velocity, dtype=float).tolist())

    def step(self) -> StepResult:
        """Run one control period of physics; return the measurements at its end."""
        c, robot, ft_joint = self.client, self.robot, self.ft_joint
        surface_id, sponge_link = self.surface_id, self.sponge_link
        joints, velocity, servo = self.joint_ids, self._velocity, self._servo
        set_motors, step_simulation = pybullet.setJointMotorControlArray, pybullet.stepSimulation
        get_joint_state, get_contact_points = pybullet.getJointState, pybullet.getContactPoints
        control = pybullet.POSITION_CONTROL
        # the servos' targets at each physics step: linear from the last targets to the new
        targets = (self._start + self._fractions * (self.targets - self._start)).tolist()
        readings = []
        sponge_force = hand_force = 0.0
        push = None if self.external_force is None else \
            np.asarray(self.external_force, dtype=float).tolist()
        for target in targets:
            set_motors(robot, joints, control, targetPositions=target, targetVelocities=velocity,
                       **servo)
            if push is not None:
                centre = pybullet.getLinkState(robot, sponge_link, physicsClientId=c)[0]
                pybullet.applyExternalForce(robot, sponge_link, push, centre, pybullet.WORLD_FRAME,
                                            physicsClientId=c)
            step_simulation(physicsClientId=c)
            readings.append(get_joint_state(robot, ft_joint, physicsClientId=c)[2])
            for point in get_contact_points(robot, surface_id, physicsClientId=c):
                if point[3] == sponge_link:
                    sponge_force += point[9]
                else:
                    hand_force += point[9]
        self.time += self.config.dt
        self._start = self.targets          # reached: hold them until the next command
        self._velocity = self._hold_velocity
        states = pybullet.getJointStates(robot, self._state_joints, physicsClientId=c)
        hand, sponge = pybullet.getLinkStates(robot, self._pose_links, physicsClientId=c)
        hand_rotation = _matrix(hand[5])
        n = len(targets)
        wrench = np.array(readings).sum(axis=0) / n
        return StepResult(q=np.array([s[0] for s in states[:-1]]),
                          qd=np.array([s[1] for s in states[:-1]]),
                          wrench=self.imperfections(self.reading_convention(wrench)),
                          sensor_rotation=hand_rotation,
                          sponge_force=sponge_force / n, hand_force=hand_force / n,
                          compression=states[-1][0],
                          tcp=np.array(hand[4]) + TCP_OFFSET * hand_rotation[:, 0],
                          tcp_rotation=hand_rotation,
                          sponge_position=np.array(sponge[4]),
                          sponge_quaternion=np.array(sponge[5]))

    @staticmethod
    def reading_convention(reaction: np.ndarray) -> np.ndarray:
        """PyBullet's joint reaction (joint frame) -> the sensor's convention (the wrench the
        wrist exerts on the payload, sensor frame)."""
        return np.asarray(reaction, dtype=float)

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Actual TCP position (3,) (m) and orientation (3, 3) in the world (the TCP frame is
        the hand's, moved by TCP_OFFSET along its x axis)."""
        state = pybullet.getLinkState(self.robot, self.hand_link, physicsClientId=self.client)
        rotation = _matrix(state[5])
        return np.array(state[4]) + TCP_OFFSET * rotation[:, 0], rotation
