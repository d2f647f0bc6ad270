"""The track's drawings (sponge box, particles, trajectory, overlays) logged all at once or a
block at a time, as the track stage and live log them."""

import numpy as np

from wipelab.logs import StageRecorder, read_mcap_topic, rrd_column
from wipelab.stages.track import TrackScene, log_track_frames
from wipelab.vision.synthetic_rig import armar_wide_stereo_calibration
from wipelab.vision.tracker import QUALITY_BOX, QUALITY_CENTROID, QUALITY_NONE

TOPICS = ("/track/particles", "/track/sponge", "/track/trajectory", "/stereo/left/overlay",
          "/stereo/right/overlay")


def _frames(n=12, seed=3):
    rng = np.random.default_rng(seed)
    poses = np.column_stack([0.55 + 0.05 * rng.standard_normal((n, 2)), np.full(n, 0.8),
                             rng.uniform(-1.0, 1.0, n)])
    quality = np.array([QUALITY_BOX, QUALITY_BOX, QUALITY_NONE, QUALITY_CENTROID, QUALITY_BOX,
                        QUALITY_BOX, QUALITY_BOX, QUALITY_NONE, QUALITY_NONE, QUALITY_BOX,
                        QUALITY_CENTROID, QUALITY_BOX][:n])
    poses[quality == QUALITY_NONE] = np.nan
    particles = poses[:, None, :] + 0.01 * rng.standard_normal((n, 5, 4))
    particles[quality != QUALITY_BOX] = np.nan
    particles[4, 3:] = np.nan   # fewer particles in one frame
    return np.arange(n) / 30.0, poses, quality, particles


def _log(directory, blocks):
    t, poses, quality, particles = _frames()
    scene = TrackScene(armar_wide_stereo_calibration(), "world", np.eye(3), (0.11, 0.075, 0.03),
                       0.08)
    directory.mkdir()
    with StageRecorder(directory, "track") as rec:
        previous = None
        for block in blocks:
            previous = log_track_frames(rec, scene, np.arange(len(t))[block], t[block],
                                        poses[block], quality[block], particles[block],
                                        previous)
    return directory


def test_frames_logged_a_block_at_a_time_are_those_logged_at_once(tmp_path):
    whole = _log(tmp_path / "whole", [slice(0, 12)])
    blocks = _log(tmp_path / "blocks", [slice(0, 4), slice(4, 6), slice(6, 12)])
    for topic in TOPICS:
        assert read_mcap_topic(blocks / "track.mcap", topic) == \
            read_mcap_topic(whole / "track.mcap", topic), topic
    # a piece of trajectory from each tracked frame to the next one, across block ends too
    pieces = read_mcap_topic(blocks / "track.mcap", "/track/trajectory")
    assert [m["entities"][0]["id"] for _, m in pieces] == \
        [f"/track/trajectory/{k}" for k in (1, 4, 5, 6, 10, 11)]
    t, strips = rrd_column(blocks / "track.rrd", "/track/trajectory", "LineStrips3D:strips")
    assert len(t) == 6 and all(len(strip[0]) == 2 for strip in strips)
    # the sponge removed while lost; the box edges drawn on tracked frames only
    sponge = read_mcap_topic(blocks / "track.mcap", "/track/sponge")
    assert [bool(m["deletions"]) for _, m in sponge] == [q == QUALITY_NONE for q in _frames()[2]]
    _, edges = rrd_column(blocks / "track.rrd", "/stereo/left/overlay", "LineStrips2D:strips")
    assert [len(e) for e in edges] == [0 if q == QUALITY_NONE else 12 for q in _frames()[2]]
    t, points = rrd_column(blocks / "track.rrd", "/track/particles", "Points3D:positions")
    assert [len(p) for p in points] == [5, 5, 3, 5, 5, 5, 5]
