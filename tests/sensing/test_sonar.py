import math

import numpy as np
import pytest

from robotlib import load_world
from robotlib.p3dx import SONAR_POSES
from robotlib.sensing import SonarModel, cast_rays, expected_ranges, simulate_ranges
from robotlib.world import World
from tests import naive

ROOM = World([[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]], start=(2, 2, 0))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["corridor", "office"])
def test_noisy_scan_matches_numpy_reference(name):
    world = load_world(name)
    model = SonarModel(noise_std=0.05, dropout_prob=0.2, multipath_prob=0.6)
    poses = world.sample_free_poses(30, rng=1)
    rng = np.random.default_rng(2)
    uniforms = rng.random((30, 8, 2))
    normals = rng.standard_normal((30, 8))
    from robotlib.sensing.sonar import _scan

    fast = _scan(world, poses, model, uniforms, normals)
    ref = naive.sonar_scan(world.obstacles, poses, model, uniforms, normals)
    np.testing.assert_allclose(fast, ref, atol=1e-9)


def test_parallel_and_serial_scans_agree():
    world = load_world("corridor")
    poses = world.sample_free_poses(200, rng=4)  # > 64 poses: the parallel kernel
    many = expected_ranges(world, poses)
    few = np.vstack([expected_ranges(world, p) for p in poses[:20]])
    np.testing.assert_array_equal(many[:20], few)


def test_ideal_sonar_reads_the_nearest_wall_in_its_cone():
    model = SonarModel().ideal()
    z = expected_ranges(ROOM, [2.0, 2.0, 0.0], model)[0]
    # The sonar at +-90 deg looks straight at the side walls, 2 m away from the
    # centre, minus its offset of 0.136 m from the centre line.
    assert z[0] == pytest.approx(2.0 - 0.136)
    assert z[7] == pytest.approx(2.0 - 0.136)
    # Every cone reading is at most the range along its axis.
    axis = cast_rays(ROOM, [2.0, 2.0, 0.0], SONAR_POSES[:, 2])[0]
    assert np.all(z <= axis + 0.2)
    assert np.all(z >= 0.1) and np.all(z <= 5.0)


def test_a_cone_is_not_a_ray():
    # A thin post just off a sonar's axis: a single ray misses it, the cone does not.
    post = World([[1.0, 0.15, 1.0, 0.2]], bounds=(-3, -3, 3, 3))
    sensor = np.array([[0.0, 0.0, 0.0]])
    cone = SonarModel(sensors=sensor).ideal()
    ray = SonarModel(sensors=sensor, n_rays=1).ideal()
    assert expected_ranges(post, [0, 0, 0], ray)[0, 0] == 5.0
    # The cone ray at 10 degrees meets the post.
    hit = 1.0 / math.cos(math.radians(10.0))
    assert expected_ranges(post, [0, 0, 0], cone)[0, 0] == pytest.approx(hit)


def test_grazing_walls_give_no_echo_or_multipath():
    # Looking along a corridor wall at a grazing angle: no echo from it.
    wall = World([[0.0, 0.5, 4.0, 0.5]], bounds=(-1, -1, 5, 2))
    sensor = np.array([[0.0, 0.0, 0.0]])
    specular = SonarModel(sensors=sensor, noise_std=0.0, dropout_prob=0.0)
    assert expected_ranges(wall, [0, 0, 0], specular)[0, 0] == 5.0
    assert expected_ranges(wall, [0, 0, 0], specular.ideal())[0, 0] < 5.0
    # With a mirror wall beyond, the reflected ray comes back as a long reading.
    mirror = World([[0.0, 0.5, 4.0, 0.5], [3.0, -2.0, 3.0, 3.0]], bounds=(-1, -3, 5, 4))
    always = SonarModel(
        sensors=sensor, noise_std=0.0, dropout_prob=0.0, multipath_prob=1.0
    )
    z = simulate_ranges(mirror, [0, 0, 0], always, rng=0)[0, 0]
    direct = expected_ranges(mirror, [0, 0, 0], always.ideal())[0, 0]
    assert direct < z < 5.0


def test_dropouts_and_noise_follow_their_parameters():
    poses = np.tile([2.0, 2.0, 0.0], (4000, 1))
    exact = expected_ranges(ROOM, poses[:1], SonarModel(specular_angle=None))[0]
    model = SonarModel(noise_std=0.02, dropout_prob=0.1, specular_angle=None)
    z = simulate_ranges(ROOM, poses, model, rng=5)
    dropped = z == 5.0
    assert dropped.mean() == pytest.approx(0.1, abs=0.01)
    rel = (z[~dropped] - np.broadcast_to(exact, z.shape)[~dropped]) / np.broadcast_to(
        exact, z.shape
    )[~dropped]
    assert rel.std() == pytest.approx(0.02, rel=0.05)
    assert abs(rel.mean()) < 0.002


def test_noise_terms_can_be_switched_off_and_seeds_reproduce():
    world = load_world("corridor")
    poses = world.sample_free_poses(50, rng=0)
    ideal = SonarModel().ideal()
    np.testing.assert_array_equal(
        simulate_ranges(world, poses, ideal, rng=1),
        expected_ranges(world, poses, ideal),
    )
    a = simulate_ranges(world, poses, rng=9)
    b = simulate_ranges(world, poses, rng=9)
    c = simulate_ranges(world, poses, rng=10)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert np.all((a >= 0.1) & (a <= 5.0))


def test_model_validates_parameters():
    with pytest.raises(ValueError):
        SonarModel(dropout_prob=1.5)
    with pytest.raises(ValueError):
        SonarModel(n_rays=0)
    with pytest.raises(ValueError):
        SonarModel(sensors=np.zeros((8, 2)))
