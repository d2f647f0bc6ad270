"""ARMAR-IIIb's wide-angle stereo pair looking down at a table: the rig synth renders with.

Intrinsics and distortion are the IVT calibration of the ARMAR wide-angle cameras
(640x480, 4 mm lens; see shared/reference/armar3_kinematics.md). The relative rotation of
the two cameras is the one of that calibration; the baseline is 90 mm (the kinematic model's
pan axes are 93 mm apart, the IVT centres 84 mm). The head is pitched so that the table top
is 0.5-0.8 m from the cameras.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.projection import invert_transform, make_transform

#: IVT calibration of the ARMAR wide-angle pair (files/camera_armar_640x480_4mm.txt).
ARMAR_WIDE_K_LEFT = np.array([[532.4691, 0.0, 338.1229], [0.0, 530.2948, 238.8943], [0, 0, 1]])
ARMAR_WIDE_D_LEFT = np.array([-0.4175221, 0.1891710, 0.00039144, -0.00118642, 0.0])
ARMAR_WIDE_K_RIGHT = np.array([[530.4126, 0.0, 317.4682], [0.0, 528.4988, 227.5575], [0, 0, 1]])
ARMAR_WIDE_D_RIGHT = np.array([-0.4129819, 0.1751222, 0.00062956, -0.00090676, 0.0])
#: Right-from-left rotation of the IVT calibration (Rodrigues vector, rad).
ARMAR_WIDE_ROTVEC = np.deg2rad([1.31978, 0.87914, -1.50776])
#: Direction of the right camera's translation in the IVT calibration (normalised below).
ARMAR_WIDE_T_DIRECTION = np.array([-83.58223, -3.58502, 3.95644])


@dataclass(frozen=True)
class SceneLayout:
    """Where things are, world frame (REP-103, base_link on the floor), metres.

    Attributes
    ----------
    table_height : float
        z of the table top.
    table_x, table_y : tuple of float
        Extent of the table top (min, max).
    left_camera_position : tuple of float
        Optical centre of the left camera.
    look_at : tuple of float
        Point the left camera's optical axis passes through.
    baseline : float
        Distance between the optical centres.
    demonstrator_x : float
        x of the demonstrator's body (a vertical plane behind the far table edge).
    image_size : tuple of int
        (width, height), pixels.
    """

    table_height: float = 0.90
    table_x: tuple[float, float] = (0.40, 1.15)
    table_y: tuple[float, float] = (-0.60, 0.60)
    left_camera_position: tuple[float, float, float] = (0.30, 0.045, 1.45)
    look_at: tuple[float, float, float] = (0.70, 0.02, 0.90)
    baseline: float = 0.090
    demonstrator_x: float = 1.30
    image_size: tuple[int, int] = (640, 480)


def look_at_rotation(position: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Rotation (3, 3) whose columns are an optical frame's axes in the world frame.

    z points from ``position`` to ``target``, x to the right (horizontal), y down.
    """
    z = np.asarray(target, float) - np.asarray(position, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def armar_wide_stereo_calibration(layout: SceneLayout = SceneLayout()) -> StereoCalibration:
    """The calibration of the synthetic rig, world pose included (``T_world_left``)."""
    R = cv2.Rodrigues(ARMAR_WIDE_ROTVEC.reshape(3, 1))[0]
    T = ARMAR_WIDE_T_DIRECTION / np.linalg.norm(ARMAR_WIDE_T_DIRECTION) * layout.baseline
    T_world_left = make_transform(look_at_rotation(layout.left_camera_position, layout.look_at),
                                  layout.left_camera_position)
    return StereoCalibration(layout.image_size, ARMAR_WIDE_K_LEFT.copy(), ARMAR_WIDE_D_LEFT.copy(),
                             ARMAR_WIDE_K_RIGHT.copy(), ARMAR_WIDE_D_RIGHT.copy(), R, T,
                             T_world_left)


def camera_poses_in_world(calibration: StereoCalibration) -> tuple[np.ndarray, np.ndarray]:
    """``(T_world_left, T_world_right)``, each (4, 4), of a calibration with a world pose."""
    T_world_left = calibration.T_world_left
    return T_world_left, T_world_left @ invert_transform(calibration.right.T_cam_ref)
