"""Every StageRecorder method, read back from the .mcap and the .rrd."""

import numpy as np
import pytest
from mcap.reader import make_reader

from logs_testdata import (CHART, FPS, FRAMES, LINES, PHASE, D, K, PARAMETERS, POINTS, QUAT,
                           SERIES, SERIES_T, STRIP)
from wipelab.logs import (StageRecorder, mcap_attachments, mcap_input_hashes, mcap_metadata, mcap_parameters,
                          mcap_topics, point_cloud_points, read_mcap_scalars, read_mcap_topic,
                          read_rrd_scalars, rrd_blueprint_views, rrd_column)
from wipelab.manifest import sha256_file


def test_files_sit_side_by_side(recording):
    assert recording.mcap_path.name == "learn.mcap" and recording.rrd_path.name == "learn.rrd"
    assert sorted(p.name for p in recording.mcap_path.parent.iterdir()) == ["learn.mcap", "learn.rrd"]


def test_topics_use_foxglove_schemas_under_their_exact_names(recording):
    topics = mcap_topics(recording.mcap_path)
    assert {t: d["schema"] for t, d in topics.items()} == {
        "/oscillators/frequency_hz": "wipelab.Scalars",
        "/track/particles": "foxglove.PointCloud",
        "/track/trajectory": "foxglove.SceneUpdate",
        "/tf": "foxglove.FrameTransforms",
        "/adapt/tcp_commanded": "foxglove.PoseInFrame",
        "/adapt/force": "foxglove.SceneUpdate",
        "/stereo/left/calibration": "foxglove.CameraCalibration",
        "/stereo/left/image": "foxglove.CompressedImage",
        "/stereo/left/video": "foxglove.CompressedVideo",
        "/model/learned": "wipelab.Model",
        "/robot/sponge": "foxglove.SceneUpdate",
        "/robot/body": "foxglove.SceneUpdate",
        "/stereo/left/overlay": "foxglove.ImageAnnotations",
        "/adapt/events": "foxglove.Log",
        "/adapt/segment": "wipelab.State",
        "/adapt/profile": "wipelab.PhaseCurves",
    }
    for d in topics.values():
        json_channel = d["schema"].startswith("wipelab.")
        assert (d["schema_encoding"], d["message_encoding"]) == \
            (("jsonschema", "json") if json_channel else ("protobuf", "protobuf"))
    assert topics["/oscillators/frequency_hz"]["message_count"] == SERIES_T.size
    assert topics["/stereo/left/video"]["message_count"] == FRAMES


def test_metadata_holds_parameters_and_input_hashes(recording, input_file):
    metadata = mcap_metadata(recording.mcap_path)
    assert metadata["wipelab.stage"] == {"stage": "learn", "recording_id": recording.recording_id}
    assert mcap_parameters(recording.mcap_path) == PARAMETERS
    assert mcap_input_hashes(recording.mcap_path) == {"trajectory": sha256_file(input_file)}
    assert metadata["wipelab.inputs"]["trajectory.file"] == "trajectory.csv"
    media_type, data = mcap_attachments(recording.mcap_path)["trajectory.csv"]
    assert data == input_file.read_bytes() and media_type == "application/octet-stream"


def test_mcap_chunks_are_zstd_and_indexed(recording):
    with open(recording.mcap_path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary.chunk_indexes and {c.compression for c in summary.chunk_indexes} == {"zstd"}
    assert all(c.message_index_offsets for c in summary.chunk_indexes)
    assert summary.statistics.message_count == sum(d["message_count"] for d in mcap_topics(recording.mcap_path).values())
    assert summary.statistics.metadata_count == 3 and summary.statistics.attachment_count == 1


def test_scalars_round_trip(recording):
    t, values, names = read_mcap_scalars(recording.mcap_path, "/oscillators/frequency_hz")
    assert names == ["omega_1", "omega_2"]
    np.testing.assert_array_equal(t, SERIES_T)
    np.testing.assert_array_equal(values, SERIES)  # exact, NaN where NaN was logged
    t_rrd, values_rrd = read_rrd_scalars(recording.rrd_path, "/oscillators/frequency_hz")
    np.testing.assert_array_equal(t_rrd, SERIES_T)
    np.testing.assert_array_equal(values_rrd, SERIES)
    _, series_names = rrd_column(recording.rrd_path, "/oscillators/frequency_hz", "SeriesLines:names")
    assert series_names == [["omega_1", "omega_2"]]


def test_points_round_trip(recording):
    (ns, message), = read_mcap_topic(recording.mcap_path, "/track/particles")
    assert ns == 500_000_000 and message["frame_id"] == "world"
    assert message["timestamp"] == {"seconds": 0, "nanos": 500_000_000}
    points, rgba = point_cloud_points(message)
    np.testing.assert_allclose(points, POINTS, atol=1e-6)  # stored as float32
    assert (rgba == [255, 0, 0, 255]).all()
    t, positions = rrd_column(recording.rrd_path, "/track/particles", "Points3D:positions")
    np.testing.assert_allclose(np.array(positions[0]), POINTS, atol=1e-6)
    assert t.tolist() == [0.5]


def test_line_strip_round_trip(recording):
    (_, message), = read_mcap_topic(recording.mcap_path, "/track/trajectory")
    entity, = message["entities"]
    line, = entity["lines"]
    assert entity["id"] == "/track/trajectory" and line["type"] == "LINE_STRIP"
    np.testing.assert_allclose([[p["x"], p["y"], p["z"]] for p in line["points"]], STRIP)
    _, strips = rrd_column(recording.rrd_path, "/track/trajectory", "LineStrips3D:strips")
    np.testing.assert_allclose(np.array(strips[0][0]), STRIP, atol=1e-6)


def _rotate(q_xyzw, v):
    x, y, z, w = q_xyzw
    u = np.array([x, y, z])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def test_arrow_round_trip(recording):
    (_, message), = read_mcap_topic(recording.mcap_path, "/adapt/force")
    arrow, = message["entities"][0]["arrows"]
    pose = arrow["pose"]
    q = [pose["orientation"][k] for k in "xyzw"]
    length = arrow["shaft_length"] + arrow["head_length"]
    np.testing.assert_allclose([pose["position"][k] for k in "xyz"], [0.6, 0.1, 0.9])
    np.testing.assert_allclose(_rotate(q, np.array([length, 0.0, 0.0])), [0.0, 0.0, -0.2], atol=1e-12)
    _, vectors = rrd_column(recording.rrd_path, "/adapt/force", "Arrows3D:vectors")
    np.testing.assert_allclose(vectors[0], [[0.0, 0.0, -0.2]], atol=1e-7)


def test_transforms_round_trip(recording):
    (ns, message), = read_mcap_topic(recording.mcap_path, "/tf")
    assert ns == 0
    first, second = message["transforms"]
    assert (first["parent_frame_id"], first["child_frame_id"]) == ("world", "base_link")
    assert (second["parent_frame_id"], second["child_frame_id"]) == ("base_link", "left_optical")
    np.testing.assert_allclose([second["rotation"][k] for k in "xyzw"], QUAT)
    np.testing.assert_allclose([second["translation"][k] for k in "xyz"], [0.1, 0.2, 1.5])
    # Rerun: the world frame is the root frame, other frames keep their names.
    _, parents = rrd_column(recording.rrd_path, "/tf/base_link", "Transform3D:parent_frame")
    _, children = rrd_column(recording.rrd_path, "/tf/left_optical", "Transform3D:child_frame")
    assert parents == [["tf#/"]] and children == [["left_optical"]]


def test_pose_round_trip(recording):
    (ns, message), = read_mcap_topic(recording.mcap_path, "/adapt/tcp_commanded")
    assert ns == 1_000_000_000 and message["frame_id"] == "world"
    np.testing.assert_allclose([message["pose"]["position"][k] for k in "xyz"], [0.6, 0.1, 0.9])
    np.testing.assert_allclose([message["pose"]["orientation"][k] for k in "xyzw"], QUAT)
    _, translation = rrd_column(recording.rrd_path, "/adapt/tcp_commanded", "Transform3D:translation")
    np.testing.assert_allclose(translation[0], [[0.6, 0.1, 0.9]], atol=1e-6)


def test_camera_calibration_round_trip(recording):
    (_, message), = read_mcap_topic(recording.mcap_path, "/stereo/left/calibration")
    assert (message["width"], message["height"], message["frame_id"]) == (160, 120, "left_optical")
    assert message["distortion_model"] == "plumb_bob"
    np.testing.assert_allclose(message["K"], K.ravel())
    np.testing.assert_allclose(message["D"], D)
    np.testing.assert_allclose(np.reshape(message["P"], (3, 4))[:, :3], K)
    _, image_from_camera = rrd_column(recording.rrd_path, "/stereo/left/calibration", "Pinhole:image_from_camera")
    # Rerun stores the 3x3 matrix column-major.
    np.testing.assert_allclose(np.reshape(image_from_camera[0], (3, 3)).T, K)
    _, child = rrd_column(recording.rrd_path, "/stereo/left/calibration", "Pinhole:child_frame")
    assert child == [["left_optical_image_plane"]]


def test_compressed_image_round_trip(recording, jpeg_bytes):
    (ns, message), = read_mcap_topic(recording.mcap_path, "/stereo/left/image")
    assert ns == 200_000_000 and message["format"] == "jpeg" and message["data"] == jpeg_bytes
    _, blobs = rrd_column(recording.rrd_path, "/stereo/left/image", "EncodedImage:blob")
    assert bytes(blobs[0][0]) == jpeg_bytes


def test_video_round_trip(recording, h264_clip):
    messages = read_mcap_topic(recording.mcap_path, "/stereo/left/video")
    assert [ns for ns, _ in messages] == [round(i / FPS * 1e9) for i in range(FRAMES)]
    first = messages[0][1]
    assert first["format"] == "h264" and first["frame_id"] == "left_optical"
    assert first["data"].startswith(b"\x00\x00\x00\x01")  # Annex B
    nal_types = {b & 0x1F for b in _nal_header_bytes(first["data"])}
    assert {7, 8, 5} <= nal_types  # SPS, PPS and an IDR slice in the first access unit
    t, references = rrd_column(recording.rrd_path, "/stereo/left/video", "VideoFrameReference:timestamp")
    np.testing.assert_allclose(t, np.arange(FRAMES) / FPS)
    _, blob = rrd_column(recording.rrd_path, "/stereo/left/video", "AssetVideo:blob")
    assert bytes(blob[0][0]) == h264_clip.read_bytes()


def _nal_header_bytes(annex_b: bytes):
    parts = annex_b.split(b"\x00\x00\x01")
    return [p[0] for p in parts[1:] if p]


def test_json_round_trip(recording):
    (ns, message), = read_mcap_topic(recording.mcap_path, "/model/learned")
    assert ns == 2_000_000_000 and message == {"weights": [0.0, 1.0, 2.0], "frequency_hz": 1.5}
    _, text = rrd_column(recording.rrd_path, "/model/learned", "TextDocument:text")
    assert '"frequency_hz": 1.5' in text[0][0]


def test_records_logged_through_the_raw_stream_are_kept(recording):
    t, text = rrd_column(recording.rrd_path, "/custom/note", "TextLog:text")
    assert t.tolist() == [1.5] and text == [["stage-specific record"]]


def test_blueprint_is_stored_in_the_rrd(recording):
    assert rrd_blueprint_views(recording.rrd_path) == [("3D", "/"), ("TimeSeries", "/oscillators")]


def test_no_wall_clock_timeline_in_the_rrd(recording):
    from wipelab.logs import rrd_record_batches
    for entity in ("/oscillators/frequency_hz", "/track/particles", "/stereo/left/video"):
        for batch in rrd_record_batches(recording.rrd_path, entity):
            assert not {"log_time", "log_tick"} & set(batch.schema.names)


@pytest.mark.parametrize("missing", ["/nope"])
def test_reading_a_missing_topic_gives_nothing(recording, missing):
    assert read_mcap_topic(recording.mcap_path, missing) == []
    with pytest.raises(KeyError, match="/nope"):
        read_mcap_scalars(recording.mcap_path, missing)


def test_box_round_trip_and_removal(recording):
    (_, drawn), (_, removed) = read_mcap_topic(recording.mcap_path, "/robot/sponge")
    (entity,) = drawn["entities"]
    (cube,) = entity["cubes"]
    assert entity["frame_id"] == "hand" and entity["frame_locked"] and entity["id"] == "/robot/sponge"
    assert [cube["size"][a] for a in "xyz"] == pytest.approx([0.1, 0.07, 0.04])
    assert [cube["pose"]["position"][a] for a in "xyz"] == pytest.approx([0.6, 0.1, 0.85])
    assert removed["entities"] == [] and removed["deletions"][0]["id"] == "/robot/sponge"
    t, half_sizes = rrd_column(recording.rrd_path, "/robot/sponge", "Boxes3D:half_sizes")
    assert t.tolist() == [0.5, 0.6]
    assert half_sizes[0] == [pytest.approx([0.05, 0.035, 0.02])] and half_sizes[1] == []


def test_shapes_are_frame_locked_entities(recording):
    (_, update), = read_mcap_topic(recording.mcap_path, "/robot/body")
    (entity,) = update["entities"]
    assert (entity["id"], entity["frame_id"], entity["frame_locked"]) == ("robot/hand", "hand", True)
    assert len(entity["cubes"]) == 1 and len(entity["spheres"]) == 1
    assert entity["cubes"][0]["color"]["r"] == pytest.approx(90 / 255)


def test_image_overlay_round_trip(recording):
    (_, annotations), = read_mcap_topic(recording.mcap_path, "/stereo/left/overlay")
    lines, points = annotations["points"]
    assert lines["type"] == "LINE_LIST" and points["type"] == "POINTS"
    assert [(p["x"], p["y"]) for p in lines["points"]] == [(10, 20), (30, 40), (30, 40), (50, 20)]
    _, strips = rrd_column(recording.rrd_path, "/stereo/left/overlay", "LineStrips2D:strips")
    assert np.array(strips[0]).tolist() == LINES.tolist()


def test_events_are_foxglove_logs_and_rerun_text_logs(recording):
    messages = read_mcap_topic(recording.mcap_path, "/adapt/events")
    assert [(ns, m["message"], m["level"], m["name"]) for ns, m in messages] == [
        (0, "approach", "INFO", "learn"), (1_000_000_000, "learning", "INFO", "learn")]
    t, text = rrd_column(recording.rrd_path, "/adapt/events", "TextLog:text")
    assert t.tolist() == [0.0, 1.0] and text == [["approach"], ["learning"]]


def test_states_round_trip(recording):
    assert [(ns, m) for ns, m in read_mcap_topic(recording.mcap_path, "/adapt/segment")] == [
        (0, {"state": "approach"}), (1_000_000_000, {"state": "learning"})]
    t, states = rrd_column(recording.rrd_path, "/adapt/segment", "StateChange:state")
    assert t.tolist() == [0.0, 1.0] and states == [["approach"], ["learning"]]


def test_phase_curves_round_trip(recording):
    (_, message), = read_mcap_topic(recording.mcap_path, "/adapt/profile")
    assert message["period"] == 1
    np.testing.assert_allclose(message["phase_rad"], PHASE)
    np.testing.assert_allclose(message["learned_m"], np.sin(PHASE))
    _, strips = rrd_column(recording.rrd_path, "/adapt/profile", "LineStrips2D:strips")
    np.testing.assert_allclose(np.array(strips[0][0]), CHART.to_chart(PHASE, np.sin(PHASE)),
                               rtol=1e-6)


@pytest.mark.parametrize("names", [["measured |F|"], ["true contact"], ["a.b"]])
def test_series_names_must_be_plottable_in_foxglove(tmp_path, names):
    with StageRecorder(tmp_path, "x") as rec, pytest.raises(ValueError, match="letters, digits"):
        rec.scalars("/a/b", np.arange(2.0), np.arange(2.0), names=names)
