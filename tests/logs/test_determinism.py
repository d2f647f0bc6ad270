"""Same inputs -> byte-identical .mcap and .rrd; different parameters -> a different recording."""

import pathlib

from logs_testdata import PARAMETERS, write_everything
from wipelab.logs import mcap_metadata


def test_rewriting_gives_identical_bytes(tmp_path, recording, h264_clip, jpeg_bytes, input_file):
    again = write_everything(tmp_path, h264_clip, jpeg_bytes, input_file)
    assert again.mcap_path.read_bytes() == recording.mcap_path.read_bytes()
    assert again.rrd_path.read_bytes() == recording.rrd_path.read_bytes()


def test_other_parameters_give_another_recording_id(tmp_path, recording, h264_clip, jpeg_bytes, input_file):
    other = write_everything(tmp_path, h264_clip, jpeg_bytes, input_file,
                             parameters={**PARAMETERS, "kernels": 30})
    assert other.recording_id != recording.recording_id
    assert mcap_metadata(other.mcap_path)["wipelab.parameters"]["kernels"] == "30"
    assert other.rrd_path.read_bytes() != recording.rrd_path.read_bytes()


def test_another_process_writes_the_same_bytes(tmp_path, recording, h264_clip, jpeg_bytes, input_file):
    """Hash-map seeds and TUID counters differ per process; the files must not."""
    import subprocess
    import sys
    jpeg = tmp_path / "frame.jpg"
    jpeg.write_bytes(jpeg_bytes)
    out = tmp_path / "out"
    out.mkdir()
    code = ("import pathlib, sys; from logs_testdata import write_everything as w; "
            "p = pathlib.Path; w(p(sys.argv[1]), p(sys.argv[2]), p(sys.argv[3]).read_bytes(), p(sys.argv[4]))")
    subprocess.run([sys.executable, "-c", code, out, h264_clip, jpeg, input_file], check=True,
                   cwd=pathlib.Path(__file__).parent, capture_output=True)
    assert (out / "learn.mcap").read_bytes() == recording.mcap_path.read_bytes()
    assert (out / "learn.rrd").read_bytes() == recording.rrd_path.read_bytes()
