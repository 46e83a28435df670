"""Foundation benchmarks: ray casts per second and simulator cycles per second.

Run: ``python bench/bench_foundation.py`` (set ``NUMBA_NUM_THREADS=1`` for
per-thread figures). Prints numbers; asserts nothing.
"""

import math
import time

import numpy as np

from robotlib import load_world, robot
from robotlib.sensing import cast_rays, cast_rays_grid, grid_field
from robotlib.sim import Simulator
from robotlib.world import World


def best_of(fn, repeat=5):
    fn()  # compile / warm up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def rays_per_second(cast, poses, angles):
    seconds = best_of(lambda: cast(poses, angles))
    return poses.shape[0] * len(angles) / seconds


def grid_world_400(rng):
    """A 20 m x 20 m room with 60 random box obstacles: 400 x 400 cells at 5 cm."""
    segs = [[0, 0, 20, 0], [20, 0, 20, 20], [20, 20, 0, 20], [0, 20, 0, 0]]
    for x, y in rng.uniform(1, 19, size=(60, 2)):
        s = rng.uniform(0.2, 1.0)
        segs += [[x, y, x + s, y], [x + s, y, x + s, y + s], [x + s, y + s, x, y + s]]
        segs += [[x, y + s, x, y]]
    return World(segs, bounds=(0, 0, 20, 20), start=(0.5, 0.5, 0))


def main():
    import numba

    print(f"numba threads: {numba.get_num_threads()}")
    rng = np.random.default_rng(0)
    angles = np.linspace(-math.pi, math.pi, 64, endpoint=False)
    for name in ("corridor", "office"):
        world = load_world(name)
        poses = world.sample_free_poses(2000, rng, radius=0.0)
        rate = rays_per_second(
            lambda p, a, w=world: cast_rays(w, p, a, 5.0), poses, angles
        )
        segs = len(world.obstacles)
        print(f"segment rays/s   {name:9s} ({segs:4d} segs): {rate:12,.0f}")
    for name in ("office", "maze"):
        world = load_world(name)
        grid = world.occupancy_grid(0.05)
        field = grid_field(grid)
        poses = world.sample_free_poses(20000, rng, radius=0.0)
        rate = rays_per_second(
            lambda p, a, g=grid, f=field: cast_rays_grid(g, p, a, 5.0, f), poses, angles
        )
        shape = f"{grid.shape[0]}x{grid.shape[1]}"
        print(f"grid rays/s      {name:9s} ({shape} at 5 cm):  {rate:12,.0f}")
    world = grid_world_400(rng)
    grid = world.occupancy_grid(0.05)
    poses = world.sample_free_poses(20000, rng, radius=0.0)
    field = grid_field(grid)
    rate = rays_per_second(
        lambda p, a: cast_rays_grid(grid, p, a, 5.0, field), poses, angles
    )
    print(f"grid rays/s      {grid.shape[0]}x{grid.shape[1]} grid, 5 m: {rate:12,.0f}")
    rate = rays_per_second(
        lambda p, a: cast_rays(world, p, a, 5.0), poses[:2000], angles
    )
    print(f"segment rays/s   same world ({len(world.obstacles)} segs):  {rate:12,.0f}")

    for name in ("corridor", "office"):
        sim = Simulator(load_world(name), seed=0)
        body = sim.add_robot()
        body.command("RVEL", 0.3)
        body.command("VEL", 0.2)
        sim.step()
        n = 5000
        t0 = time.perf_counter()
        for _ in range(n):
            sim.step()
        rate = n / (time.perf_counter() - t0)
        print(f"simulator cycles/s {name:9s} (8 sonar cones x 7 rays): {rate:10,.0f}")

    def paper():
        r = robot("sim:corridor", seed=0)
        for _ in range(10):
            r.move(0.5)
            while not r.ismovedone():
                pass
            r.setdeltaheading(math.pi)
            while not r.isheadingdone():
                pass
        r.disconnect()

    print(f"paper example (10 x move 0.5 m, turn 180 deg): {best_of(paper, 3):.3f} s")


if __name__ == "__main__":
    main()
