"""A deterministic Pioneer 3-DX simulator stepped on simulated time.

`Simulator` holds a world and any number of robots (`robotlib.sim.body.SimBody`)
and advances them together, one 100 ms cycle per `Simulator.step`, as a
Pioneer's controller does. `SimRobot` wraps a body as a
`robotlib.robot.Robot`, so the paper's API runs on it; each poll is one
simulated cycle. Imports the world, sensing and the robot interface; never
an estimator, plotting or anything above the simulator.
"""

from __future__ import annotations

import numpy as np

from .._random import as_rng
from ..p3dx import CYCLE
from ..robot import Robot, RobotState
from ..sensing import LaserModel, SonarModel
from ..world import World, load_world
from ..world.geometry import wrap_angle
from .body import OdometryNoise, SimBody, scene_obstacles

__all__ = ["Simulator", "SimRobot"]


class Simulator:
    """Robots in a world, stepped together on simulated time.

    Parameters
    ----------
    world : World
        The world the robots live in.
    seed : numpy.random.Generator, int or None
        Randomness for odometry slip and sonar noise; each robot gets its own
        stream spawned from it, so a seed reproduces every run bit for bit.
    sonar : SonarModel, optional
        The robots' sonar ring and its noise (default: a Pioneer 3-DX's).
    odometry : OdometryNoise, optional
        The odometry error model.
    laser : LaserModel, optional
        The laser each robot carries (default: a SICK LMS-200), read with
        `SimBody.scan_laser` or `SimRobot.readlaser`.
    end_faces : bool
        Whether the sonar and laser see the walls' free ends as end faces
        (`robotlib.world.World.sensed_obstacles`, the default) or see bare
        segments (a wall met end-on is invisible; for comparison only).
    """

    def __init__(
        self,
        world: World,
        seed: np.random.Generator | int | None = None,
        sonar: SonarModel | None = None,
        odometry: OdometryNoise | None = None,
        laser: LaserModel | None = None,
        end_faces: bool = True,
    ):
        self.world = world
        self.sensed_obstacles = world.sensed_obstacles if end_faces else world.obstacles
        self.sonar = SonarModel() if sonar is None else sonar
        self.laser = LaserModel() if laser is None else laser
        self.odometry = OdometryNoise() if odometry is None else odometry
        self._rng = as_rng(seed)
        self.bodies: list[SimBody] = []
        self.time = 0.0

    def add_robot(self, pose=None) -> SimBody:
        """Add a robot at ``pose`` (m, rad; default: the world's start pose).

        Raises
        ------
        ValueError
            If the robot would overlap a wall or another robot.
        """
        pose = np.array(self.world.start if pose is None else pose, dtype=float)
        if pose.shape != (3,):
            raise ValueError(f"pose must be (x, y, theta), got shape {pose.shape}")
        pose[2] = wrap_angle(pose[2])
        body = SimBody(self, pose, self._rng.spawn(1)[0])
        others = [b.true_pose for b in self.bodies]
        if not body._clear(pose, self.world.obstacles, others):
            raise ValueError(f"a robot at {tuple(pose)} would overlap a wall or robot")
        self.bodies.append(body)
        return body

    def step(self) -> None:
        """Advance every robot by one cycle (`robotlib.p3dx.CYCLE`, 100 ms)."""
        for body in self.bodies:
            others = [b.true_pose for b in self.bodies if b is not body]
            body._advance(self.world.obstacles, others)
        for body in self.bodies:
            body._sense(scene_obstacles(self.sensed_obstacles, self.bodies, body))
        self.time += CYCLE

    def reset(self) -> None:
        """Put every robot back at its initial pose, stopped, odometry reset."""
        for body in self.bodies:
            body._reset()
        self.time = 0.0


class SimRobot(Robot):
    """The in-process simulator behind the `robotlib.robot.Robot` interface.

    Each poll advances the whole simulator by one cycle.

    Parameters
    ----------
    sim : Simulator
        The simulator.
    body : SimBody, optional
        The body to drive; default: a new one at the world's start pose.
    """

    def __init__(self, sim: Simulator, body: SimBody | None = None):
        super().__init__()
        self.simulator = sim
        self.body = sim.add_robot() if body is None else body
        self._state = self.body.state

    @classmethod
    def from_address(cls, address: str, seed=None, **options) -> SimRobot:
        """Open ``"sim:NAME_OR_PATH"``; ``options`` go to `Simulator`."""
        where = address.split(":", 1)[1] or "corridor"
        return cls(Simulator(load_world(where), seed=seed, **options))

    def true_pose(self) -> np.ndarray:
        """Return the true pose ``(x, y, theta)`` (for evaluation only)."""
        return self.body.true_pose.copy()

    def _send(self, command: str, value=None) -> None:
        self.body.command(command, value)

    def _has_laser(self) -> bool:
        return True

    def _read_laser(self) -> np.ndarray:
        return self.body.scan_laser()

    def _update(self) -> RobotState:
        self.simulator.step()
        return self.body.state

    def _close(self) -> None:
        self.body.command("STOP")
