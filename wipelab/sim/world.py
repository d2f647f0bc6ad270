"""The simulated world: ARMAR-IIIb with a sponge in its right hand, in front of a surface.

PyBullet (DIRECT, headless) steps the physics at ``physics_hz``; the controller runs at
``control_hz`` and calls :meth:`SimWorld.step` once per control period, which runs the
physics sub-steps, makes the sponge's prismatic joint a spring-damper and averages the wrist
F/T sensor over the period (its anti-aliasing). PyBullet quaternions are (x, y, z, w).

Only the joints the task moves are simulated as joints: the torso (3) and the right arm (7).
The loaded copy of the URDF holds the platform fixed at the configured base pose
(:func:`~wipelab.sim.urdf_edit.freeze_joints`) and leaves out the head and the left arm,
which stand still far above the table and touch nothing
(:func:`~wipelab.sim.urdf_edit.drop_subtrees`); this makes a control period about twice
cheaper. The logs show the whole robot.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass

import numpy as np
from wipelab.sim.bullet import pybullet

from wipelab.sim.armar3 import (PLATFORM_JOINTS, RIGHT_ARM_JOINTS, TCP_OFFSET, TORSO_JOINTS,
                                armar3b_urdf_path)
from wipelab.sim.ft_sensor import FTSensorParams, SensorImperfections
from wipelab.sim.kinematics import parse_urdf_joints, rotation_from_quaternion_xyzw
from wipelab.sim.sponge import Grasp, SpongeParams, collision_spheres, tcp_to_sponge
from wipelab.sim.surfaces import Surface
from wipelab.sim.urdf_edit import attach_compliant_box, drop_subtrees, freeze_joints

#: Joints simulated as joints, in the order of the controller's q: torso then right arm.
ACTIVE_JOINTS = TORSO_JOINTS + RIGHT_ARM_JOINTS
#: Name of the sponge link and of its spring joint in the loaded URDF.
SPONGE_LINK = "sponge"
SPONGE_JOINT = "sponge_compression"
#: Radius (m) of the spheres that make the sponge's collision shape.
SPONGE_SPHERE_RADIUS = 0.008
#: Subtrees left out of the physics (they stand still, far from the task).
UNSIMULATED_SUBTREES = ("neck_1_pitch", "shoulder_1_l")
#: The fixed joint carrying the F/T sensor, and the link it measures (its frame = sensor frame).
FT_JOINT = "ft_sensor_r"


def _matrix(quaternion_xyzw) -> np.ndarray:
    """PyBullet quaternion (x, y, z, w) -> rotation matrix (3, 3), in C."""
    return np.array(pybullet.getMatrixFromQuaternion(quaternion_xyzw)).reshape(3, 3)


@dataclass(frozen=True)
class SimConfig:
    """Rates of the simulation."""

    physics_hz: float = 240.0   # Hz: PyBullet time step 1 / physics_hz (>= 240)
    control_hz: float = 120.0   # Hz: controller rate (>= 100); physics_hz / control_hz integer
    solver_iterations: int = 30  # PyBullet constraint solver iterations per step

    def __post_init__(self):
        if self.physics_hz < 240 or self.control_hz < 100:
            raise ValueError("physics_hz must be >= 240 and control_hz >= 100")
        ratio = self.physics_hz / self.control_hz
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError("physics_hz must be an integer multiple of control_hz")

    @property
    def substeps(self) -> int:
        return int(round(self.physics_hz / self.control_hz))

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

    q: np.ndarray                  # (10,) measured joint positions (rad), ACTIVE_JOINTS order
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
        Torso joint values (rad) at which the arm starts (the IK may move them).
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
        self.tcp_from_sponge = tcp_to_sponge(grasp, np.asarray(reference_rotation))
        hand_to_tcp = np.eye(4)
        hand_to_tcp[0, 3] = TCP_OFFSET
        held = base.joint_values()
        text = drop_subtrees(freeze_joints(self.urdf_text, ACTIVE_JOINTS, held),
                             UNSIMULATED_SUBTREES)
        text = attach_compliant_box(text, "hand_r", hand_to_tcp @ self.tcp_from_sponge,
                                    SPONGE_LINK, sponge.size, sponge.mass,
                                    sponge.max_compression,
                                    collision_spheres(sponge.size, SPONGE_SPHERE_RADIUS),
                                    SPONGE_SPHERE_RADIUS)
        self.client = pybullet.connect(pybullet.DIRECT)
        c = self.client
        pybullet.setGravity(0, 0, -9.81, physicsClientId=c)
        pybullet.setPhysicsEngineParameter(fixedTimeStep=1.0 / config.physics_hz,
                                           numSolverIterations=config.solver_iterations,
                                           deterministicOverlappingPairs=1,
                                           jointFeedbackMode=pybullet.JOINT_FEEDBACK_IN_JOINT_FRAME,
                                           physicsClientId=c)
        handle, path = tempfile.mkstemp(suffix=".urdf")
        try:
            with os.fdopen(handle, "w") as f:
                f.write(text)
            self.robot = pybullet.loadURDF(path, useFixedBase=True,
                                           flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
                                           physicsClientId=c)
        finally:
            os.unlink(path)
        self.surface_id = surface_body(c, surface)
        by_name = {}
        for j in range(pybullet.getNumJoints(self.robot, physicsClientId=c)):
            info = pybullet.getJointInfo(self.robot, j, physicsClientId=c)
            by_name[info[1].decode()] = j
            by_name["link:" + info[12].decode()] = j
        self.joint_ids = [by_name[n] for n in ACTIVE_JOINTS]
        self.sponge_joint = by_name[SPONGE_JOINT]
        self.sponge_link = by_name["link:" + SPONGE_LINK]
        self.ft_joint = by_name[FT_JOINT]
        self.hand_link = by_name["link:hand_r"]
        self.tcp_link = by_name["link:tcp_r"]
        self._pose_links = [self.hand_link, self.tcp_link, self.sponge_link]
        joints = parse_urdf_joints(self.urdf_text)
        self.effort = np.array([joints[n].effort for n in ACTIVE_JOINTS])
        pybullet.changeDynamics(self.robot, self.sponge_link, lateralFriction=surface.friction,
                                rollingFriction=0.0, spinningFriction=0.0, physicsClientId=c)
        pybullet.changeDynamics(self.surface_id, -1, lateralFriction=1.0, physicsClientId=c)
        pybullet.setJointMotorControl2(self.robot, self.sponge_joint, pybullet.VELOCITY_CONTROL,
                                       force=0.0, physicsClientId=c)
        pybullet.enableJointForceTorqueSensor(self.robot, self.ft_joint, True, physicsClientId=c)
        start = np.concatenate([np.asarray(torso, dtype=float), np.asarray(arm, dtype=float)])
        for j, value in zip(self.joint_ids, start):
            pybullet.resetJointState(self.robot, j, value, physicsClientId=c)
        self.targets = start.copy()
        self.command(start)
        self.imperfections = SensorImperfections(sensor, np.random.default_rng(seed))
        self.time = 0.0
        #: Force (3,) (N, world) applied to the sponge's centre at every physics step: a
        #: disturbance, or a known load for checking the F/T sensor.
        self.external_force = np.zeros(3)

    def close(self) -> None:
        """Disconnect the PyBullet client (idempotent)."""
        if self.client is not None:
            pybullet.disconnect(self.client)
            self.client = None

    def __enter__(self) -> SimWorld:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def command(self, q, velocity=None) -> None:
        """Joint position targets (10,) (rad), ACTIVE_JOINTS order, with the joint velocities
        (10,) (rad/s) of the commanded motion as feed-forward (zero if None): the joint
        servos then follow a moving target without the lag of a pure position loop."""
        self.targets = np.asarray(q, dtype=float).copy()
        velocity = [0.0] * len(q) if velocity is None else np.asarray(velocity, float).tolist()
        pybullet.setJointMotorControlArray(self.robot, self.joint_ids, pybullet.POSITION_CONTROL,
                                           targetPositions=self.targets.tolist(),
                                           targetVelocities=velocity,
                                           forces=self.effort.tolist(),
                                           positionGains=[0.5] * len(q),
                                           velocityGains=[1.0] * len(q),
                                           physicsClientId=self.client)

    def step(self) -> StepResult:
        """Run one control period of physics; return the measurements at its end."""
        c, robot, sponge_joint, ft_joint = self.client, self.robot, self.sponge_joint, self.ft_joint
        k, damping = self.sponge.stiffness, self.sponge.damping
        wrench = [0.0] * 6
        sponge_force = hand_force = 0.0
        n = self.config.substeps
        for _ in range(n):
            position, velocity = pybullet.getJointState(robot, sponge_joint,
                                                        physicsClientId=c)[:2]
            pybullet.setJointMotorControl2(robot, sponge_joint, pybullet.TORQUE_CONTROL,
                                           force=-k * position - damping * velocity,
                                           physicsClientId=c)
            if self.external_force.any():
                centre = pybullet.getLinkState(robot, self.sponge_link, physicsClientId=c)[0]
                pybullet.applyExternalForce(robot, self.sponge_link, self.external_force.tolist(),
                                            centre, pybullet.WORLD_FRAME, physicsClientId=c)
            pybullet.stepSimulation(physicsClientId=c)
            reaction = pybullet.getJointState(robot, ft_joint, physicsClientId=c)[2]
            wrench = [a + b for a, b in zip(wrench, reaction)]
            for point in pybullet.getContactPoints(robot, self.surface_id, physicsClientId=c):
                if point[3] == self.sponge_link:
                    sponge_force += point[9]
                else:
                    hand_force += point[9]
        self.time += self.config.dt
        states = pybullet.getJointStates(robot, self.joint_ids + [sponge_joint],
                                         physicsClientId=c)
        hand, tcp, sponge = pybullet.getLinkStates(robot, self._pose_links, physicsClientId=c)
        return StepResult(q=np.array([s[0] for s in states[:-1]]),
                          wrench=self.imperfections(self.reading_convention(np.array(wrench) / n)),
                          sensor_rotation=_matrix(hand[5]),
                          sponge_force=sponge_force / n, hand_force=hand_force / n,
                          compression=float(states[-1][0]),
                          tcp=np.array(tcp[4]), tcp_rotation=_matrix(tcp[5]),
                          sponge_position=np.array(sponge[4]), sponge_quaternion=np.array(sponge[5]))

    @staticmethod
    def reading_convention(reaction: np.ndarray) -> np.ndarray:
        """PyBullet's joint reaction (joint frame) -> the sensor's convention (the wrench the
        wrist exerts on the payload, sensor frame)."""
        return np.asarray(reaction, dtype=float)

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Actual TCP position (3,) (m) and orientation (3, 3) in the world."""
        state = pybullet.getLinkState(self.robot, self.tcp_link, physicsClientId=self.client)
        return np.array(state[4]), _matrix(state[5])
