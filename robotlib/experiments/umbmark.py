"""UMBmark: Borenstein and Feng's square test for systematic odometry error.

The robot drives an ``L x L`` square, clockwise and counter-clockwise, several
times each, steered by its own odometry. At the end of each run the
odometry believes it is back at the start; the difference between where it
really is and where the odometry says (``true - odometry``, m) is the
return error. Unequal wheel diameters (``Ed = D_R / D_L``) bend every
straight leg into an arc, which adds up the same way in both directions; a
wrong wheel track (``Eb``) makes every turn too large or too small, which
adds up in opposite ways. From the centres of gravity of the two clouds of
return errors,

- ``alpha = (x_cw + x_ccw) / (-4 L)`` (rad): the turn error per corner;
- ``beta = (x_cw - x_ccw) / (-4 L)`` (rad): the heading change per leg from
  unequal wheels;
- ``R = (L / 2) / sin(beta / 2)``; ``Ed = (R + b/2) / (R - b/2)``;
  ``Eb = (pi/2) / (pi/2 - alpha)``

(Borenstein and Feng, "Measurement and correction of systematic odometry
errors in mobile robots", IEEE Trans. Robotics and Automation, 1996, with
errors measured in the start frame: ``x`` along the first leg, ``y`` to the
left). `square_test` drives a `robotlib.robot.Robot`; `umbmark_estimate`
turns return errors into ``(Ed, Eb)``. Sits above the robot interface; never
plots.
"""

from __future__ import annotations

import math

import numpy as np

from ..p3dx import AXLE_TRACK
from ..robot import Robot
from ..world.geometry import wrap_angle

__all__ = ["square_test", "return_error", "umbmark_estimate", "umbmark"]


def _settle(r: Robot, max_cycles: int = 100) -> None:
    """Poll until the robot has stopped (bounded)."""
    for k in range(max_cycles):
        v, w = r.state.velocity
        if k >= 2 and abs(v) < 1e-3 and abs(w) < 1e-3:
            return
        r.pose()


def square_test(r: Robot, side: float = 4.0, clockwise: bool = False) -> None:
    """Drive one UMBmark square by odometry: four legs, four quarter turns.

    Each leg is a `Robot.move` of ``side`` m, each turn a `Robot.setheading`
    to the next multiple of 90 degrees from the start heading, each waited
    for until the robot stands still.

    Parameters
    ----------
    r : Robot
        The robot (it needs about ``side`` m of free space ahead and to the
        side it turns to).
    side : float
        Side of the square, m.
    clockwise : bool
        Turn right at the corners (clockwise) instead of left.
    """
    start = float(r.pose()[2])
    turn = -math.pi / 2 if clockwise else math.pi / 2
    for leg in range(1, 5):
        r.move(side)
        r.wait_move_done(timeout=60.0)
        _settle(r)
        r.setheading(wrap_angle(start + leg * turn))
        r.wait_heading_done(timeout=60.0)
        _settle(r)


def return_error(start_true, end_true, start_odo, end_odo) -> np.ndarray:
    """Return the error ``true - odometry`` in the start frame, m, shape (2,).

    Parameters
    ----------
    start_true, end_true : array_like, shape (3,)
        True pose at the start and end of a run, m and rad.
    start_odo, end_odo : array_like, shape (3,)
        Odometry pose at the start and end of the run.

    Returns
    -------
    numpy.ndarray, shape (2,)
        ``(x, y)``: along the first leg and to its left, m.
    """
    st, et = np.asarray(start_true, float), np.asarray(end_true, float)
    so, eo = np.asarray(start_odo, float), np.asarray(end_odo, float)
    c, s = math.cos(st[2]), math.sin(st[2])
    dt = et[:2] - st[:2]
    true_local = np.array([c * dt[0] + s * dt[1], -s * dt[0] + c * dt[1]])
    c, s = math.cos(so[2]), math.sin(so[2])
    do = eo[:2] - so[:2]
    odo_local = np.array([c * do[0] + s * do[1], -s * do[0] + c * do[1]])
    return true_local - odo_local


def umbmark_estimate(errors_cw, errors_ccw, side: float, track: float = AXLE_TRACK):
    """Estimate ``(Ed, Eb)`` from UMBmark return errors.

    Parameters
    ----------
    errors_cw, errors_ccw : array_like, shape (n, 2)
        Return errors ``true - odometry`` (m) of the clockwise and the
        counter-clockwise runs, in each run's start frame (see
        `return_error`).
    side : float
        Side of the square, m.
    track : float
        The nominal wheel track the odometry uses, m.

    Returns
    -------
    tuple of float
        ``Ed`` (right over left wheel diameter) and ``Eb`` (real over nominal
        track).
    """
    cw = np.asarray(errors_cw, dtype=float).reshape(-1, 2).mean(axis=0)
    ccw = np.asarray(errors_ccw, dtype=float).reshape(-1, 2).mean(axis=0)
    alpha = (cw[0] + ccw[0]) / (-4.0 * side)
    beta = (cw[0] - ccw[0]) / (-4.0 * side)
    if beta == 0.0:
        ed = 1.0
    else:
        radius = (side / 2.0) / math.sin(beta / 2.0)
        ed = (radius + track / 2.0) / (radius - track / 2.0)
    eb = (math.pi / 2.0) / (math.pi / 2.0 - alpha)
    return float(ed), float(eb)


def umbmark(
    r: Robot, side: float = 4.0, runs: int = 5
) -> tuple[np.ndarray, np.ndarray]:
    """Run the whole test on a simulated robot: ``runs`` squares each way.

    The true pose comes from ``r.true_pose()`` (a simulator's ground truth;
    on a real robot, measure the return error by hand and call
    `umbmark_estimate`). Before each run the robot is put back at its start
    (``r.body.set_true_pose`` on a `robotlib.sim.SimRobot`) if it can be.

    Parameters
    ----------
    r : Robot
        A robot with a ``true_pose()`` method.
    side : float
        Side of the square, m.
    runs : int
        Runs in each direction.

    Returns
    -------
    tuple of numpy.ndarray
        Return errors of the clockwise and the counter-clockwise runs, each
        shape ``(runs, 2)``, m.
    """
    home = np.asarray(r.true_pose(), dtype=float)
    out = {True: [], False: []}
    for clockwise in (True, False):
        for _ in range(runs):
            body = getattr(r, "body", None)
            if body is not None:
                body.set_true_pose(home)
            t0, o0 = r.true_pose(), r.pose()
            square_test(r, side, clockwise)
            out[clockwise].append(return_error(t0, r.true_pose(), o0, r.pose()))
    return np.array(out[True]), np.array(out[False])
