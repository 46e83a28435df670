"""The paper's robot API: `robot(address)` and the functions that drive any backend.

- `Robot`, `RobotState`, `RobotTimeout`: the interface every backend
  implements (`base`)
- `robot`, `move`, `setheading`, ... and `BACKENDS`, the address-scheme
  registry (``sim:``, ``tcp://``, ``serial://``), whose backends are imported
  on first use (`api`)

Imports only the world's geometry and the robot's constants; the backends
(`robotlib.sim`, `robotlib.pioneer`) import this package, never the reverse.
"""

from .api import (
    BACKENDS,
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
from .base import Robot, RobotState, RobotTimeout

__all__ = [
    "BACKENDS",
    "Robot",
    "RobotState",
    "RobotTimeout",
    "disconnect",
    "isheadingdone",
    "ismovedone",
    "move",
    "pose",
    "readsonar",
    "robot",
    "setdeltaheading",
    "setheading",
    "setrotvel",
    "setvel",
    "stop",
]
