"""staged_output publishes whole files on success and nothing on failure."""

import pytest

from wipelab.stage_output import staged_output


def test_files_appear_only_after_success(tmp_path):
    out = tmp_path / "out"
    with staged_output(out) as tmp:
        (tmp / "a.json").write_text("{}")
        (tmp / "sub").mkdir()
        (tmp / "sub" / "b.csv").write_text("t\n0\n")
        assert not out.exists()
    assert (out / "a.json").read_text() == "{}"
    assert (out / "sub" / "b.csv").read_text() == "t\n0\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_failure_leaves_nothing_and_keeps_old_files(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "model.json").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with staged_output(out) as tmp:
            (tmp / "model.json").write_text("half")
            raise KeyboardInterrupt
    assert (out / "model.json").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
