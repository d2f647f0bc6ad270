"""Trajectory CSV: round trip, determinism, and one clear error per kind of bad file."""

import numpy as np
import pytest

from wipelab.errors import InputError
from wipelab.trajectory_csv import read_trajectory, write_trajectory


def _write(path, text):
    path.write_text(text)
    return path


def test_round_trip_keeps_extra_columns_and_valid(tmp_path):
    t = np.arange(5) * 0.1
    columns = {"x": np.sin(t), "y": np.cos(t), "z": t ** 2,
               "valid": np.array([1, 1, 0, 1, 1], dtype=bool), "u_norm": t - 0.2}
    write_trajectory(tmp_path / "a.csv", t, columns)
    trajectory = read_trajectory(tmp_path / "a.csv")
    assert list(trajectory.columns) == ["x", "y", "z", "valid", "u_norm"]
    np.testing.assert_allclose(trajectory.t, t, atol=1e-6)
    np.testing.assert_allclose(trajectory.array(["x", "y"]), np.column_stack([np.sin(t), np.cos(t)]),
                               atol=1e-6)
    assert trajectory.valid.tolist() == [True, True, False, True, True]
    assert (tmp_path / "a.csv").read_text().splitlines()[1].endswith(",1,-0.200000")


def test_writer_is_deterministic_and_leaves_no_partial_file(tmp_path):
    t = np.linspace(0.0, 1.0, 7)
    for name in ("a.csv", "b.csv"):
        write_trajectory(tmp_path / name, t, {"x": np.exp(t)}, float_format="%.9f")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]


def test_invalid_rows_may_hold_nan(tmp_path):
    path = _write(tmp_path / "a.csv", "t,x,y,valid\n0,1,2,1\n0.1,nan,nan,0\n0.2,1,2,1\n")
    assert read_trajectory(path).valid.tolist() == [True, False, True]


@pytest.mark.parametrize("text, message", [
    ("t,x\n0,1\n0.1,2\n0.2,3\n", r"missing column\(s\) y \(header is t,x\)"),
    ("t,x,y\n0,1,2\n0.1,inf,2\n0.2,1,2\n", r"column x has NaN or inf \(data row 2\)"),
    ("t,x,y\n0,1,2\n0.1,nan,2\n0.2,1,2\n", r"column x has NaN or inf"),
    ("t,x,y\n0,1,2\n0.1,1,2\n", r"too short, 2 data row\(s\), need at least 3"),
    ("t,x,y\n0,1,2\n0.2,1,2\n0.1,1,2\n", r"time column t is not strictly increasing \(data row 3\)"),
    ("t,x,y\n0,1,2\n0.1,a,2\n0.2,1,2\n", r"not a table of numbers"),
    ("t,x,y\n0,1,2\n0.1,1\n0.2,1,2\n", r"not a table of numbers"),
    ("", r"empty file"),
    ("t,x,x\n0,1,2\n0.1,1,2\n0.2,1,2\n", r"bad header"),
    ("t,x,y,valid\n0,1,2,0\n0.1,1,2,0\n0.2,1,2,0\n", r"no row has valid = 1"),
    ("t,x,y,valid\n0,1,2,2\n0.1,1,2,1\n0.2,1,2,1\n", r"valid must hold only 0 or 1"),
])
def test_bad_files_raise_one_clear_error_naming_the_file(tmp_path, text, message):
    path = _write(tmp_path / "bad.csv", text)
    with pytest.raises(InputError, match=message) as error:
        read_trajectory(path)
    assert str(error.value).startswith(str(path))


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(InputError, match=r"nope\.csv: file not found"):
        read_trajectory(tmp_path / "nope.csv")
    with pytest.raises(InputError, match=r"is a directory"):
        read_trajectory(tmp_path)
    binary = tmp_path / "binary.csv"
    binary.write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(InputError, match=r"binary\.csv: not a text file"):
        read_trajectory(binary)
