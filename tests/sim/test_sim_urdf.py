"""The shipped ARMAR-IIIb URDF: generated from the sourced table, loads in PyBullet and in two
other parsers (yourdfpy, Rerun's), and all of them agree on the kinematics."""

import numpy as np
import pybullet
import pytest

from wipelab.sim.armar3 import (PLATFORM_JOINTS, RIGHT_ARM_JOINTS, TORSO_JOINTS, armar3b_urdf,
                                armar3b_urdf_path)
from wipelab.sim.kinematics import KinematicChain, parse_urdf_joints

ARM = TORSO_JOINTS + RIGHT_ARM_JOINTS


@pytest.fixture(scope="module")
def urdf_text():
    return armar3b_urdf_path().read_text()


@pytest.fixture(scope="module")
def bullet_robot():
    client = pybullet.connect(pybullet.DIRECT)
    robot = pybullet.loadURDF(str(armar3b_urdf_path()), useFixedBase=True,
                              flags=pybullet.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
    yield client, robot
    pybullet.disconnect(client)


def _bullet_indices(client, robot):
    joints, links = {}, {}
    for j in range(pybullet.getNumJoints(robot, physicsClientId=client)):
        info = pybullet.getJointInfo(robot, j, physicsClientId=client)
        joints[info[1].decode()] = j
        links[info[12].decode()] = j
    return joints, links


def test_shipped_file_is_the_generator_output(urdf_text):
    assert urdf_text == armar3b_urdf()


def test_loads_in_pybullet_with_all_joints_and_sourced_limits(bullet_robot):
    client, robot = bullet_robot
    joints, links = _bullet_indices(client, robot)
    movable = [n for n, j in joints.items()
               if pybullet.getJointInfo(robot, j, physicsClientId=client)[2] != pybullet.JOINT_FIXED]
    # platform 3, hip 3, two arms 7 + 7, head 7
    assert len(movable) == 27
    assert {"ft_sensor_r", "tcp_r_joint", "camera_left_optical_joint"} <= set(joints)
    lower, upper = pybullet.getJointInfo(robot, joints["elbow_r"], physicsClientId=client)[8:10]
    assert (lower, upper) == pytest.approx((-1.9998, 0.9599))
    # zero pose: shoulders 1.375 m up, 0.464 m apart; eyes at 1.6675 m; TCP 0.37 m ahead of
    # the elbow, which is 0.31 m below the shoulder
    shoulder = pybullet.getLinkState(robot, links["shoulder_1_r_link"], physicsClientId=client)[4]
    eye = pybullet.getLinkState(robot, links["camera_left"], physicsClientId=client)[4]
    tcp = pybullet.getLinkState(robot, links["tcp_r"], physicsClientId=client)[4]
    assert shoulder == pytest.approx((0.123, -0.232, 1.375), abs=1e-6)
    assert eye[2] == pytest.approx(1.6675, abs=1e-6)
    assert tcp == pytest.approx((0.123 + 0.02 + 0.37, -0.232 - 0.080233 - 0.007244,
                                 1.375 - 0.299437 + 0.001941), abs=1e-6)


def test_numpy_kinematics_match_pybullet(urdf_text, bullet_robot):
    client, robot = bullet_robot
    joints, links = _bullet_indices(client, robot)
    held = {"platform_x": 0.3, "platform_y": -0.2, "platform_yaw": 0.4}
    chain = KinematicChain(urdf_text, "tcp_r", ARM, held=held)
    for name, value in held.items():
        pybullet.resetJointState(robot, joints[name], value, physicsClientId=client)
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = rng.uniform(chain.lower, chain.upper)
        for name, value in zip(ARM, q):
            pybullet.resetJointState(robot, joints[name], value, physicsClientId=client)
        state = pybullet.getLinkState(robot, links["tcp_r"], computeForwardKinematics=True,
                                      physicsClientId=client)
        pose = chain.forward(q)
        assert pose[:3, 3] == pytest.approx(state[4], abs=1e-6)
        rotation = np.array(pybullet.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        assert np.abs(pose[:3, :3] - rotation).max() < 1e-6


def test_second_parser_yourdfpy_validates_and_agrees(urdf_text):
    yourdfpy = pytest.importorskip("yourdfpy")
    robot = yourdfpy.URDF.load(str(armar3b_urdf_path()), load_meshes=False,
                               build_scene_graph=True)
    assert robot.validate()
    assert len(robot.actuated_joint_names) == 27
    rng = np.random.default_rng(3)
    chain = KinematicChain(urdf_text, "tcp_r", PLATFORM_JOINTS + ARM)
    q = rng.uniform(np.maximum(chain.lower, -1.0), np.minimum(chain.upper, 1.0))
    robot.update_cfg(dict(zip(PLATFORM_JOINTS + ARM, q)))
    pose = robot.get_transform("tcp_r", "world")
    assert np.abs(pose - chain.forward(q)).max() < 1e-9


def test_rerun_urdf_parser_reads_the_same_joints(urdf_text):
    from rerun.urdf import UrdfTree

    tree = UrdfTree.from_file_path(armar3b_urdf_path())
    ours = parse_urdf_joints(urdf_text)
    theirs = {j.name: j for j in tree.joints()}
    assert set(theirs) == set(ours)
    for name in RIGHT_ARM_JOINTS:
        assert (theirs[name].limit_lower, theirs[name].limit_upper) == pytest.approx(
            (ours[name].lower, ours[name].upper))
        assert theirs[name].axis == pytest.approx(tuple(ours[name].axis), abs=1e-6)
