"""The stage cache: content hashes, keys and records."""

import hashlib
import json
import os

import pytest

from wipelab.pipeline.cache import (RECORD_NAME, DigestMemo, StageRecord, code_files_in_use,
                                    package_root, read_record, remove_record, stage_key,
                                    write_record)


def record_for(stage_dir, memo, key="k1"):
    return StageRecord(key=key, stage="learn", command="learn",
                       code={"pipeline/cache.py": memo.file(package_root() / "pipeline/cache.py")},
                       parameters={"kernels": 25}, input="track/track.csv", input_digest="abc",
                       outputs=memo.files(stage_dir), seconds=1.5)


def test_digests_are_sha256_and_follow_content_changes(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"one")
    memo = DigestMemo()
    assert memo.file(path) == hashlib.sha256(b"one").hexdigest()
    path.write_bytes(b"two!")  # size changes, so the memo cannot serve the old hash
    assert memo.file(path) == hashlib.sha256(b"two!").hexdigest()


def test_directory_content_hash_covers_names_and_bytes_but_not_hidden_files(tmp_path):
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "left.mp4").write_bytes(b"L")
    (tmp_path / "d" / "sub").mkdir()
    (tmp_path / "d" / "sub" / "x.txt").write_bytes(b"X")
    before = DigestMemo().content(tmp_path / "d")
    (tmp_path / "d" / ".hidden").write_bytes(b"ignored")
    assert DigestMemo().content(tmp_path / "d") == before
    (tmp_path / "d" / "sub" / "x.txt").rename(tmp_path / "d" / "sub" / "y.txt")
    assert DigestMemo().content(tmp_path / "d") != before


def test_stage_key_changes_with_every_ingredient():
    base = dict(stage="learn", command="learn", version="0.1.0", parameters={"kernels": 25},
                output=None, input_digest="d1")
    key = stage_key(**base)
    assert stage_key(**{**base, "parameters": {"kernels": 25}}) == key
    for change in [{"stage": "learn2"}, {"command": "rollout"}, {"version": "0.2.0"},
                   {"parameters": {"kernels": 26}}, {"output": "x.csv"}, {"input_digest": "d2"}]:
        assert stage_key(**{**base, **change}) != key, change


def test_record_round_trip_and_output_check(tmp_path):
    stage_dir = tmp_path / "learn"
    stage_dir.mkdir()
    (stage_dir / "model.json").write_text("{}")
    (stage_dir / "learn.mcap").write_bytes(b"mcap")
    memo = DigestMemo()
    record = record_for(stage_dir, memo)
    write_record(stage_dir, record)
    assert sorted(os.listdir(stage_dir)) == [RECORD_NAME, "learn.mcap", "model.json"]
    assert json.loads((stage_dir / RECORD_NAME).read_text())["format"] == "wipelab.stage_cache/1"
    assert read_record(stage_dir) == record
    assert record.outputs == {"learn.mcap": hashlib.sha256(b"mcap").hexdigest(),
                              "model.json": hashlib.sha256(b"{}").hexdigest()}
    assert record.outputs_intact(stage_dir, DigestMemo())

    (stage_dir / "model.json").write_text("{ }")
    assert not record.outputs_intact(stage_dir, DigestMemo())
    (stage_dir / "model.json").write_text("{}")
    (stage_dir / "extra.csv").write_text("t\n")
    assert not record.outputs_intact(stage_dir, DigestMemo())
    (stage_dir / "extra.csv").unlink()
    (stage_dir / "learn.mcap").unlink()
    assert not record.outputs_intact(stage_dir, DigestMemo())

    remove_record(stage_dir)
    assert read_record(stage_dir) is None


@pytest.mark.parametrize("text", ["", "{", '{"format": "other/1"}',
                                  '{"format": "wipelab.stage_cache/1"}'])
def test_unreadable_records_count_as_absent(tmp_path, text):
    (tmp_path / RECORD_NAME).write_text(text)
    assert read_record(tmp_path) is None


def test_code_files_are_the_loaded_wipelab_modules_and_the_package_data(tmp_path):
    files = code_files_in_use()
    assert "pipeline/cache.py" in files and "__init__.py" in files
    assert all(not name.endswith(".pyc") for name in files)
    assert any(name.startswith("sim/assets/") for name in files)  # the robot model


def test_a_record_holds_while_its_code_files_are_unchanged(tmp_path):
    memo = DigestMemo()
    record = record_for(tmp_path, memo)
    assert record.code_intact(memo)
    edited = StageRecord(**{**record.__dict__, "code": {"pipeline/cache.py": "0" * 64}})
    assert not edited.code_intact(DigestMemo())
    gone = StageRecord(**{**record.__dict__, "code": {"pipeline/removed.py": "0" * 64}})
    assert not gone.code_intact(DigestMemo())
