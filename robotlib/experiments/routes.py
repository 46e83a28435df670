"""The paper's route: a seeded, obstacle-avoiding drive logged step by step.

The simulated Pioneer starts at the world's start pose and drives steps of
about 0.5 m, centring itself between the walls and turning around where the
way ahead is blocked, so along the corridor and back. `drive_route` drives it
once per seed and logs odometry, sonar and ground truth in a `RouteLog`;
every filter then runs on that same log. Imports the simulator and the
world; never an estimator or plotting.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..sim import Simulator
from ..world import World
from ..world.geometry import wrap_angle

__all__ = ["RouteLog", "drive_route", "MAX_STEPS"]

MAX_STEPS = 75
"""The paper's longest run, steps."""


@dataclass
class RouteLog:
    """One drive of the robot, step by step (step 0 is the start).

    Attributes
    ----------
    odometry : numpy.ndarray, shape (T, 3)
        Odometry pose after each step, m and rad.
    sonar : numpy.ndarray, shape (T, 8)
        Sonar scan after each step, m.
    truth : numpy.ndarray, shape (T, 3)
        True pose after each step, m and rad.
    world : World
        Where it drove.
    seed : int
        The seed of the simulator and of the route.
    kidnapped_at : int or None
        The step before whose motion the robot was moved to another place
        without its odometry knowing (`robotlib.experiments.tours`), or None.
    trace : numpy.ndarray or None, shape (C, 3)
        The true pose after every 100 ms cycle of the drive, m and rad (the
        tours record it; None for `drive_route`).
    """

    odometry: np.ndarray
    sonar: np.ndarray
    truth: np.ndarray
    world: World
    seed: int
    kidnapped_at: int | None = None
    trace: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.odometry)


def _wait(sim: Simulator, body, max_cycles: int = 150) -> None:
    """Step until the robot has started and stopped again (bounded)."""
    for k in range(max_cycles):
        sim.step()
        if k >= 2 and not body.moving:
            return


def drive_route(
    world: World,
    seed: int,
    n_steps: int = MAX_STEPS,
    step_length: float = 0.5,
    clearance: float = 0.9,
) -> RouteLog:
    """Drive the simulated robot on a seeded, obstacle-avoiding route.

    Each step: read the sonar; if the way ahead (the +-10 and +-30 degree
    sonars) is clear beyond ``clearance``, steer back to the course (and,
    between two side walls, a little towards the middle), add seeded noise
    and move ``step_length`` (shorter near an obstacle); otherwise turn
    around, or make a quarter turn towards the more open side at a bend
    (both sonars of a side beyond 2 m) or when the previous step was blocked
    too. Every step is a turn and/or a move, then one sonar scan.

    Parameters
    ----------
    world : World
        Where to drive (the robot starts at ``world.start``).
    seed : int
        Seeds the simulator (odometry slip, sonar noise) and the route.
    n_steps : int
        Scans in the log, the start's included.
    step_length : float
        Nominal move per step, m.
    clearance : float
        Distance ahead below which the robot turns instead of moving, m.

    Returns
    -------
    RouteLog
    """
    sim = Simulator(world, seed=seed)
    body = sim.add_robot()
    rng = np.random.default_rng([seed, 1])
    sim.step()
    odo, sonar, truth = [], [], []

    def log():
        state = body.state
        odo.append(state.pose)
        sonar.append(state.sonar)
        truth.append(body.true_pose.copy())

    log()
    course = float(body.state.pose[2])
    blocked = False
    for _ in range(n_steps - 1):
        s = body.state.sonar
        heading = float(body.state.pose[2])
        front, diagonal = min(s[3], s[4]), min(s[2], s[5])
        if front > clearance and diagonal > 0.6 * clearance:
            turn = wrap_angle(course - heading)
            if max(s[0], s[7]) < 1.5:  # walls on both sides: centre
                turn += float(np.clip(0.2 * (s[0] - s[7]), -0.15, 0.15))
            turn = float(np.clip(turn, -0.5, 0.5)) + 0.05 * rng.standard_normal()
            dist = min(step_length, front - 0.6) * rng.uniform(0.9, 1.1)
            blocked = False
        else:
            left, right = min(s[0], s[1]), min(s[6], s[7])
            if blocked or max(left, right) > 2.0:  # a bend, or a dead end
                course += math.pi / 2 if left >= right else -math.pi / 2
            else:
                course += math.pi
            course = wrap_angle(course)
            turn = wrap_angle(course - heading) + 0.1 * rng.standard_normal()
            dist = 0.0
            blocked = True
        if abs(turn) > 1e-3:
            body.command("DHEAD", turn)
            _wait(sim, body)
        if dist > 0.05:
            body.command("MOVE", dist)
            _wait(sim, body)
            if body.stalled:
                body.command("MOVE", -0.2)
                _wait(sim, body)
        log()
    return RouteLog(np.array(odo), np.array(sonar), np.array(truth), world, seed)
