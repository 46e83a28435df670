"""The world: walls, bounds, start pose, grids, geometry, and world files.

The bottom layer of robotlib with `robotlib.sensing`: it imports nothing of
robotlib above it (only the robot's constants in `robotlib.p3dx`, the JIT
options and `robotlib._random`).

- `World`, `Grid` (`model`, `grid`), their numba kernels in `_kernels`
- `generate_world`, `reachable_pairs`: seeded test worlds of five kinds (`generate`)
- `wrap_angle`, `compose`, `relative` (`geometry`)
- ``.wld`` (`wld`) and MobileSim ``.map`` (`mapfile`) files; `WorldFileError`
  and the formats' shared rules (`fileformat`)
- `load_world`, `world_names`, `read_world`, `WORLDS_DIR`, and `seeded_world`
  (a bench's world per seed, ``gen-KIND`` drawn afresh) (`catalog`)
"""

from .catalog import WORLDS_DIR, load_world, read_world, seeded_world, world_names
from .fileformat import MAP_MAGICS, MAX_EXTENT, WorldFileError
from .generate import KINDS, generate_world, reachable_pairs
from .geometry import compose, relative, wrap_angle
from .grid import Grid
from .mapfile import format_map, parse_map, read_map, write_map
from .model import END_FACE, POINT_SIZE, World
from .wld import format_wld, parse_wld, read_wld, write_wld

__all__ = [
    "MAP_MAGICS",
    "MAX_EXTENT",
    "END_FACE",
    "POINT_SIZE",
    "WORLDS_DIR",
    "KINDS",
    "Grid",
    "World",
    "WorldFileError",
    "compose",
    "format_map",
    "format_wld",
    "generate_world",
    "load_world",
    "parse_map",
    "parse_wld",
    "read_map",
    "read_wld",
    "reachable_pairs",
    "read_world",
    "relative",
    "seeded_world",
    "world_names",
    "wrap_angle",
    "write_map",
    "write_wld",
]
