"""Every stage's MCAP as Foxglove reads it (from its schemas, without the URDF or Rerun):
series a message path can plot, the robot's body and the sponge as solids on frames that
/tf moves, events in the Log panel."""

import csv
import re

import numpy as np
import pybullet
import pytest
from click.testing import CliRunner

from wipelab.cli import cli
from wipelab.logs import mcap_topics, read_mcap_topic
from wipelab.sim.armar3 import armar3b_urdf_path
from wipelab.sim.sponge import SpongeParams
from wipelab.vision.sponge_box import SpongeBox

#: What a Foxglove message path can address after ``/topic.``.
PLOTTABLE = re.compile(r"[A-Za-z0-9_]+")


@pytest.fixture(scope="module")
def track_mcap(tmp_path_factory):
    folder = tmp_path_factory.mktemp("track")
    runner = CliRunner()
    result = runner.invoke(cli, ["synth", str(folder / "demo"), "--pattern", "circle",
                                 "--frequency", "1.2", "--duration", "2", "--seed", "3", "-q"])
    assert result.exit_code == 0, result.output
    result = runner.invoke(cli, ["track", str(folder / "demo"), "-o", str(folder / "track"),
                                 "--particles", "60", "-q"])
    assert result.exit_code == 0, result.output
    return folder / "track" / "track.mcap"


def tf_frames(mcap) -> tuple[set, set]:
    """(every frame /tf names, the frames /tf moves: children)."""
    parents, children = set(), set()
    for _, message in read_mcap_topic(mcap, "/tf"):
        for transform in message["transforms"]:
            parents.add(transform["parent_frame_id"])
            children.add(transform["child_frame_id"])
    return parents | children, children


def contract_problems(mcap) -> list[str]:
    """What a Foxglove user would trip over in ``mcap``: JSON keys a message path cannot
    address, scene entities on frames /tf does not know, events that are not foxglove.Log."""
    frames, _ = tf_frames(mcap)
    problems = []
    for topic, info in mcap_topics(mcap).items():
        messages = read_mcap_topic(mcap, topic)
        if info["message_encoding"] == "json":
            keys = {key for _, message in messages for key in message}
            problems += [f"{topic}: key {key!r}" for key in sorted(keys)
                         if not PLOTTABLE.fullmatch(key)]
        if info["schema"] == "foxglove.SceneUpdate":
            problems += [f"{topic}: entity {entity['id']} on unknown frame {entity['frame_id']!r}"
                         for _, message in messages for entity in message["entities"]
                         if entity["frame_id"] not in frames]
        if topic.endswith("/events") and info["schema"] != "foxglove.Log":
            problems.append(f"{topic}: events as {info['schema']}")
    return problems


def test_track_mcap(track_mcap):
    assert contract_problems(track_mcap) == []
    topics = mcap_topics(track_mcap)
    assert topics["/track/sponge"]["schema"] == "foxglove.SceneUpdate"
    assert topics["/stereo/left/overlay"]["schema"] == "foxglove.ImageAnnotations"
    drawn = {t: m for t, m in read_mcap_topic(track_mcap, "/track/sponge") if m["entities"]}
    assert len(drawn) == topics["/track/position"]["message_count"]   # one per tracked frame
    # the sponge box where it was fitted, a flat square the colour region's size elsewhere
    track = track_mcap.parent / "track.csv"
    rows = list(csv.DictReader(track.open()))
    def size_at(t):
        nearest = min(drawn, key=lambda ns: abs(ns - t * 1e9))
        return [drawn[nearest]["entities"][0]["cubes"][0]["size"][a] for a in "xyz"]

    sizes = {row["quality"]: size_at(float(row["t"])) for row in rows if row["quality"]}
    sponge = SpongeBox()
    assert sizes["box"] == pytest.approx([sponge.length, sponge.width, sponge.height], rel=1e-6)
    if "centroid" in sizes:
        x, y, z = sizes["centroid"]
        assert x == y and z < x / 2
    first = min(t for t, _ in read_mcap_topic(track_mcap, "/track/position"))
    (overlay,) = [m for t, m in read_mcap_topic(track_mcap, "/stereo/left/overlay") if t == first]
    lines = [a for a in overlay["points"] if a["type"] == "LINE_LIST"]
    assert len(lines) == 1 and len(lines[0]["points"]) == 24           # the box's 12 edges


@pytest.mark.slow
@pytest.mark.parametrize("stage", ["learn", "adapt", "replay"])
def test_robot_stage_mcaps(robot_run, stage):
    _, run = robot_run
    assert contract_problems(run / stage / f"{stage}.mcap") == []


@pytest.mark.slow
@pytest.mark.parametrize("stage", ["adapt", "replay"])
def test_robot_body_and_sponge_are_drawn_from_the_mcap_alone(robot_run, stage):
    _, run = robot_run
    mcap = run / stage / f"{stage}.mcap"
    _, moved = tf_frames(mcap)
    (_, body), = read_mcap_topic(mcap, "/robot/body")
    entities = {e["frame_id"]: e for e in body["entities"]}
    expected = urdf_visuals_by_pybullet()
    assert set(entities) == set(expected)
    for link, shapes in expected.items():
        entity = entities[link]
        assert link in moved and entity["frame_locked"]
        drawn = [(kind, p) for kind in ("cubes", "cylinders", "spheres") for p in entity[kind]]
        assert len(drawn) == len(shapes)
        for (kind, primitive), (true_kind, size, position, orientation) in zip(drawn, shapes):
            assert kind == true_kind
            assert [primitive["size"][a] for a in "xyz"] == pytest.approx(size, abs=1e-6)
            assert [primitive["pose"]["position"][a] for a in "xyz"] == pytest.approx(
                position, abs=1e-6)
            q = np.array([primitive["pose"]["orientation"][a] for a in "xyzw"])
            assert abs(np.dot(q, orientation)) == pytest.approx(1.0, abs=1e-6)
    (_, sponge), = read_mcap_topic(mcap, "/robot/sponge")
    (entity,) = sponge["entities"]
    (cube,) = entity["cubes"]
    assert entity["frame_id"] == "sponge" and "sponge" in moved
    assert [cube["size"][a] for a in "xyz"] == pytest.approx(SpongeParams().size)
    events = [m["message"] for _, m in read_mcap_topic(mcap, f"/{stage}/events")]
    assert "F/T calibration" in events and events[-1] == "end"


def urdf_visuals_by_pybullet() -> dict[str, list]:
    """The robot's visual solids as PyBullet reads the URDF: link -> [(primitive list name,
    bounding-box size (3,), position (3,), orientation (x, y, z, w))], in URDF order."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(armar3b_urdf_path()), useFixedBase=True,
                                 physicsClientId=client)
        names = {-1: pybullet.getBodyInfo(body, physicsClientId=client)[0].decode()}
        for j in range(pybullet.getNumJoints(body, physicsClientId=client)):
            names[j] = pybullet.getJointInfo(body, j, physicsClientId=client)[12].decode()
        out = {}
        for shape in pybullet.getVisualShapeData(body, physicsClientId=client):
            kind, dims = shape[2], shape[3]
            if kind == pybullet.GEOM_BOX:
                entry = ("cubes", list(dims))
            elif kind == pybullet.GEOM_SPHERE:
                entry = ("spheres", [2 * dims[0]] * 3)
            else:                                   # cylinder: (length, radius)
                entry = ("cylinders", [2 * dims[1], 2 * dims[1], dims[0]])
            out.setdefault(names[shape[1]], []).append((*entry, list(shape[5]),
                                                        np.array(shape[6])))
        return out
    finally:
        pybullet.disconnect(client)
