"""The simulator: Pioneer 3-DX bodies on simulated time, and the ``sim:`` backend.

- `SimBody`, `OdometryNoise`: one robot's motion, odometry error, collisions
  and sonar (`body`)
- `Simulator`, `SimRobot`: several bodies in a world, stepped together; the
  `robotlib.robot.Robot` backend behind ``robot("sim:...")`` (`simulator`)

The robot's constants are in `robotlib.p3dx` (a leaf every layer may read).
Imports the world, sensing and the robot interface; never an estimator,
controller, planner, plotting or the course tools.
"""

from .body import OdometryNoise, SimBody
from .simulator import SimRobot, Simulator

__all__ = ["OdometryNoise", "SimBody", "SimRobot", "Simulator"]
