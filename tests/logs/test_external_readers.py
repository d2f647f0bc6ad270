"""Files pass readers that are not ours: the Rust MCAP and RRD readers in the rerun CLI."""

import subprocess

import pytest

from logs_testdata import rerun_cli
from wipelab.logs import rrd_record_batches

RERUN = rerun_cli()
needs_cli = pytest.mark.skipif(RERUN is None, reason="the `rerun` CLI (rerun-sdk wheel) is not installed")


def run(*args):
    return subprocess.run([RERUN, *map(str, args)], capture_output=True, text=True, timeout=120)


@needs_cli
def test_rerun_mcap_check_accepts_the_mcap(recording):
    result = run("mcap", "check", recording.mcap_path)
    assert result.returncode == 0, result.stderr
    assert "/stereo/left/video" in result.stdout and "—" in result.stdout


@needs_cli
def test_rerun_rrd_verify_accepts_the_rrd(recording):
    result = run("rrd", "verify", recording.rrd_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "verified without error" in result.stdout + result.stderr


@needs_cli
def test_rerun_maps_the_foxglove_schemas(recording, tmp_path):
    """``rerun mcap convert`` recognises the schemas and turns them into Rerun archetypes."""
    converted = tmp_path / "converted.rrd"
    result = run("mcap", "convert", recording.mcap_path, "-o", converted)
    assert result.returncode == 0, result.stderr
    columns = {entity: {name for batch in rrd_record_batches(converted, entity) for name in batch.schema.names}
               for entity in ("/track/particles", "/tf", "/stereo/left/calibration", "/stereo/left/image",
                              "/adapt/tcp_commanded")}
    assert "Points3D:positions" in columns["/track/particles"]
    assert "Transform3D:child_frame" in columns["/tf"]
    assert "Pinhole:image_from_camera" in columns["/stereo/left/calibration"]
    assert "EncodedImage:blob" in columns["/stereo/left/image"]
    assert "InstancePoses3D:translations" in columns["/adapt/tcp_commanded"]


def test_the_rrd_footer_manifest_indexes_every_chunk(recording):
    """The rewritten footer (chunk manifest) drives Rerun's random-access reader."""
    from rerun.chunk import RrdReader
    summary = RrdReader(recording.rrd_path).store().summary()
    for entity in ("/oscillators/frequency_hz", "/track/particles", "/stereo/left/video", "/tf/left_optical"):
        assert f"{entity} rows=" in summary
    lazily_read = RrdReader(recording.rrd_path).store().stream().to_chunks()
    assert len(lazily_read) == len(RrdReader(recording.rrd_path).stream().to_chunks())
