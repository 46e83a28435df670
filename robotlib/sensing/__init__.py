"""Sensing: ray casting against walls and grids, and the Pioneer sonar model.

Above `robotlib.world` only: it imports the world and the robot's constants,
never the simulator, the robot API or anything above them. The numba kernels
(`_kernels`) import nothing of robotlib but the JIT options.

- `cast_rays` (exact, against segments), `cast_rays_grid` and `grid_field`
  (fast, on an occupancy grid's clearance field) (`raycast`)
- `SonarModel`, `expected_ranges`, `simulate_ranges` (`sonar`)
- `LaserModel`, `laser_poses`, `expected_laser`, `simulate_laser`: the SICK
  LMS-200 (`laser`)
"""

from .laser import LaserModel, expected_laser, laser_poses, simulate_laser
from .raycast import cast_rays, cast_rays_grid, grid_field
from .sonar import SonarModel, expected_ranges, simulate_ranges

__all__ = [
    "LaserModel",
    "SonarModel",
    "cast_rays",
    "cast_rays_grid",
    "expected_laser",
    "expected_ranges",
    "grid_field",
    "laser_poses",
    "simulate_laser",
    "simulate_ranges",
]
