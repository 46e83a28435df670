"""robotlib: mobile-robotics courseware around a simulated (or real) Pioneer 3-DX.

The paper's robot API is importable from the top level::

    from robotlib import robot, move, ismovedone, readsonar, disconnect
"""

from . import _config  # noqa: F401  (first: numba imported lean, `robotlib._config`)
from ._versions import __version__
from .robot import (
    Robot,
    RobotState,
    RobotTimeout,
    disconnect,
    isheadingdone,
    ismovedone,
    move,
    pose,
    readsonar,
    robot,
    setdeltaheading,
    setheading,
    setrotvel,
    setvel,
    stop,
)
from .world import World, load_world, world_names

__all__ = [
    "__version__",
    "Robot",
    "RobotState",
    "RobotTimeout",
    "World",
    "disconnect",
    "isheadingdone",
    "ismovedone",
    "load_world",
    "move",
    "pose",
    "readsonar",
    "robot",
    "setdeltaheading",
    "setheading",
    "setrotvel",
    "setvel",
    "stop",
    "world_names",
]
