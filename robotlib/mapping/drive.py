"""Recorded drives for mapping: odometry, truth, sonar and laser per record.

`record_drive` drives a simulated P3-DX through waypoints (steered on its
true pose, as a person with a joystick would) and records, every few
cycles, the odometry pose, the true pose, the eight sonar readings and a
laser scan. `ROUTES` holds the tours of the shipped worlds the labs and
benches use; `perturbed_route` jitters a route's waypoints for hidden or
seeded variants.

Imports the simulator and the world; never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._random import as_rng
from ..sensing import SonarModel
from ..sensing.laser import LaserModel
from ..sim import OdometryNoise, Simulator
from ..world import World, load_world
from ..world.geometry import wrap_angle

__all__ = ["DriveLog", "record_drive", "ROUTES", "perturbed_route"]


def _room(door_x: float, door_y: float, side: int, x0, x1, y0, y1) -> list:
    """Enter a room through its door, go round it 1 m inside its walls, leave."""
    inner = (door_x, door_y + side * 0.9)
    loop = [(x0 + 1, y0 + 1), (x1 - 1, y0 + 1), (x1 - 1, y1 - 1), (x0 + 1, y1 - 1)]
    # start the loop at the corner nearest the door
    k = int(np.argmin([math.hypot(x - inner[0], y - inner[1]) for x, y in loop]))
    loop = loop[k:] + loop[:k] + [loop[k]]
    return [(door_x, 7.5), inner, *loop, inner, (door_x, 7.5)]


ROUTES: dict[str, list[tuple[float, float]]] = {
    # the office: along the corridor, round each room it opens into
    "office": [
        *_room(2.5, 6.5, -1, 0, 5, 0, 6.5),
        *_room(3.0, 8.5, 1, 0, 6, 8.5, 15),
        *_room(7.5, 6.5, -1, 5, 10, 0, 6.5),
        *_room(9.0, 8.5, 1, 6, 12, 8.5, 15),
        *_room(12.0, 6.5, -1, 10, 15, 0, 6.5),
        (15.0, 7.5),
        (15.0, 9.4),
        (13.0, 9.6),
        (13.0, 14.0),
        (19.0, 14.0),
        (19.0, 9.6),
        (19.0, 14.0),
        (15.0, 13.5),
        (15.0, 9.4),
        (15.0, 7.5),
        *_room(17.0, 6.5, -1, 15, 20, 0, 6.5),
        (19.0, 7.5),
    ],
    # the loop building: once round the corridor ring, then 4 m on
    "loop": [(19.5, 1.5), (19.5, 14.5), (1.5, 14.5), (1.5, 1.5), (6.0, 1.5)],
}
"""Waypoints (m) of the shipped tours, by world name."""


def perturbed_route(route, rng: np.random.Generator | int | None, scale: float = 0.2):
    """Return the route with each waypoint moved by uniform noise of ``scale`` m."""
    rng = as_rng(rng)
    r = np.asarray(route, dtype=float)
    return [tuple(p) for p in r + rng.uniform(-scale, scale, r.shape)]


@dataclass(frozen=True, eq=False)
class DriveLog:
    """A recorded drive: one row per record.

    Attributes
    ----------
    world : World
        Where it was driven.
    odometry, truth : numpy.ndarray, shape (T, 3)
        Odometry and true poses, m and rad.
    sonar : numpy.ndarray, shape (T, S)
        Sonar readings, m.
    laser : numpy.ndarray, shape (T, n_beams) or None
        Laser scans, m (None if not recorded).
    sonar_model : SonarModel
    laser_model : LaserModel
    time : numpy.ndarray, shape (T,)
        Simulated time of each record, s.
    """

    world: World
    odometry: np.ndarray
    truth: np.ndarray
    sonar: np.ndarray
    laser: np.ndarray | None
    sonar_model: SonarModel
    laser_model: LaserModel
    time: np.ndarray

    def __len__(self) -> int:
        return len(self.odometry)

    def every(self, k: int) -> DriveLog:
        """Every ``k``-th record (the first and then each ``k`` on)."""
        laser = None if self.laser is None else self.laser[::k]
        return DriveLog(
            self.world, self.odometry[::k], self.truth[::k], self.sonar[::k],
            laser, self.sonar_model, self.laser_model, self.time[::k],
        )  # fmt: skip


def record_drive(
    world: World | str,
    route=None,
    seed: np.random.Generator | int | None = 0,
    every: int = 2,
    speed: float = 0.4,
    laser: bool = True,
    odometry: OdometryNoise | None = None,
    sonar: SonarModel | None = None,
    laser_model: LaserModel | None = None,
    max_cycles: int = 20000,
) -> DriveLog:
    """Drive the simulator through ``route`` and record it.

    Parameters
    ----------
    world : World or str
        The world (or a shipped world's name).
    route : sequence of (x, y), optional
        Waypoints, m (default: ``ROUTES[world.name]``).
    seed : numpy.random.Generator, int or None
        Seeds the simulator (odometry slip, sonar and laser noise).
    every : int
        Cycles (100 ms) between records.
    speed : float
        Cruising speed, m/s.
    laser : bool
        Record laser scans too (their noise has its own stream: sonar and
        odometry are the same either way).
    odometry, sonar, laser_model : optional
        The simulator's models.
    max_cycles : int
        Give up after this many cycles (`RuntimeError`).

    Returns
    -------
    DriveLog
    """
    world = load_world(world) if isinstance(world, str) else world
    route = ROUTES[world.name] if route is None else route
    sim = Simulator(world, seed=seed, sonar=sonar, odometry=odometry, laser=laser_model)
    body = sim.add_robot()
    rows: list[tuple] = []

    def record():
        st = body.state
        scan = body.scan_laser() if laser else None
        rows.append((st.pose, body.true_pose.copy(), st.sonar, scan, sim.time))

    sim.step()
    record()
    cycle = 0
    for wx, wy in route:
        while True:
            x, y, th = body.true_pose
            dist = math.hypot(wx - x, wy - y)
            if dist < 0.2:
                break
            err = wrap_angle(math.atan2(wy - y, wx - x) - th)
            if abs(err) > 0.6:
                v, w = 0.0, math.copysign(min(1.0, 2 * abs(err)), err)
            else:
                v, w = speed * math.cos(err) * min(1.0, dist + 0.3), 1.5 * err
            body.command("VEL", v)
            body.command("RVEL", w)
            sim.step()
            cycle += 1
            if cycle % every == 0:
                record()
            if cycle > max_cycles:
                raise RuntimeError(f"route not done after {max_cycles} cycles")
    odo, truth, son, scans, t = zip(*rows, strict=True)
    return DriveLog(
        world=world,
        odometry=np.array(odo),
        truth=np.array(truth),
        sonar=np.array(son),
        laser=np.array(scans) if laser else None,
        sonar_model=sim.sonar,
        laser_model=sim.laser,
        time=np.array(t),
    )
