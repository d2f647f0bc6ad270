"""Surfaces: built-ins, the user's heightfield and mesh files, and their PyBullet bodies."""

import numpy as np
import pybullet
import pytest

from wipelab.errors import InputError
from wipelab.sim.surfaces import bowl_surface, flat_surface, load_surface, sink_surface
from wipelab.sim.world import surface_body


def test_builtins_have_the_promised_shapes():
    flat = load_surface("flat")
    assert flat.height_at(np.array([0.6, -0.2])) == pytest.approx(0.80)
    bowl = load_surface("bowl")
    depth = np.nanmax(bowl.heights) - np.nanmin(bowl.heights)
    assert depth >= 0.06
    sink = load_surface("sink")
    y_edge = sink.parameters["edge_y"]
    x = sink.wipe_center[0]
    assert sink.height_at(np.array([x, y_edge + 0.06])) - sink.height_at(
        np.array([x, y_edge - 0.01])) == pytest.approx(0.02)


def test_tilted_flat_table_is_a_plane_through_the_wiping_centre():
    surface = flat_surface(tilt_y=0.1)
    cx, cy = surface.wipe_center
    assert surface.height_at(np.array([cx, cy])) == pytest.approx(0.80)
    assert surface.height_at(np.array([cx + 0.1, cy])) == pytest.approx(0.80 - 0.1 * np.tan(0.1))
    assert np.isnan(surface.height_at(np.array([3.0, 0.0])))


@pytest.mark.parametrize("surface", [flat_surface(tilt_x=0.05), bowl_surface(), sink_surface()],
                         ids=["flat", "bowl", "sink"])
def test_pybullet_body_matches_the_true_height(surface):
    client = pybullet.connect(pybullet.DIRECT)
    try:
        surface_body(client, surface)
        xy = np.random.default_rng(0).uniform([0.45, -0.5], [0.9, 0.1], size=(40, 2))
        hits = pybullet.rayTestBatch([[x, y, 3.0] for x, y in xy], [[x, y, -3.0] for x, y in xy],
                                     physicsClientId=client)
        z = np.array([hit[3][2] for hit in hits])
    finally:
        pybullet.disconnect(client)
    # a heightfield cell is two triangles, the reference is bilinear: they differ by a
    # fraction of a millimetre where the surface curves
    assert np.abs(z - surface.height_at(xy)).max() < 5e-4


def test_heightfield_toml(tmp_path):
    heights = np.zeros((30, 40))
    heights[10:20, 10:30] = 0.02
    np.save(tmp_path / "h.npy", heights)
    (tmp_path / "s.toml").write_text('type = "heightfield"\nfile = "h.npy"\ncell = 0.02\n'
                                     'origin = [0.4, -0.6, 0.78]\nwipe_center = [0.6, -0.3]\n')
    surface = load_surface(tmp_path / "s.toml")
    assert surface.name == "s" and surface.kind == "heightfield"
    assert surface.height_at(np.array([0.4 + 15 * 0.02, -0.6 + 20 * 0.02])) == pytest.approx(0.80)
    assert surface.height_at(np.array([0.41, -0.59])) == pytest.approx(0.78)


@pytest.mark.parametrize("array", [np.zeros(5), np.zeros((3, 3, 3)), np.zeros((1, 9))])
def test_heightfield_of_wrong_shape_is_refused(tmp_path, array):
    np.save(tmp_path / "h.npy", array)
    (tmp_path / "s.toml").write_text('type = "heightfield"\nfile = "h.npy"\n')
    with pytest.raises(InputError, match=r"h\.npy: heightfield must be a 2-D array"):
        load_surface(tmp_path / "s.toml")


def test_builtin_type_with_parameters_and_bad_keys(tmp_path):
    (tmp_path / "deep.toml").write_text('type = "bowl"\ndepth = 0.09\n')
    assert load_surface(tmp_path / "deep.toml").parameters["depth"] == 0.09
    (tmp_path / "bad.toml").write_text('type = "bowl"\ncolour = "red"\n')
    with pytest.raises(InputError, match="unknown key"):
        load_surface(tmp_path / "bad.toml")
    with pytest.raises(InputError, match="unknown surface 'marble'"):
        load_surface("marble")


def test_mesh_obj_is_rasterised_to_its_top(tmp_path):
    # a ramp 0.4 x 0.4 m rising 0.05 m along x, at table height
    (tmp_path / "ramp.obj").write_text(
        "v 0.4 -0.5 0.8\nv 0.8 -0.5 0.85\nv 0.8 -0.1 0.85\nv 0.4 -0.1 0.8\nf 1 2 3 4\n")
    (tmp_path / "ramp.toml").write_text('type = "mesh"\nfile = "ramp.obj"\ncell = 0.01\n')
    surface = load_surface(tmp_path / "ramp.toml")
    assert surface.kind == "mesh"
    assert surface.height_at(np.array([0.6, -0.3])) == pytest.approx(0.825, abs=1e-6)
