"""Failure handling, argument checks, long series, the order of series in the MCAP."""

import numpy as np
import pytest
from mcap.reader import make_reader

from wipelab.errors import InputError
from wipelab.logs import (StageRecorder, mcap_topics, read_mcap_scalars, read_rrd_scalars,
                          rrd_column)


def test_files_are_complete_when_the_with_block_raises(tmp_path):
    with pytest.raises(RuntimeError, match="stage failed"):
        with StageRecorder(tmp_path, "adapt") as rec:
            rec.scalars("/adapt/force_n", [0.0, 0.1], [1.0, 2.0])
            raise RuntimeError("stage failed")
    assert mcap_topics(tmp_path / "adapt.mcap")["/adapt/force_n"]["message_count"] == 2
    np.testing.assert_array_equal(read_rrd_scalars(tmp_path / "adapt.rrd", "/adapt/force_n")[1], [[1.0], [2.0]])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adapt.mcap", "adapt.rrd"]


def test_missing_directory_raises(tmp_path):
    with pytest.raises(FileNotFoundError):
        StageRecorder(tmp_path / "absent", "learn")


@pytest.mark.parametrize("call, message", [
    (lambda rec: rec.scalars("no_slash", [0.0], [1.0]), "must look like /a/b"),
    (lambda rec: rec.scalars("/a/", [0.0], [1.0]), "must look like /a/b"),
    (lambda rec: rec.scalars("/a", [0.0, -1.0], [1.0, 2.0]), ">= 0 s"),
    (lambda rec: rec.scalars("/a", [0.0, np.nan], [1.0, 2.0]), "finite"),
    (lambda rec: rec.scalars("/a", [0.0, 1.0], [[1.0, 2.0]]), r"shape \(2, k\)"),
    (lambda rec: rec.scalars("/a", [0.0], [[1.0, 2.0]], names=["x", "x"]), "distinct names"),
    (lambda rec: rec.arrow3d("/a", 0.0, [0, 0, 0], [[0, 0, 1], [0, 1, 0]]), "differ in shape"),
    (lambda rec: rec.pose("/a", 0.0, "world", [0, 0, 0], [0, 0, 0, 0]), "non-zero"),
    (lambda rec: rec.compressed_image("/a", 0.0, b"GIF89a", "cam"), "magic bytes"),
    (lambda rec: rec.points3d("/a", 0.0, np.zeros((2, 3)), colors=np.zeros((3, 3))), r"colors must have shape"),
])
def test_bad_arguments_raise(tmp_path, call, message):
    with StageRecorder(tmp_path, "x") as rec:
        with pytest.raises(ValueError, match=message):
            call(rec)


def test_a_topic_keeps_its_schema(tmp_path):
    with StageRecorder(tmp_path, "x") as rec:
        rec.scalars("/a", [0.0], [1.0])
        with pytest.raises(ValueError, match="already carries another schema"):
            rec.points3d("/a", 0.0, np.zeros((1, 3)))


def test_video_needs_a_codec_viewers_decode(tmp_path):
    import cv2
    path = tmp_path / "mpeg4.mp4"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 10, (64, 48))
    for _ in range(3):
        writer.write(np.zeros((48, 64, 3), np.uint8))
    writer.release()
    with StageRecorder(tmp_path, "x") as rec:
        with pytest.raises(InputError, match=r"mpeg4.mp4: video codec 'mpeg4' cannot be logged as video"):
            rec.video("/stereo/left/video", path, np.arange(3) / 10)


def test_more_frame_times_than_frames_raise(tmp_path, h264_clip):
    with StageRecorder(tmp_path, "x") as rec:
        with pytest.raises(ValueError, match="has 20 frames, got 25 frame times"):
            rec.video("/stereo/left/video", h264_clip, np.arange(25) / 10)


def test_a_long_fast_series_is_logged_whole(tmp_path):
    """60 s at 500 Hz, 10 channels: 30 000 MCAP messages plus one Rerun column batch, read
    back unchanged (how fast is for a benchmark: a time bound here failed on a loaded
    machine)."""
    t = np.arange(30_000) / 500.0
    values = np.random.default_rng(1).normal(size=(30_000, 10))
    with StageRecorder(tmp_path, "x") as rec:
        rec.scalars("/robot/joint_positions", t, values, names=[f"q{i}" for i in range(10)])
    t_back, values_back, _ = read_mcap_scalars(tmp_path / "x.mcap", "/robot/joint_positions")
    np.testing.assert_array_equal(values_back, values)
    assert read_rrd_scalars(tmp_path / "x.rrd", "/robot/joint_positions")[1].shape == (30_000, 10)


def test_video_keeps_the_rrd_near_the_mp4_size(tmp_path, h264_clip):
    with StageRecorder(tmp_path, "x") as rec:
        rec.video("/stereo/left/video", h264_clip, np.arange(20) / 10)
    mp4 = h264_clip.stat().st_size
    assert (tmp_path / "x.rrd").stat().st_size < mp4 + 64 * 1024
    assert (tmp_path / "x.mcap").stat().st_size < mp4 + 64 * 1024


def test_series_logged_in_time_order_lie_in_the_mcap_time_by_time(tmp_path):
    with StageRecorder(tmp_path, "x") as rec:
        with rec.in_time_order():
            rec.points3d_series("/p", [0.0, 1.0, 2.0], np.zeros((5, 3)), [2, 0, 3])
            rec.box3d_series("/b", [0.0, 1.0, 2.0], np.ones((3, 3)),
                             [[0, 0, 0], [np.nan] * 3, [1, 2, 3]], [[0, 0, 0, 1]] * 3)
            with pytest.raises(RuntimeError, match="do not nest"):
                with rec.in_time_order():
                    pass
    with open(tmp_path / "x.mcap", "rb") as f:
        written = [(channel.topic, message.log_time // 10**9, message.sequence)
                   for _, channel, message in make_reader(f).iter_messages(log_time_order=False)]
    assert written == [("/p", 0, 0), ("/b", 0, 0), ("/p", 1, 1), ("/b", 1, 1), ("/p", 2, 2),
                       ("/b", 2, 2)]
    t, points = rrd_column(tmp_path / "x.rrd", "/p", "Points3D:positions")
    assert t.tolist() == [0.0, 1.0, 2.0] and [len(p) for p in points] == [2, 0, 3]
    t, half_sizes = rrd_column(tmp_path / "x.rrd", "/b", "Boxes3D:half_sizes")
    assert t.tolist() == [0.0, 1.0, 2.0] and half_sizes == [[[0.5] * 3], [], [[0.5] * 3]]
    t, centres = rrd_column(tmp_path / "x.rrd", "/b", "Boxes3D:centers")
    assert t.tolist() == [0.0, 2.0] and centres == [[[0.0, 0.0, 0.0]], [[1.0, 2.0, 3.0]]]
