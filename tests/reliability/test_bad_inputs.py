"""Bad input to every command and in every file format: one line, exit code 2, nothing left.

Each case runs ``wipelab COMMAND ...`` in its own workspace (links to the session's real
artefacts plus what the case breaks) and asserts: exit code 2; on stderr exactly one line
``error: ...`` that names the file or option and says what is wrong; nothing on stdout; no
traceback; the workspace and the artefacts exactly as before (nothing created, nothing
half-written). The table in the module's CASES is grouped by command.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from reliability_testdata import error_line, invoke, run_process, tree

Setup = Callable[[Path], None]


@dataclass(frozen=True)
class Case:
    """``wipelab COMMAND *ARGV`` after ``setup(workspace)``; the error line must contain
    ``names`` (the file or option) and ``says`` (what is wrong)."""

    command: str
    id: str
    argv: tuple[str, ...]
    names: str
    says: str
    setup: Setup | None = None


def text(name: str, content: str) -> Setup:
    return lambda ws: (ws / name).write_text(content)


def data(name: str, content: bytes) -> Setup:
    return lambda ws: (ws / name).write_bytes(content)


def npy(name: str, array, toml: str = "") -> Setup:
    """A heightfield surface.toml around ``array`` saved as ``name``."""
    def setup(ws: Path) -> None:
        np.save(ws / name, array, allow_pickle=True)
        (ws / "surface.toml").write_text(f'type = "heightfield"\nfile = "{name}"\n' + toml)
    return setup


def mesh(obj: str | bytes, toml: str = "") -> Setup:
    """A mesh surface.toml around an OBJ file m.obj with content ``obj``."""
    def setup(ws: Path) -> None:
        path = ws / "m.obj"
        path.write_bytes(obj) if isinstance(obj, bytes) else path.write_text(obj)
        (ws / "surface.toml").write_text('type = "mesh"\nfile = "m.obj"\n' + toml)
    return setup


def copy_of(link: str, change: Callable[[Path], None], name: str = "broken") -> Setup:
    """A copy of the linked artefact ``link`` under ``name``, then ``change(copy)``."""
    def setup(ws: Path) -> None:
        source = (ws / link).resolve()
        target = ws / name
        (shutil.copytree if source.is_dir() else shutil.copyfile)(source, target)
        change(target)
    return setup


def model(**changes) -> Setup:
    """m.json: the learned model with ``changes`` to its JSON object (None deletes a key)."""
    def setup(ws: Path) -> None:
        content = json.loads((ws / "model.json").read_text())
        for key, value in changes.items():
            if value is None:
                del content[key]
            else:
                content[key] = value
        (ws / "m.json").write_text(json.dumps(content))
    return setup


def placed(placement) -> Setup:
    """a.json: the adapted model with ``placement`` as where adapt placed the robot."""
    def setup(ws: Path) -> None:
        content = json.loads((ws / "adapted.json").read_text())
        content["surface"]["placement"] = placement
        (ws / "a.json").write_text(json.dumps(content))
    return setup


def csv(rows: list[str], header: str = "t,x,y") -> Setup:
    return text("t.csv", "\n".join([header, *rows]) + "\n")


def wiping_rows(n: int = 200, dt: float = 1 / 30, x=None) -> list[str]:
    """n rows of a 1.2 Hz circle, t from 0 in steps of dt; x overrides the x column."""
    t = np.arange(n) * dt
    xs = 0.08 * np.cos(2 * np.pi * 1.2 * t) if x is None else x
    return [f"{a:.6f},{b:.6g},{c:.6f}" for a, b, c in zip(t, xs, 0.08 * np.sin(2 * np.pi * 1.2 * t))]


def replaced(file: str, old: str, new: str) -> Callable[[Path], None]:
    def change(folder: Path) -> None:
        path = folder / file
        path.write_text(path.read_text().replace(old, new, 1))
    return change


def written(file: str, content: str | bytes) -> Callable[[Path], None]:
    def change(folder: Path) -> None:
        path = folder / file
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)
    return change


def removed(file: str) -> Callable[[Path], None]:
    return lambda folder: (folder / file).unlink()


def cut(file: str, keep: float) -> Callable[[Path], None]:
    """Keep the first ``keep`` fraction of a file's bytes (a copy cut short)."""
    def change(folder: Path) -> None:
        path = folder / file
        content = path.read_bytes()
        path.write_bytes(content[:int(len(content) * keep)])
    return change


GARBAGE = bytes(range(256)) * 4
MODEL_RUN = ("m.json", "-o", "r.csv")
LEARN_OUT = ("-o", "out")
PIPELINE_HEAD = '[pipeline]\nname = "p"\n[inputs]\ntrajectory = "track.csv"\n'

CASES = [
    # ---- synth: options (click's own range and choice checks)
    Case("synth", "duration-negative", ("demo2", "--duration", "-1"), "--duration", "not in the range"),
    Case("synth", "frequency-zero", ("demo2", "--frequency", "0"), "--frequency", "not in the range"),
    Case("synth", "pattern-unknown", ("demo2", "--pattern", "spiral"), "--pattern", "'spiral' is not one of"),
    Case("synth", "amplitude-huge", ("demo2", "--amplitude", "2"), "--amplitude", "not in the range"),
    Case("synth", "colour-unknown", ("demo2", "--sponge-color", "mauve"), "--sponge-color", "is not one of"),
    Case("synth", "seed-not-integer", ("demo2", "--seed", "x"), "--seed", "not a valid integer"),
    # ---- synth-dataset
    Case("synth-dataset", "jobs-negative", ("set", "-j", "-1"), "--jobs", "not in the range x>=1"),
    Case("synth-dataset", "duration-zero", ("set", "--duration", "0"), "--duration", "not in the range"),
    Case("synth-dataset", "pattern-unknown", ("set", "--pattern", "spiral"), "--pattern spiral", "unknown"),
    Case("synth-dataset", "fps-zero", ("set", "--fps", "0"), "--fps", "not in the range"),
    Case("synth-dataset", "frequency-negative", ("set", "--frequency", "-1"), "--frequency", "not in the range"),
    Case("synth-dataset", "seed-not-integer", ("set", "--seed", "x"), "--seed", "not a valid integer"),
    Case("synth-dataset", "demo-folder-taken", ("set", "--pattern", "line"), "set/line_1hz_seed0",
         "exists and is not a directory", lambda ws: ((ws / "set").mkdir(), (ws / "set" / "line_1hz_seed0").touch())),
    # ---- track: the demo directory and its files
    Case("track", "demo-missing", ("nodemo", *LEARN_OUT), "nodemo", "not a directory"),
    Case("track", "demo-is-a-file", ("track.csv", *LEARN_OUT), "track.csv", "not a directory"),
    Case("track", "left-video-missing", ("broken", *LEARN_OUT), "broken/left.mp4", "file not found",
         copy_of("demo", removed("left.mp4"))),
    Case("track", "left-video-a-directory", ("broken", *LEARN_OUT), "broken/left.mp4", "file not found",
         copy_of("demo", lambda d: ((d / "left.mp4").unlink(), (d / "left.mp4").mkdir()))),
    Case("track", "calibration-missing", ("broken", *LEARN_OUT), "calibration.yaml", "file not found",
         copy_of("demo", removed("calibration.yaml"))),
    Case("track", "calibration-binary", ("broken", *LEARN_OUT), "calibration.yaml",
         "not an OpenCV FileStorage file", copy_of("demo", written("calibration.yaml", GARBAGE))),
    Case("track", "calibration-not-yaml", ("broken", *LEARN_OUT), "calibration.yaml",
         "not an OpenCV FileStorage file", copy_of("demo", written("calibration.yaml", "K1: [1, 2\n"))),
    Case("track", "calibration-key-missing", ("broken", *LEARN_OUT), "calibration.yaml", "missing key K2",
         copy_of("demo", replaced("calibration.yaml", "K2:", "K3:"))),
    Case("track", "calibration-width-negative", ("broken", *LEARN_OUT), "calibration.yaml",
         "image_width must be a positive integer",
         copy_of("demo", replaced("calibration.yaml", "image_width: 640", "image_width: -640"))),
    Case("track", "calibration-size-differs", ("broken", *LEARN_OUT), "left.mp4",
         "the calibration is for 800x480",
         copy_of("demo", replaced("calibration.yaml", "image_width: 640", "image_width: 800"))),
    Case("track", "demo-toml-not-toml", ("broken", *LEARN_OUT), "demo.toml", "not valid TOML",
         copy_of("demo", written("demo.toml", "fps = = 3\n"))),
    Case("track", "demo-toml-binary", ("broken", *LEARN_OUT), "demo.toml", "not a text file",
         copy_of("demo", written("demo.toml", GARBAGE))),
    Case("track", "demo-toml-sponge-size", ("broken", *LEARN_OUT), "demo.toml: sponge_size",
         "three positive lengths", copy_of("demo", written("demo.toml", 'sponge_size = ["a", 2]\n'))),
    Case("track", "demo-toml-colour", ("broken", *LEARN_OUT), "demo.toml",
         "not a known colour", copy_of("demo", written("demo.toml", 'sponge_colour = "mauve"\n'))),
    # ---- track: options
    Case("track", "particles-negative", ("demo", *LEARN_OUT, "--particles", "-5"), "--particles", "not in the range"),
    Case("track", "hsv-short", ("demo", *LEARN_OUT, "--hsv", "20,100"), "--hsv", "six integers"),
    Case("track", "roi-outside", ("demo", *LEARN_OUT, "--roi", "600,400,100,100"), "--roi", "does not fit"),
    Case("track", "roi-not-numbers", ("demo", *LEARN_OUT, "--roi", "a,b,c,d"), "--roi", "4 comma-separated integers"),
    Case("track", "colour-and-hsv", ("demo", *LEARN_OUT, "--color", "yellow", "--hsv", "1,2,3,4,5,6"),
         "--color, --hsv and --roi", "give only one"),
    Case("track", "colour-unknown", ("demo", *LEARN_OUT, "--color", "mauve"), "--color", "unknown colour"),
    Case("track", "sponge-size-two", ("demo", *LEARN_OUT, "--sponge-size", "1,2"), "--sponge-size", "3 comma-separated"),
    Case("track", "area-window-text", ("demo", *LEARN_OUT, "--area-window", "x"), "--area-window", "comma-separated"),
    # ---- live: the source, the cameras and their calibration, options
    Case("live", "demo-missing", ("nodemo", *LEARN_OUT), "nodemo", "not a directory"),
    Case("live", "no-source", LEARN_OUT, "SOURCE", "missing argument"),
    Case("live", "left-video-missing", ("broken", *LEARN_OUT), "broken/left.mp4", "file not found",
         copy_of("demo", removed("left.mp4"))),
    Case("live", "calibration-not-yaml", ("broken", *LEARN_OUT), "calibration.yaml",
         "not an OpenCV FileStorage file", copy_of("demo", written("calibration.yaml", "K1: [1, 2\n"))),
    Case("live", "camera-without-calibration", ("--camera", "demo/left.mp4,demo/right.mp4", *LEARN_OUT),
         "--camera", "needs --calibration"),
    Case("live", "camera-one", ("--camera", "demo/left.mp4", "--calibration", "demo/calibration.yaml",
                                *LEARN_OUT), "--camera", "expected LEFT,RIGHT"),
    Case("live", "camera-file-missing", ("--camera", "no.mp4,demo/right.mp4", "--calibration",
                                         "demo/calibration.yaml", *LEARN_OUT), "no.mp4", "file not found"),
    Case("live", "camera-not-a-video", ("--camera", "track.csv,demo/right.mp4", "--calibration",
                                        "demo/calibration.yaml", *LEARN_OUT), "track.csv",
         "cannot be opened by OpenCV"),
    Case("live", "camera-calibration-bad", ("--camera", "demo/left.mp4,demo/right.mp4", "--calibration",
                                            "track.csv", *LEARN_OUT), "track.csv",
         "not an OpenCV FileStorage file"),
    Case("live", "camera-device-at-max-speed", ("--camera", "0,1", "--calibration",
                                                "demo/calibration.yaml", "--speed", "max", *LEARN_OUT),
         "--speed", "max needs video files"),
    Case("live", "calibration-without-camera", ("demo", "--calibration", "demo/calibration.yaml",
                                                *LEARN_OUT), "--calibration", "only with --camera"),
    Case("live", "source-and-camera", ("demo", "--camera", "demo/left.mp4,demo/right.mp4",
                                       "--calibration", "demo/calibration.yaml", *LEARN_OUT),
         "--camera", "either SOURCE"),
    Case("live", "viewer-unknown", ("demo", *LEARN_OUT, "--viewer", "window"), "--viewer",
         "is not one of none, spawn, serve"),
    Case("live", "viewer-port-text", ("demo", *LEARN_OUT, "--viewer", "serve=abc"), "--viewer",
         "not a port number"),
    Case("live", "viewer-connect-url", ("demo", *LEARN_OUT, "--viewer", "connect=http://x:1"), "--viewer",
         "expected a port or a URL"),
    Case("live", "speed-unknown", ("demo", *LEARN_OUT, "--speed", "2"), "--speed", "is not one of"),
    Case("live", "surface-unknown", ("demo", *LEARN_OUT, "--surface", "moon"), "--surface", "unknown surface"),
    Case("live", "colour-unknown", ("demo", *LEARN_OUT, "--color", "mauve"), "--color", "unknown colour"),
    Case("live", "learn-periods-zero", ("demo", *LEARN_OUT, "--learn-periods", "0"), "--learn-periods",
         "not in the range"),
    Case("live", "replay-scale-huge", ("demo", *LEARN_OUT, "--replay-scale", "9"), "--replay-scale",
         "not in the range"),
    # ---- learn: the trajectory CSV
    Case("learn", "csv-missing", ("none.csv", *LEARN_OUT), "none.csv", "file not found"),
    Case("learn", "csv-a-directory", ("demo", *LEARN_OUT), "demo", "is a directory"),
    Case("learn", "csv-binary", ("t.csv", *LEARN_OUT), "t.csv", "not a text file", data("t.csv", GARBAGE)),
    Case("learn", "csv-empty", ("t.csv", *LEARN_OUT), "t.csv", "empty file", text("t.csv", "")),
    Case("learn", "csv-header-only", ("t.csv", *LEARN_OUT), "t.csv", "too short", csv([])),
    Case("learn", "csv-column-missing", ("t.csv", *LEARN_OUT), "t.csv", "missing column(s) y",
         csv(["0,1", "1,2", "2,3"], header="t,x")),
    Case("learn", "csv-duplicate-columns", ("t.csv", *LEARN_OUT), "t.csv", "duplicate column names",
         csv(["0,1,1"] * 3, header="t,x,x")),
    Case("learn", "csv-not-numbers", ("t.csv", *LEARN_OUT), "t.csv", "not a table of numbers",
         csv(["0,1,1", "0.1,one,1", "0.2,1,1"])),
    Case("learn", "csv-ragged-rows", ("t.csv", *LEARN_OUT), "t.csv", "not a table of numbers",
         csv(["0,1,1", "0.1,1", "0.2,1,1"])),
    Case("learn", "csv-nan", ("t.csv", *LEARN_OUT), "t.csv", "column x has NaN or inf (data row 3)",
         csv(wiping_rows(x=np.where(np.arange(200) == 2, np.nan, 0.1)))),
    Case("learn", "csv-inf", ("t.csv", *LEARN_OUT), "t.csv", "column x has NaN or inf",
         csv(wiping_rows(x=np.full(200, np.inf)))),
    Case("learn", "csv-huge-values", ("t.csv", *LEARN_OUT), "t.csv", "column x holds 1e+308 (data row 2)",
         csv(wiping_rows(x=np.where(np.arange(200) % 2, 1e308, 0.0)))),
    Case("learn", "csv-huge-times", ("t.csv", *LEARN_OUT), "t.csv", "column t holds",
         csv([f"{i * 1e300:g},1,1" for i in range(50)])),
    Case("learn", "csv-time-backwards", ("t.csv", *LEARN_OUT), "t.csv", "not strictly increasing (data row 3)",
         csv(["0,1,1", "1,1,1", "0.5,1,1", "2,1,1"])),
    Case("learn", "csv-time-negative", ("t.csv", *LEARN_OUT), "t.csv", "starts at -1 s",
         csv([f"{i / 30 - 1:.6f},{np.cos(i / 5):.4f},{np.sin(i / 5):.4f}" for i in range(200)])),
    Case("learn", "csv-valid-not-flag", ("t.csv", *LEARN_OUT), "t.csv", "must hold only 0 or 1",
         csv(["0,1,1,2", "1,1,1,1", "2,1,1,1"], header="t,x,y,valid")),
    Case("learn", "csv-nothing-valid", ("t.csv", *LEARN_OUT), "t.csv", "no row has valid = 1",
         csv(["0,1,1,0", "1,1,1,0", "2,1,1,0"], header="t,x,y,valid")),
    Case("learn", "csv-too-few-valid", ("t.csv", *LEARN_OUT), "t.csv", "too short, 5 valid rows",
         csv([f"{i},1,1,{int(i < 5)}" for i in range(30)], header="t,x,y,valid")),
    Case("learn", "csv-not-periodic", ("t.csv", *LEARN_OUT), "t.csv", "not periodic",
         csv(wiping_rows(x=np.random.default_rng(1).normal(size=200)))),
    Case("learn", "csv-irregular-times", ("t.csv", *LEARN_OUT), "t.csv", "more than 2e+07 samples",
         csv([f"{i * 0.001:.3f},{np.cos(i):.3f},1" for i in range(100)] + ["9e8,1,1"])),
    Case("learn", "csv-samples-far-apart", ("t.csv", *LEARN_OUT), "t.csv", "is resolvable",
         csv(wiping_rows(n=100, dt=10.0))),
    Case("learn", "mcap-garbage", ("g.mcap", *LEARN_OUT), "g.mcap", "cannot be read as MCAP",
         data("g.mcap", GARBAGE)),
    Case("learn", "mcap-cut-short", ("broken.mcap", *LEARN_OUT), "broken.mcap", "cannot be read as MCAP",
         lambda ws: (ws / "broken.mcap").write_bytes((ws / "track.mcap").read_bytes()[:3000])),
    Case("learn", "mcap-not-a-track", ("learn.mcap", *LEARN_OUT), "learn.mcap", "not a track.mcap"),
    # ---- learn: options
    Case("learn", "mode-unknown", ("track.csv", *LEARN_OUT, "--mode", "sideways"), "--mode", "is not one of"),
    Case("learn", "kernels-text", ("track.csv", *LEARN_OUT, "--kernels", "abc"), "--kernels", "not a valid integer"),
    Case("learn", "kernels-one", ("track.csv", *LEARN_OUT, "--kernels", "1"), "--kernels", "at least 2"),
    Case("learn", "dofs-twice", ("track.csv", *LEARN_OUT, "--dofs", "x,x"), "--dofs", "distinct"),
    Case("learn", "dofs-unknown-column", ("track.csv", *LEARN_OUT, "--dofs", "x,q"), "track.csv", "missing column(s) q"),
    Case("learn", "width-negative", ("track.csv", *LEARN_OUT, "--width", "-1"), "--width", "must be positive"),
    Case("learn", "canonical-unknown", ("track.csv", *LEARN_OUT, "--canonical", "xyz"), "--canonical", "is not one of"),
    Case("learn", "dofs-without-value", ("track.csv", *LEARN_OUT, "--dofs"), "--dofs", "requires an argument"),
    # ---- rollout: the model JSON
    Case("rollout", "model-missing", ("none.json", "-o", "r.csv"), "none.json", "file not found"),
    Case("rollout", "model-binary", MODEL_RUN, "m.json", "not a text file", data("m.json", GARBAGE)),
    Case("rollout", "model-not-json", MODEL_RUN, "m.json", "not a model file, not JSON", text("m.json", "{x")),
    Case("rollout", "model-cut-short", MODEL_RUN, "m.json", "not JSON",
         lambda ws: (ws / "m.json").write_text((ws / "model.json").read_text()[:300])),
    Case("rollout", "model-a-list", MODEL_RUN, "m.json", "expected a JSON object", text("m.json", "[1, 2]")),
    Case("rollout", "model-format", MODEL_RUN, "m.json", "expected 'wipelab.periodic_dmp/1'",
         model(format="wipelab.trajectory/1")),
    Case("rollout", "model-key-missing", MODEL_RUN, "m.json", "missing key(s) weights", model(weights=None)),
    Case("rollout", "model-weights-shape", MODEL_RUN, "m.json", "weights must have shape", model(weights=[[1.0]])),
    Case("rollout", "model-weights-text", MODEL_RUN, "m.json", "could not convert", model(weights="abc")),
    Case("rollout", "model-weights-huge", MODEL_RUN, "m.json", "weights holds values beyond",
         lambda ws: model(weights=(np.ones((2, json.loads((ws / "model.json").read_text())["kernels"]))
                                   * 1e300).tolist())(ws)),
    Case("rollout", "model-goal-nan", MODEL_RUN, "m.json", "goal holds NaN or inf", model(goal=[float("nan"), 0])),
    Case("rollout", "model-frequency-huge", MODEL_RUN, "m.json", "frequency_hz is 1e+308", model(frequency_hz=1e308)),
    Case("rollout", "model-frequency-zero", MODEL_RUN, "m.json", "frequency_hz must be > 0", model(frequency_hz=0)),
    Case("rollout", "model-kernels-negative", MODEL_RUN, "m.json", "kernels must be a positive integer",
         model(kernels=-3)),
    Case("rollout", "model-dofs-number", MODEL_RUN, "m.json", "wipelab.periodic_dmp/1", model(dofs=5)),
    # ---- rollout: options
    Case("rollout", "periods-negative", ("model.json", "-o", "r.csv", "--periods", "-1"), "--periods", "positive"),
    Case("rollout", "periods-huge", ("model.json", "-o", "r.csv", "--periods", "1e12"), "--periods", "samples"),
    Case("rollout", "rate-zero", ("model.json", "-o", "r.csv", "--rate", "0"), "--rate", "positive"),
    Case("rollout", "frequency-zero", ("model.json", "-o", "r.csv", "--frequency", "0"), "--frequency", "positive"),
    Case("rollout", "goal-count", ("model.json", "-o", "r.csv", "--goal", "1"), "--goal", "need 2 finite numbers"),
    Case("rollout", "goal-text", ("model.json", "-o", "r.csv", "--goal", "a,b"), "--goal", "comma-separated numbers"),
    Case("rollout", "amplitude-nan", ("model.json", "-o", "r.csv", "--amplitude-scale", "nan"),
         "--amplitude-scale", "positive"),
    # ---- adapt: the model and the surface (built-in name, TOML, heightfield .npy, mesh .obj)
    Case("adapt", "model-not-json", ("m.json", *LEARN_OUT), "m.json", "not JSON", text("m.json", "{x")),
    Case("adapt", "model-without-xy", ("m.json", *LEARN_OUT), "m.json", "needs x", model(dofs=["a", "b"])),
    Case("adapt", "surface-unknown", ("model.json", *LEARN_OUT, "--surface", "marble"), "--surface", "unknown surface"),
    Case("adapt", "surface-missing", ("model.json", *LEARN_OUT, "--surface", "no.toml"), "no.toml", "does not exist"),
    Case("adapt", "surface-binary", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml", "not a text file",
         data("s.toml", GARBAGE)),
    Case("adapt", "surface-not-toml", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml", "not valid TOML",
         text("s.toml", "type = = 1\n")),
    Case("adapt", "surface-type-unknown", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml",
         "type must be one of", text("s.toml", 'type = "marble"\n')),
    Case("adapt", "surface-key-unknown", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml",
         "unknown key(s) for type 'flat': colour", text("s.toml", 'type = "flat"\ncolour = 1\n')),
    Case("adapt", "surface-friction", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml",
         "friction must be in", text("s.toml", 'type = "flat"\nfriction = 5\n')),
    Case("adapt", "surface-centre-nan", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml",
         "wipe_center must be [x, y]", text("s.toml", 'type = "flat"\nwipe_center = [nan, 0.0]\n')),
    Case("adapt", "heightfield-file-missing", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml",
         "'h.npy' does not exist", text("s.toml", 'type = "heightfield"\nfile = "h.npy"\n')),
    Case("adapt", "heightfield-garbage", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "not a .npy array", lambda ws: (npy("h.npy", np.zeros((3, 3)))(ws), (ws / "h.npy").write_bytes(GARBAGE))),
    Case("adapt", "heightfield-cut-short", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "not a .npy array", lambda ws: (npy("h.npy", np.zeros((50, 50)))(ws),
                                         (ws / "h.npy").write_bytes((ws / "h.npy").read_bytes()[:500]))),
    Case("adapt", "heightfield-1d", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "must be a 2-D array", npy("h.npy", np.zeros(10))),
    Case("adapt", "heightfield-nan", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "NaN or infinite", npy("h.npy", np.full((4, 4), np.nan))),
    Case("adapt", "heightfield-huge", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "heightfield holds 1e+300 m", npy("h.npy", np.full((4, 4), 1e300))),
    Case("adapt", "heightfield-text", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "non-numeric", npy("h.npy", np.array([["a", "b"], ["c", "d"]]))),
    Case("adapt", "heightfield-pickled", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "Object arrays cannot be loaded", npy("h.npy", np.array([[{}, {}], [{}, {}]], dtype=object))),
    Case("adapt", "heightfield-cell-zero", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "cell must be a positive number", npy("h.npy", np.zeros((4, 4)), "cell = 0\n")),
    Case("adapt", "heightfield-cell-inf", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "h.npy",
         "cell must be a positive number", npy("h.npy", np.zeros((4, 4)), "cell = inf\n")),
    Case("adapt", "heightfield-origin", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "surface.toml",
         "origin must be [x, y, z]", npy("h.npy", np.zeros((4, 4)), "origin = [1, 2]\n")),
    Case("adapt", "mesh-binary", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "not a text file", mesh(GARBAGE)),
    Case("adapt", "mesh-vertex-text", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "bad vertex on line 2", mesh("v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n")),
    Case("adapt", "mesh-vertex-two-values", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "a vertex needs x, y and z", mesh("v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")),
    Case("adapt", "mesh-vertex-nan", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "bad vertex on line 2", mesh("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")),
    Case("adapt", "mesh-in-millimetres", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "coordinates are metres", mesh("v 0 0 800\nv 600 0 800\nv 0 600 800\nf 1 2 3\n")),
    Case("adapt", "mesh-face-missing-vertex", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "a face refers to a vertex that does not exist", mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")),
    Case("adapt", "mesh-face-text", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "bad face on line 4", mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n")),
    Case("adapt", "mesh-face-two-vertices", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "a face needs at least three vertices", mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n")),
    Case("adapt", "mesh-no-faces", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "not a triangle mesh", mesh("v 0 0 0\nv 1 0 0\nv 0 1 0\n")),
    Case("adapt", "mesh-grid-too-fine", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "grid points", mesh("v 0 0 0\nv 9 0 0\nv 0 9 0\nf 1 2 3\n", "cell = 0.0001\n")),
    Case("adapt", "mesh-no-top", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "m.obj",
         "no upward-facing surface", mesh("v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n")),
    Case("adapt", "mesh-a-directory", ("model.json", *LEARN_OUT, "--surface", "surface.toml"), "surface.toml",
         "'m.obj' does not exist", lambda ws: (mesh("")(ws), (ws / "m.obj").unlink(), (ws / "m.obj").mkdir())),
    # ---- adapt: options
    Case("adapt", "feedback-unknown", ("model.json", *LEARN_OUT, "--feedback", "foo"), "--feedback", "is not one of"),
    Case("adapt", "kernels-three", ("model.json", *LEARN_OUT, "--kernels", "3"), "--kernels", "must be in [5, 200]"),
    Case("adapt", "slowdown-below-one", ("model.json", *LEARN_OUT, "--slowdown", "0.5"), "--slowdown", "must be >= 1"),
    Case("adapt", "amplitude-scale-five", ("model.json", *LEARN_OUT, "--amplitude-scale", "5"), "--amplitude-scale",
         "must be in (0, 3]"),
    Case("adapt", "centre-one-value", ("model.json", *LEARN_OUT, "--center", "1"), "--center", "2 comma-separated"),
    Case("adapt", "base-text", ("model.json", *LEARN_OUT, "--base", "x"), "--base", "3 comma-separated"),
    Case("adapt", "reference-unknown", ("model.json", *LEARN_OUT, "--reference", "xyz"), "--reference", "is not one of"),
    Case("adapt", "periods-zero", ("model.json", *LEARN_OUT, "--periods", "0"), "--periods", "not in the range"),
    Case("adapt", "tempos-four", ("model.json", *LEARN_OUT, "--tempos", "1,4"), "--tempos", "must be in (0, 3]"),
    Case("adapt", "tempos-text", ("model.json", *LEARN_OUT, "--tempos", "fast"), "--tempos",
         "comma-separated numbers"),
    Case("adapt", "unreachable", ("model.json", *LEARN_OUT, "--center", "0.88,-0.58", "--base", "0,0,0"),
         "model.json", "the arm cannot reach the movement"),
    Case("adapt", "nowhere-to-stand", ("model.json", *LEARN_OUT, "--surface", "s.toml"), "model.json",
         "the arm cannot reach the movement", text("s.toml", 'type = "flat"\nheight = 1.35\n')),
    # ---- replay
    Case("replay", "model-not-json", ("m.json", *LEARN_OUT), "m.json", "not JSON", text("m.json", "[")),
    Case("replay", "model-without-z", ("model.json", *LEARN_OUT, "--mode", "learned"), "model.json", "no learned z"),
    Case("replay", "mode-unknown", ("adapted.json", *LEARN_OUT, "--mode", "sideways"), "--mode", "is not one of"),
    Case("replay", "scale-zero", ("adapted.json", *LEARN_OUT, "--frequency-scale", "0"), "--frequency-scale",
         "positive scales"),
    Case("replay", "scale-seven", ("adapted.json", *LEARN_OUT, "--frequency-scale", "7"), "--frequency-scale",
         "at most 4 times the demonstrated tempo"),
    Case("replay", "placement-text", ("a.json", *LEARN_OUT), "a.json", "surface.placement is not what adapt writes",
         placed("here")),
    Case("replay", "placement-base-two-values", ("a.json", *LEARN_OUT), "a.json",
         "surface.placement is not what adapt writes", placed({"base": [0.1, 0.2]})),
    Case("replay", "base-text", ("adapted.json", *LEARN_OUT, "--base", "x"), "--base", "3 comma-separated"),
    Case("replay", "surface-not-toml", ("adapted.json", *LEARN_OUT, "--surface", "s.toml"), "s.toml",
         "not valid TOML", text("s.toml", "[")),
    Case("replay", "periods-zero", ("adapted.json", *LEARN_OUT, "--periods", "0"), "--periods", "not in the range"),
    Case("replay", "extra-arguments", ("adapted.json", *LEARN_OUT, "3", "4"), "replay:",
         "unexpected extra arguments"),
    # ---- run: the pipeline file, its inputs and options (no run directory may appear)
    Case("run", "pipeline-missing", ("no.toml", "-o", "r"), "no.toml", "file not found"),
    Case("run", "pipeline-binary", ("p.toml", "-o", "r"), "p.toml", "not a text file", data("p.toml", GARBAGE)),
    Case("run", "pipeline-not-toml", ("p.toml", "-o", "r"), "p.toml", "not valid TOML", text("p.toml", "[stages\n")),
    Case("run", "pipeline-unknown-table", ("p.toml", "-o", "r"), "p.toml", "unknown table(s) stage",
         text("p.toml", "[stage.learn]\n")),
    Case("run", "pipeline-no-stages", ("p.toml", "-o", "r"), "p.toml", "no stages", text("p.toml", PIPELINE_HEAD)),
    Case("run", "stage-command-unknown", ("p.toml", "-o", "r"), "p.toml", "unknown command 'wipe'",
         text("p.toml", PIPELINE_HEAD + '[stages.w]\ncommand = "wipe"\ninput = "trajectory"\n')),
    Case("run", "stage-input-missing", ("p.toml", "-o", "r"), "p.toml", "not found",
         text("p.toml", PIPELINE_HEAD.replace("track.csv", "none.csv") + '[stages.learn]\ninput = "trajectory"\n')),
    Case("run", "stage-option-unknown", ("p.toml", "-o", "r"), "p.toml", "has no option 'kernel'",
         text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\nkernel = 3\n')),
    Case("run", "stage-option-value", ("p.toml", "-o", "r"), "p.toml", "stage learn: --mode",
         text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\nmode = "sideways"\n')),
    Case("run", "later-stage-option-value", ("p.toml", "-o", "r", "--set", "rollout.periods=many"), "p.toml",
         "--periods: 'many' is not a valid float",
         text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n'
              '[stages.rollout]\ninput = "learn:model.json"\n')),
    Case("run", "stage-file-missing", ("p.toml", "-o", "r"), "p.toml", "none.toml not found",
         text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n[stages.adapt]\n'
              'input = "learn:model.json"\nsurface = { file = "none.toml" }\n')),
    Case("run", "set-malformed", ("p.toml", "-o", "r", "--set", "kernels"), "--set kernels",
         "expected STAGE.KEY=VALUE", text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')),
    Case("run", "set-unknown-stage", ("p.toml", "-o", "r", "--set", "wipe.x=1"), "--set wipe.x=1",
         "no stage named 'wipe'", text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')),
    Case("run", "input-unknown", ("p.toml", "-o", "r", "--input", "video=x"), "--input video=x",
         "no input 'video'", text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')),
    # ---- dataset
    Case("dataset", "data-missing", ("none", "--pipeline", "p.toml", "-o", "d"), "none", "not a directory",
         text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')),
    Case("dataset", "no-demos", ("empty", "--pipeline", "p.toml", "-o", "d"), "empty", "no demo directory",
         lambda ws: ((ws / "empty").mkdir(), text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')(ws))),
    Case("dataset", "pipeline-two-inputs", (".", "--pipeline", "p.toml", "-o", "d"), "p.toml", "exactly one entry",
         text("p.toml", PIPELINE_HEAD + 'other = "track.csv"\n[stages.learn]\ninput = "trajectory"\n')),
    Case("dataset", "pipeline-missing", (".", "--pipeline", "none.toml", "-o", "d"), "none.toml", "file not found"),
    Case("dataset", "jobs-zero", (".", "--pipeline", "p.toml", "-j", "0"), "--jobs", "not in the range x>=1"),
    Case("dataset", "data-is-a-file", ("track.csv", "--pipeline", "p.toml", "-o", "d"), "track.csv", "not a directory",
         text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')),
    Case("dataset", "pipeline-not-toml", (".", "--pipeline", "p.toml", "-o", "d"), "p.toml", "not valid TOML",
         text("p.toml", "[[[\n")),
    Case("dataset", "pipeline-binary", (".", "--pipeline", "p.toml", "-o", "d"), "p.toml", "not a text file",
         data("p.toml", GARBAGE)),
    Case("dataset", "set-malformed", (".", "--pipeline", "p.toml", "-o", "d", "--set", "x"), "--set x",
         "expected STAGE.KEY=VALUE", text("p.toml", PIPELINE_HEAD + '[stages.learn]\ninput = "trajectory"\n')),
    # ---- report: everything it reads in a run directory
    Case("report", "run-missing", ("none",), "none", "not a directory"),
    Case("report", "run-is-a-file", ("track.csv",), "track.csv", "not a directory"),
    Case("report", "nothing-finished", ("empty",), "empty", "no finished stage", lambda ws: (ws / "empty").mkdir()),
    Case("report", "metrics-cut-short", ("broken",), "adapt/metrics.json", "not valid JSON",
         copy_of("run", cut("adapt/metrics.json", 0.5))),
    Case("report", "metrics-binary", ("broken",), "adapt/metrics.json", "not a text file",
         copy_of("run", written("adapt/metrics.json", GARBAGE))),
    Case("report", "metrics-a-list", ("broken",), "broken/adapt", "does not hold what adapt writes",
         copy_of("run", written("adapt/metrics.json", "[1, 2]"))),
    Case("report", "metrics-missing", ("broken",), "adapt/metrics.json", "file not found",
         copy_of("run", removed("adapt/metrics.json"))),
    Case("report", "model-cut-short", ("broken",), "learn/model.json", "not valid JSON",
         copy_of("run", cut("learn/model.json", 0.5))),
    Case("report", "learn-mcap-garbage", ("broken",), "learn/learn.mcap", "not a readable log",
         copy_of("run", written("learn/learn.mcap", GARBAGE))),
    Case("report", "learn-mcap-cut-short", ("broken",), "learn/learn.mcap", "not a readable log",
         copy_of("run", cut("learn/learn.mcap", 0.3))),
    Case("report", "adapt-mcap-missing", ("broken",), "adapt/adapt.mcap", "file not found",
         copy_of("run", removed("adapt/adapt.mcap"))),
    # ---- view: the recordings it joins
    Case("view", "path-missing", ("none",), "none", "no such file or directory"),
    Case("view", "not-a-recording", ("track.csv",), "track.csv", "not a Rerun recording"),
    Case("view", "folder-without-recordings", ("empty",), "empty", "no .rrd recording", lambda ws: (ws / "empty").mkdir()),
    Case("view", "recording-garbage", ("g.rrd", "--save", "joined.rrd"), "g.rrd", "not a readable Rerun recording",
         data("g.rrd", GARBAGE)),
    Case("view", "recording-cut-short", ("broken.rrd", "--save", "joined.rrd"), "broken.rrd",
         "not a readable Rerun recording", copy_of("learn.rrd", lambda p: p.write_bytes(p.read_bytes()[:4000]),
                                                   "broken.rrd")),
]


@pytest.mark.parametrize("case", CASES, ids=[f"{c.command}-{c.id}" for c in CASES])
def test_bad_input_is_one_line_exit_2_and_leaves_nothing(case, workspace):
    if case.setup is not None:
        case.setup(workspace)
    before = tree(workspace)
    result = invoke([case.command, *case.argv])
    assert result.exit_code == 2, (result.output, result.exception)
    error_line(result.stderr, case.names, case.says)
    assert result.stdout == ""
    assert tree(workspace) == before


def test_every_command_has_bad_input_cases():
    from wipelab.cli import cli

    missing = set(cli.list_commands(None)) - {case.command for case in CASES}
    assert not missing, f"add bad-input cases for {', '.join(sorted(missing))}"


@pytest.mark.parametrize("argv, names", [
    (["learn", "secret.csv", "-o", "open/out"], "secret.csv"),
    (["rollout", "secret.json", "-o", "open/r.csv"], "secret.json"),
    (["track", "demo_calibration", "-o", "open/out"], "demo_calibration/calibration.yaml"),
    (["track", "demo_video", "-o", "open/out"], "demo_video/left.mp4"),
    (["adapt", "model.json", "-o", "open/out", "--surface", "secret.toml"], "secret.toml"),
    (["replay", "secret.json", "-o", "open/out"], "secret.json"),
    (["run", "p.toml", "-o", "open/run"], "secret.csv"),
    (["view", "secret.rrd", "--save", "open/joined.rrd"], "secret.rrd"),
], ids=lambda value: value[0] if isinstance(value, list) else None)
def test_a_file_the_user_may_not_read_is_named(argv, names, unprivileged):
    runner, folder, env = unprivileged
    before = tree(folder)
    completed = run_process(argv, folder, runner.prefix, env)
    assert completed.returncode == 2, completed.stderr
    error_line(completed.stderr, names, "cannot be read (permission denied)")
    after = tree(folder)
    assert after == before, {k: (before.get(k), after.get(k)) for k in before.keys() | after.keys()
                             if before.get(k) != after.get(k)}


def test_a_viewer_address_nobody_listens_at_is_one_line_exit_2_not_a_session_that_blocks(
        workspace, monkeypatch):
    """``--viewer connect=PORT`` with no viewer there: the stream's buffer would fill and
    block the session for good (as it did, in bench_live, for 25 minutes)."""
    import socket

    import wipelab.live.viewer as viewer

    monkeypatch.setattr(viewer, "LISTEN_WAIT_S", 0.3)
    with socket.socket() as probe:  # a port nobody listens at
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    before = tree(workspace)
    result = invoke(["live", "demo", *LEARN_OUT, "--viewer", f"connect={port}"])
    assert result.exit_code == 2, (result.output, result.exception)
    error_line(result.stderr, "--viewer", f"nothing listens at 127.0.0.1:{port}")
    assert tree(workspace) == before
