"""Stereo vision: from a wiping demonstration on video to the sponge's 3D trajectory.

Notation and frames: camera optical frames are x right, y down, z forward (metres); pixels
(u, v) as in OpenCV; the tracking frame is the world (REP-103: x forward, y left, z up) when
the calibration gives ``T_world_left``, else the left camera's optical frame. A sponge pose
is (x, y, z, yaw): the centre of the sponge box and its rotation about the table normal.

Modules (one concept each):

* :mod:`~wipelab.vision.projection` - pinhole projection with OpenCV's lens distortion;
* :mod:`~wipelab.vision.calibration` - stereo calibration files (OpenCV FileStorage);
* :mod:`~wipelab.vision.stereo_geometry` - triangulation;
* :mod:`~wipelab.vision.sampling`, :mod:`~wipelab.vision.undistortion` - bilinear image
  look-ups, undistorted (pinhole) windows of a frame;
* :mod:`~wipelab.vision.colour_model` - named colours, HSV ranges, the histogram
  back-projection and the linear colour feature;
* :mod:`~wipelab.vision.sponge_box`, :mod:`~wipelab.vision.sponge_likelihood` - the sponge
  as a box and how well a pose explains both images (per-sample loops compiled in
  ``_likelihood_kernel``; the colour blob's moments in ``_moments_kernel``);
* :mod:`~wipelab.vision.particle_filter`, :mod:`~wipelab.vision.pose_refinement` - the
  filter's building blocks and the Newton refinement (compiled);
* :mod:`~wipelab.vision.colour_regions` - the soft colour prior of a named colour, colour
  blobs with sub-pixel centroids;
* :mod:`~wipelab.vision.acquisition` - telling the moving sponge from static things of its
  colour (stereo pairing, motion, static objects);
* :mod:`~wipelab.vision.table_plane`, :mod:`~wipelab.vision.table_stereo` - the plane the
  sponge slides on (dense stereo of the table) and points constrained to it;
* :mod:`~wipelab.vision.static_background` - what each camera sees where the sponge is
  not: still things of its colour (the per-pixel tests compiled in ``_still_kernel``);
* :mod:`~wipelab.vision.region_tracker` - the sponge's colour region in both cameras,
  placed on the plane (needs only the sponge's colour);
* :mod:`~wipelab.vision.box_tracker` - the box refinement: particle filter and Newton fit of
  a sponge box of known dimensions;
* :mod:`~wipelab.vision.tracker` - the tracker the track stage runs (paper Sec. III-A2):
  both of the above, occlusion handling, the per-frame quality;
* :mod:`~wipelab.vision.demonstration_area` - the demonstration area of Fig. 3;
* :mod:`~wipelab.vision.camshift_baseline` - CamShift + triangulation, for comparison;
* :mod:`~wipelab.vision.video_io` - decoding (OpenCV) and H.264 encoding (PyAV);
* :mod:`~wipelab.vision.wiping_motion`, :mod:`~wipelab.vision.synthetic_rig`,
  :mod:`~wipelab.vision.synthetic_scene`, :mod:`~wipelab.vision.synthetic_renderer` - the
  synthetic demonstrations of ``wipelab synth``.
"""

from wipelab.vision.calibration import Camera, StereoCalibration, load_calibration, save_calibration
from wipelab.vision.camshift_baseline import CamShiftBaseline
from wipelab.vision.colour_model import (NAMED_COLOURS, ColourModel, ColourSource, HsvRange,
                                         LinearColourFeature, parse_hsv_range)
from wipelab.vision.demonstration_area import DemonstrationArea, measure_demonstration_area
from wipelab.vision.projection import (invert_transform, make_transform, pixel_rays,
                                       project_points, transform_points)
from wipelab.vision.sponge_box import SpongeBox
from wipelab.vision.stereo_geometry import triangulate_pixels
from wipelab.vision.synthetic_rig import SceneLayout, armar_wide_stereo_calibration
from wipelab.vision.tracker import FrameEstimate, SpongeTracker, TrackerParams
from wipelab.vision.video_io import H264Writer, StereoVideoReader, probe_video
from wipelab.vision.wiping_motion import PATTERNS, WipingMotion, WipingMotionParams

__all__ = [
    "Camera", "StereoCalibration", "load_calibration", "save_calibration", "CamShiftBaseline",
    "NAMED_COLOURS", "ColourModel", "ColourSource", "HsvRange", "LinearColourFeature",
    "parse_hsv_range", "DemonstrationArea", "measure_demonstration_area", "invert_transform",
    "make_transform", "pixel_rays", "project_points", "transform_points", "SpongeBox",
    "triangulate_pixels", "SceneLayout", "armar_wide_stereo_calibration", "FrameEstimate",
    "SpongeTracker", "TrackerParams", "H264Writer", "StereoVideoReader", "probe_video",
    "PATTERNS", "WipingMotion", "WipingMotionParams",
]
