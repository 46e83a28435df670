"""MobileSim's single-ray sonar, offered beside robotlib's cone."""

import math

import numpy as np

from robotlib.p3dx import SONAR_POSES
from robotlib.sensing import SonarModel, cast_rays, expected_ranges
from robotlib.sim import OdometryNoise, Simulator
from robotlib.world import World, load_world


def sensor_poses(pose):
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    return np.array(
        [[x + c * a - s * b, y + s * a + c * b, th + h] for a, b, h in SONAR_POSES]
    )


def test_single_ray_reads_the_wall_on_each_axis_at_any_angle():
    world = load_world("corridor")
    model = SonarModel.single_ray()
    assert model.is_single_ray and not SonarModel().is_single_ray
    rng = np.random.default_rng(3)
    poses = world.sample_free_poses(50, rng)
    got = expected_ranges(world, poses, model)
    for pose, z in zip(poses, got, strict=True):
        rays = np.array(
            [
                cast_rays(world, p[None], np.zeros(1), 5.0)[0, 0]
                for p in sensor_poses(pose)
            ]
        )
        want = np.clip(np.where(np.isfinite(rays) & (rays < 5.0), rays, 5.0), 0.1, 5.0)
        np.testing.assert_allclose(z, want, atol=1e-9)


def test_cone_and_single_ray_differ_where_a_wall_is_oblique():
    # a wall at 60 degrees to the front sonar's axis: the ray echoes (MobileSim),
    # the cone's specular model misses it; a wall off the axis: only the cone sees it
    wall = World([[2.0, -3.0, 2.0 + 6 * math.cos(math.radians(60)), 3.0]])
    pose = np.array([[0.0, 0.0, 0.0]])
    cone = expected_ranges(wall, pose, SonarModel())
    ray = expected_ranges(wall, pose, SonarModel.single_ray())
    assert not np.array_equal(cone, ray)
    assert np.all(ray[0, 3:5] < 5.0)


def test_the_simulator_runs_with_the_single_ray_model():
    world = load_world("corridor")
    sim = Simulator(
        world, seed=0, sonar=SonarModel.single_ray(noise_std=0.0, dropout_prob=0.0),
        odometry=OdometryNoise.none(),
    )  # fmt: skip
    body = sim.add_robot()
    sim.step()
    want = expected_ranges(world, body.true_pose[None], sim.sonar)[0]
    np.testing.assert_allclose(body.state.sonar, want, atol=1e-12)
