"""The laser scan equals a brute-force ray cast against every wall and human disc."""

import numpy as np

from socialzoo.core.config import LaserConfig
from socialzoo.core.geometry import ray_circle_hit, ray_segment_hit
from socialzoo.core.laser import laser_scan, ray_angles
from socialzoo.maps.map_file import load_map
from socialzoo.scenarios.generator import ScenarioConfig, generate_scenario
from socialzoo.scenarios.start_state import scenarios_to_state

CROWD = ScenarioConfig(min_humans=25, max_humans=25)


def brute_force(state, walls, cfg, radius):
    pose = state.robot_pose[:, 0]
    angles = pose[:, 2:3] + ray_angles(cfg)
    direction = np.stack((np.cos(angles), np.sin(angles)), axis=-1)
    wall_hit = ray_segment_hit(
        pose[:, None, None, :2], direction[:, :, None], walls[:, :2], walls[:, 2:]
    ).min(-1)
    human_hit = ray_circle_hit(
        pose[:, None, None, :2], direction[:, :, None], state.human_pos[:, None], radius
    )
    human_hit = np.where(state.human_mask[:, None], human_hit, np.inf).min(-1)
    return np.minimum(np.minimum(wall_hit, human_hit), cfg.max_range)


def test_scan_matches_brute_force_on_gdc1():
    m = load_map("gdc1")
    state = scenarios_to_state([generate_scenario(m, s, CROWD) for s in range(4)])
    # Put some humans right in front of the robots so that discs are hit too.
    state.human_pos[:, 0] = state.robot_pose[:, 0, :2] + 1.0 * np.stack(
        (np.cos(state.robot_pose[:, 0, 2]), np.sin(state.robot_pose[:, 0, 2])), axis=-1
    )
    cfg = LaserConfig(num_rays=90, fov_deg=270.0, max_range=12.0)
    got = laser_scan(state, m.wall_index, cfg, 0.2)[:, 0]
    want = brute_force(state, m.walls, cfg, 0.2)
    np.testing.assert_allclose(got, want, atol=1e-9)
    centre = np.argmin(np.abs(ray_angles(cfg)))
    assert np.all(got[:, centre] < 0.81), "the human 1 m ahead must block the centre ray"


def test_full_circle_and_noise_are_row_deterministic():
    m = load_map("open_room")
    scenarios = [generate_scenario(m, s, ScenarioConfig(min_humans=5, max_humans=5)) for s in range(3)]
    state = scenarios_to_state(scenarios)
    cfg = LaserConfig(num_rays=64, fov_deg=360.0, max_range=20.0, noise_std=0.05)
    assert len(ray_angles(cfg)) == 64
    batch = laser_scan(state, m.wall_index, cfg, 0.2)
    assert np.all((batch >= 0) & (batch <= cfg.max_range))
    for i in range(3):
        alone = laser_scan(state.rows(i), m.wall_index, cfg, 0.2)
        np.testing.assert_array_equal(alone[0], batch[i])
    clean = laser_scan(state, m.wall_index, LaserConfig(num_rays=64, fov_deg=360.0, max_range=20.0), 0.2)
    noise = batch - clean
    assert 0.03 < noise.std() < 0.07
    state.step_count += 1
    assert not np.array_equal(laser_scan(state, m.wall_index, cfg, 0.2), batch), "noise must change per step"
