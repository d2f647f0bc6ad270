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


def test_a_killed_run_s_partial_folder_goes_but_a_live_one_stays(tmp_path):
    """A partial folder nobody holds a lock on is a leftover; one a process is writing into
    (here another process holds its flock) is not touched."""
    import subprocess
    import sys

    stale = tmp_path / ".out.partial-stale"
    live = tmp_path / ".out.partial-live"
    other = tmp_path / ".other.partial-x"
    for folder in (stale, live, other):
        folder.mkdir()
        (folder / "half.csv").write_text("t\n")
    holder = subprocess.Popen(
        [sys.executable, "-c", "import fcntl, os, sys; fd = os.open(sys.argv[1], os.O_RDONLY); "
         "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); sys.stdin.read()", live],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "held\n"
        with staged_output(tmp_path / "out") as tmp:
            (tmp / "a.csv").write_text("t\n")
        assert not stale.exists() and live.exists() and other.exists()
    finally:
        holder.communicate("")
    assert sorted(p.name for p in tmp_path.iterdir()) == [".other.partial-x", ".out.partial-live",
                                                          "out"]


def test_a_file_in_the_way_of_an_output_file_is_refused_before_anything_moves(tmp_path):
    from wipelab.errors import InputError

    out = tmp_path / "out"
    (out / "model.json").mkdir(parents=True)
    with pytest.raises(InputError, match=r"model\.json: is a directory, expected a file name"):
        with staged_output(out) as tmp:
            (tmp / "a.csv").write_text("t\n")
            (tmp / "model.json").write_text("{}")
    assert sorted(p.name for p in out.iterdir()) == ["model.json"]
