"""manifest.json records inputs with hashes, parameters, versions and seed."""

import hashlib
import json

from wipelab.manifest import build_manifest, write_json


def test_manifest_contents_and_determinism(tmp_path):
    data = tmp_path / "traj.csv"
    data.write_bytes(b"t,x\n0,1\n")
    manifest = build_manifest("learn", {"trajectory": data}, {"kernels": 25}, seed=3)
    assert manifest["inputs"]["trajectory"]["sha256"] == hashlib.sha256(b"t,x\n0,1\n").hexdigest()
    assert manifest["parameters"] == {"kernels": 25}
    assert manifest["seed"] == 3
    assert {"wipelab", "numpy", "python"} <= set(manifest["versions"])
    write_json(tmp_path / "a.json", manifest)
    write_json(tmp_path / "b.json", build_manifest("learn", {"trajectory": data}, {"kernels": 25}, 3))
    assert (tmp_path / "a.json").read_bytes() == (tmp_path / "b.json").read_bytes()
    assert json.loads((tmp_path / "a.json").read_text())["stage"] == "learn"
