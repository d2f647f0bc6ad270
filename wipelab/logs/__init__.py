"""Logging layer: one MCAP file and one Rerun recording per stage run, side by side.

Every stage writes ``<out>/<stage>.mcap`` (for Foxglove, MCAP/ROS tooling, long-term
storage) and ``<out>/<stage>.rrd`` (for the Rerun Viewer) through
:class:`StageRecorder`; :mod:`wipelab.logs.reader` reads both back.

Naming scheme
-------------
* **Topics are entity paths.** Every record is logged under one ROS-style name,
  ``/<area>/<thing>[/<detail>]`` (lower case, ``_`` between words, units as a suffix
  where a number has one, e.g. ``/oscillators/frequency_hz``), which is both the MCAP
  topic and the Rerun entity path. Areas: ``/input`` (what the stage read),
  ``/oscillators`` and ``/dmp`` (learning), ``/stereo/left|right/...`` (cameras: ``.../image``
  or ``.../video``, ``.../calibration``), ``/track`` (sponge tracking), ``/robot`` (joint
  states, TCP), ``/adapt`` and ``/replay`` (force learning, execution), ``/model``
  (learned models). The one exception: all frame transforms share the MCAP topic ``/tf``
  and Rerun puts the transform of frame ``<child>`` on ``/tf/<child>``.
* **Frames** are REP-103: ``world`` (x forward, y left, z up), ``base_link``, camera optical
  frames ``<camera>_optical`` (x right, y down, z forward). MCAP messages carry them as
  ``frame_id``; Rerun uses the same names as transform frames, except that ``world`` is
  Rerun's root frame (so entities logged without a frame are in the world), and a camera
  image is in ``<frame_id>_image_plane`` (the Pinhole's child frame, as ``rerun mcap
  convert`` names it).
* **Time** is data time: seconds since the start of the recording on the Rerun duration
  timeline ``time`` (stages may add a ``frame`` sequence timeline), the same clock in
  nanoseconds as MCAP ``log_time`` and ``publish_time``. Nothing depends on the wall clock:
  the same inputs and parameters give byte-identical ``.mcap`` and ``.rrd`` files.
* **MCAP schemas.** Foxglove's well-known protobuf schemas under their exact names where
  one fits: ``foxglove.FrameTransforms`` (``/tf``), ``foxglove.PoseInFrame``,
  ``foxglove.CameraCalibration``, ``foxglove.CompressedImage``, ``foxglove.CompressedVideo``,
  ``foxglove.PointCloud`` (points), ``foxglove.SceneUpdate`` (line strips, arrows, boxes and
  other solids on frames; entity id = topic unless given), ``foxglove.ImageAnnotations``
  (drawings over a camera's images), ``foxglove.Log`` (events). Everything else is JSON
  (message encoding ``json``) with a named JSON Schema (schema encoding ``jsonschema``):
  ``wipelab.Scalars`` for time series (one message per time stamp, ``{name: value}``, names
  of ``[A-Za-z0-9_]`` so that Foxglove plots ``/topic.name``), ``wipelab.State`` (a state
  per change), ``wipelab.PhaseCurves`` (curves over one period) and stage-specific
  ``wipelab.*`` names. Chunks are ZSTD-compressed and indexed (chunk and message indexes,
  statistics, summary offsets). Metadata records: ``wipelab.stage`` (stage, recording
  id), ``wipelab.parameters`` (one key per parameter, JSON value) and ``wipelab.inputs``
  (``<role>.sha256``, ``<role>.file``). Attachments hold files such as calibrations.
* **Rerun recordings** have application id ``wipelab_<stage>`` (the viewer keeps one layout
  per application id, so stages opened together keep theirs) and a recording id derived
  from the stage, its parameters and input hashes; they open with the stage's default
  blueprint. Quantities over the phase of the movement are drawn as charts in 2D views
  (:mod:`wipelab.logs.phase_chart`); colours come from :mod:`wipelab.logs.palette`.
"""

from wipelab.logs.reader import (mcap_attachments, mcap_input_hashes, mcap_metadata,
                                 mcap_parameters, mcap_topics, point_cloud_points,
                                 read_mcap_scalars, read_mcap_topic, read_rrd_scalars,
                                 rrd_blueprint_views, rrd_column, rrd_record_batches)
from wipelab.logs.recorder import (TF_TOPIC, TIMELINE, WORLD_FRAME, StageRecorder, application_id,
                                   default_blueprint, stage_panels, whole_run)

__all__ = [
    "TF_TOPIC", "TIMELINE", "WORLD_FRAME", "StageRecorder", "application_id", "default_blueprint",
    "stage_panels", "whole_run",
    "mcap_attachments", "mcap_input_hashes", "mcap_metadata", "mcap_parameters", "mcap_topics",
    "point_cloud_points", "read_mcap_scalars", "read_mcap_topic", "read_rrd_scalars",
    "rrd_blueprint_views", "rrd_column", "rrd_record_batches",
]
