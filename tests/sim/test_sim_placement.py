"""Placement by default: the pure search on a made-up arm, and the real arm's map and IK."""

import math

import numpy as np
import pytest

from wipelab.errors import InputError
from wipelab.sim.placement import (NOMINAL_TOOL_DROP, PlacementError, PlacementRequest,
                                   choose_placements, platform_outline)
from wipelab.sim.reach import HIP_PITCHES, cell_ik, grid_points, load_reach_map, reach_cell
from wipelab.sim.surfaces import flat_surface, heightfield_surface, load_surface
from wipelab.sim.task import REACH_TOLERANCE, TaskOptions, place_task
from wipelab.sim.world import BasePose

from sim_models import circle_model

#: The made-up arm: it reaches with margin inside a ball around its "shoulder" (base_link).
SHOULDER, ARM_LENGTH = np.array([0.15, -0.25, 1.25]), 0.75


def ball_arm():
    """A ReachMap of the made-up arm on the real map's grid: one torso lean, margin 0.2 rad
    inside the ball, a joint speed of 2 rad/s per m/s of TCP speed in any direction."""
    reach = load_reach_map()
    points = grid_points()
    inside = np.linalg.norm(points - SHOULDER, axis=-1) < ARM_LENGTH
    inverse = np.zeros((*inside.shape, 7, 2))
    inverse[..., 0, 0] = inverse[..., 1, 1] = 2.0
    return type(reach)(np.zeros(1), reach.start, reach.step,
                       np.where(inside, 0.2, -1.0)[None], inverse[None])


def circle_request(surface, radius=0.1, frequency_hz=0.5, **fixed):
    phase = np.linspace(0, 2 * math.pi, 128, endpoint=False)
    path = radius * np.column_stack([np.cos(phase), np.sin(phase)])
    velocity = radius * np.column_stack([-np.sin(phase), np.cos(phase)])
    return PlacementRequest(path, velocity, frequency_hz, np.array([0.04, 0.12]),
                            np.array([0.10, 0.07]), surface.wipe_center, **fixed)


def in_base_frame(points_xy, base: BasePose):
    c, s = math.cos(base.yaw), math.sin(base.yaw)
    return (np.asarray(points_xy) - [base.x, base.y]) @ np.array([[c, -s], [s, c]])


def over(surface, points_xy):
    index = np.rint((np.asarray(points_xy) - surface.origin[:2]) / surface.cell).astype(int)
    inside = np.all((index >= 0) & (index < surface.heights.shape), axis=-1)
    return inside


def test_keeps_a_declared_wiping_centre_and_stands_off_the_table_within_reach():
    surface = flat_surface()
    request = circle_request(surface)
    best = choose_placements(request, surface, ball_arm(), joint_speed_limit=2.5)[0]
    assert best.centre == pytest.approx(surface.wipe_center)
    assert not over(surface, platform_outline(best.base)).any()
    path = in_base_frame(best.centre + request.path, best.base)
    height = surface.height_at(best.centre + request.path) + NOMINAL_TOOL_DROP
    tcp = np.column_stack([path, height])
    assert np.linalg.norm(tcp - SHOULDER, axis=1).max() < ARM_LENGTH
    # joint rate 2 rad/s per m/s, path speed 0.1 m per rad: 2.5 / (2 * 0.1) rad/s
    assert best.max_frequency_hz == pytest.approx(2.5 / 0.2 / (2 * math.pi), rel=0.05)


def test_goes_to_a_far_surface_and_stays_on_the_covered_part():
    heights = np.zeros((61, 81))
    footprint = np.ones_like(heights, dtype=bool)
    footprint[:, :40] = False                         # only the left half has a surface
    surface = heightfield_surface("far", heights, 0.01, [2.0, -0.4, 0.8])
    surface = type(surface)(**{**surface.__dict__, "footprint": footprint})
    request = circle_request(surface)
    best = choose_placements(request, surface, ball_arm(), joint_speed_limit=2.5)[0]
    assert best.base.x > 1.2                          # the platform drove there
    sponge = best.centre + request.path + [0.04, 0.12]
    assert np.all(sponge[:, 1] > -0.4 + 0.40)         # on the covered half
    assert not over(surface, platform_outline(best.base)).any()


def test_a_fixed_platform_pose_is_kept():
    surface = flat_surface()
    base = BasePose(-0.05, 0.05, 0.0)
    best = choose_placements(circle_request(surface, base=base), surface, ball_arm(), 2.5)[0]
    assert (best.base.x, best.base.y, best.base.yaw) == (base.x, base.y, base.yaw)


def test_the_sponge_beside_the_hand_must_stay_on_the_surface_too():
    surface = flat_surface()                          # y from -0.70 to 0.30
    on_table = np.array([0.6, 0.19])                  # the path reaches y = 0.29
    with pytest.raises(PlacementError, match="does not fit on the surface 'flat' there"):
        choose_placements(circle_request(surface, centre=on_table), surface, ball_arm(), 2.5)
    best = choose_placements(circle_request(surface, centre=on_table - [0, 0.25]), surface,
                             ball_arm(), 2.5)[0]
    assert best.centre == pytest.approx(on_table - [0, 0.25])


def test_refuses_a_surface_too_small_or_too_high_saying_so():
    small = heightfield_surface("stool", np.zeros((21, 21)), 0.01, [0.5, -0.3, 0.7])
    with pytest.raises(PlacementError, match="does not fit on the surface 'stool' anywhere"):
        choose_placements(circle_request(small, radius=0.15), small, ball_arm(), 2.5)
    high = flat_surface(height=1.5)
    with pytest.raises(PlacementError, match=r"the arm cannot reach .* \(1\.50-1\.50 m high"):
        choose_placements(circle_request(high), high, ball_arm(), 2.5)


def test_the_shipped_reach_map_is_what_the_ik_gives():
    reach = load_reach_map()
    points = grid_points()
    rng = np.random.default_rng(7)
    for p in rng.choice(len(HIP_PITCHES), 3, replace=False):
        ik = cell_ik(float(HIP_PITCHES[p]))
        for i, j, k in zip(*(rng.integers(0, n, 4) for n in points.shape[:3])):
            margin, inverse = reach_cell(ik, points[i, j, k])
            assert reach.margin[p, i, j, k] == pytest.approx(margin, abs=1e-6)
            assert reach.inverse[p, i, j, k] == pytest.approx(inverse, abs=0.026)


@pytest.mark.parametrize("spec", ["flat", "bowl", "low", "high-sloped"])
def test_real_arm_placements_pass_the_full_check(spec, tmp_path):
    surface = {"low": lambda: flat_surface(height=0.60),
               "high-sloped": lambda: flat_surface(height=1.0, tilt_y=math.radians(10))}.get(
        spec, lambda: load_surface(spec))()
    placed = place_task(circle_model(), surface, TaskOptions())
    record = placed.record
    assert record["chosen_by"] == "search" and placed.plan.posture.error <= REACH_TOLERANCE
    assert not over(surface, platform_outline(placed.options.base, 0.0)).any()
    assert record["max_frequency_hz"] > 0.5 and record["base"] == [
        placed.options.base.x, placed.options.base.y, placed.options.base.yaw]


def test_real_arm_refusal_names_the_limit():
    with pytest.raises(InputError, match="MODEL: the arm cannot reach the movement"):
        place_task(circle_model(), flat_surface(height=1.4), TaskOptions())


def test_a_sponge_held_off_to_one_side_of_the_whole_path():
    """The sponge's footprint need not contain the path's centre (a short stroke, the sponge
    beside the hand)."""
    surface = flat_surface()
    phase = np.linspace(0, 2 * math.pi, 64, endpoint=False)
    path = np.column_stack([0.01 * np.sin(phase), np.zeros_like(phase)])
    request = PlacementRequest(path, np.gradient(path, axis=0), 1.0, np.array([0.04, 0.25]),
                               np.array([0.10, 0.07]), surface.wipe_center)
    best = choose_placements(request, surface, ball_arm(), 2.5)[0]
    assert best.centre == pytest.approx(surface.wipe_center)
