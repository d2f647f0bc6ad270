"""The canonical .rrd rewrite."""

import pytest
import rerun.blueprint as rrb

from wipelab.logs.rrd_file import _canonical_framing, deterministic_blueprint


def layout():
    return rrb.Blueprint(rrb.Vertical(rrb.Spatial3DView(origin="/"), rrb.TimeSeriesView(origin="/a")))


def test_blueprint_ids_depend_only_on_key_and_position():
    first, second = deterministic_blueprint(layout(), "k"), deterministic_blueprint(layout(), "k")
    ids = lambda bp: [bp.root_container.id] + [c.id for c in bp.root_container.contents]
    assert ids(first) == ids(second)
    assert len(set(ids(first))) == 3
    assert ids(deterministic_blueprint(layout(), "other")) != ids(first)


def test_framing_rejects_what_is_not_an_rrd_stream(tmp_path):
    path = tmp_path / "x.rrd"
    path.write_bytes(b"\x89MCAP0\r\n" + bytes(40))
    with pytest.raises(RuntimeError, match="bad magic"):
        _canonical_framing(path, b"a", b"b")


def test_framing_refuses_ids_of_other_lengths(tmp_path):
    with pytest.raises(ValueError, match="same length"):
        _canonical_framing(tmp_path / "x.rrd", b"abc", b"ab")


def test_row_ids_keep_the_logging_order_across_chunks(tmp_path):
    """Rows with different timelines land in different chunks; their order must survive."""
    import rerun as rr

    from wipelab.logs import StageRecorder, rrd_record_batches
    with StageRecorder(tmp_path, "x") as rec:
        rec.rerun.set_time("time", duration=1.0)
        rec.rerun.log("/e", rr.TextLog("a"))
        rec.rerun.set_time("frame", sequence=0)
        rec.rerun.log("/e", rr.TextLog("b"))
        rec.rerun.disable_timeline("frame")
        rec.rerun.log("/e", rr.TextLog("c"))
    rows = []
    batches = rrd_record_batches(tmp_path / "x.rrd", "/e")
    assert len(batches) == 2
    for batch in batches:
        ids = [int.from_bytes(row_id, "big") for row_id in batch.column("rerun.controls.RowId").to_pylist()]
        rows += zip(ids, [t[0] for t in batch.column("TextLog:text").to_pylist()])
    assert [text for _, text in sorted(rows)] == ["a", "b", "c"]


def _eye_and_override_layout():
    import rerun as rr

    return rrb.Blueprint(rrb.Horizontal(
        rrb.Spatial3DView(origin="/", eye_controls=rrb.EyeControls3D(
            position=[1.0, 2.0, 3.0], look_target=[0.0, 0.0, 0.0], eye_up=[0.0, 0.0, 1.0])),
        rrb.TimeSeriesView(origin="/a", overrides={
            "/a": rr.SeriesLines.from_fields(visible_series=[True, False])})))


def test_stored_layout_keeps_rerun_encodings_and_is_reproducible(tmp_path):
    """The viewer drops a default layout whose nested fields lost their non-null flags (a
    deep copy of the blueprint did that), and visualizer overrides get random ids."""
    import rerun as rr
    from rerun.chunk import RrdReader

    from wipelab.logs import StageRecorder

    files = []
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        with StageRecorder(tmp_path / name, "x", blueprint=_eye_and_override_layout()) as rec:
            rec.scalars("/a", [0.0, 1.0], [[1.0, 2.0], [3.0, 4.0]], names=["u", "v"])
        files.append(tmp_path / name / "x.rrd")
    assert files[0].read_bytes() == files[1].read_bytes()
    direct = rr.RecordingStream("x", recording_id="direct")
    direct.save(tmp_path / "direct.rrd", default_blueprint=_eye_and_override_layout())
    direct.flush()
    direct.disconnect()

    def eye_type(path):
        reader = RrdReader(path)
        return {str(field.type) for store in reader.blueprints()
                for chunk in reader.stream(store=store).to_chunks()
                for field in chunk.to_record_batch().schema if field.name.startswith("EyeControls3D:")}

    assert eye_type(files[0]) == eye_type(tmp_path / "direct.rrd")
    assert "float not null" in next(iter(eye_type(files[0])))
