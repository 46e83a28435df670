"""The `Robot` interface every backend implements, and its state record.

Backends implement three small private methods (`Robot._send`,
`Robot._update`, `Robot._close`); the motion bookkeeping that ARIA does on the
client side (move and heading completion) is written once, here. Imports
only the world's geometry and the robot's constants: the simulator and the
Pioneer client import this module, never the reverse.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from ..p3dx import HEADING_DONE_TOLERANCE, MOVE_DONE_TOLERANCE
from ..world.geometry import wrap_angle

__all__ = ["Robot", "RobotState", "RobotTimeout", "check_argument"]

_WIRE = 32.767
"""Largest magnitude of a MOVE (m) or VEL (m/s): the protocol's signed 16-bit mm."""
_WIRE_ROT = math.radians(32767.0)
"""Largest magnitude of an RVEL (rad/s): the protocol's signed 16-bit deg/s."""


def check_argument(
    what: str, value, limit: float = math.inf, *, nonnegative: bool = False
) -> float:
    """Return ``value`` as a float, or raise one clear `ValueError`.

    Every backend checks its arguments here before it stores or sends
    anything, so a refused command leaves the robot as it was.

    Parameters
    ----------
    what : str
        The call and argument, for the message (``"move: distance (m)"``).
    value : float
        The argument.
    limit : float
        Largest magnitude accepted.
    nonnegative : bool
        Refuse negative values too.

    Raises
    ------
    ValueError
        If ``value`` is not a number, not finite, or out of range.
    """
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{what} must be finite, got {value!r}")
    if abs(x) > limit or (nonnegative and x < 0):
        lo = 0 if nonnegative else -limit
        raise ValueError(f"{what} must be within [{lo:g}, {limit:g}], got {value!r}")
    return x


class RobotTimeout(TimeoutError):
    """A robot did not reach a state, or did not answer, in the time allowed."""


@dataclass(frozen=True)
class RobotState:
    """What a robot reports each cycle, in SI units.

    Attributes
    ----------
    pose : numpy.ndarray, shape (3,)
        Odometry pose ``(x, y, theta)``, m and rad (the robot's own estimate,
        not the truth).
    velocity : tuple of float
        Translational (m/s) and rotational (rad/s) velocity.
    sonar : numpy.ndarray, shape (8,)
        Front sonar ranges, m; ``SONAR_MAX_RANGE`` (5 m) means no echo.
    stalled : bool
        A wheel is stalled (the robot pushes against an obstacle).
    time : float
        The robot's clock, s.
    motors_enabled : bool
        Motors are on.
    """

    pose: np.ndarray
    velocity: tuple[float, float]
    sonar: np.ndarray
    stalled: bool = False
    time: float = 0.0
    motors_enabled: bool = True
    extra: dict = field(default_factory=dict, compare=False)


class Robot(ABC):
    """A Pioneer-like robot, simulated or real.

    All arguments and results are SI: metres, radians, seconds. Every poll
    (`ismovedone`, `isheadingdone`, `readsonar`, `pose`) waits for the robot's
    next cycle (100 ms on a Pioneer; one simulated step in the simulator) and
    returns what it reported then. Use as a context manager to disconnect on
    exit.
    """

    def __init__(self):
        self._state: RobotState | None = None
        self._move_start: np.ndarray | None = None
        self._move_distance = 0.0
        self._heading_target: float | None = None
        self._closed = False

    # -- what a backend implements -------------------------------------
    @abstractmethod
    def _send(self, command: str, value: float | None = None) -> None:
        """Send one motion command in SI units.

        ``command`` is a protocol command name: ``MOVE`` (m), ``HEAD``
        (absolute heading, rad, odometry frame), ``VEL`` (m/s), ``RVEL``
        (rad/s), ``SETV`` (m/s), ``SETRV`` (rad/s), ``SETA`` (m/s^2),
        ``SETRA`` (rad/s^2), ``STOP`` (no value).
        """

    @abstractmethod
    def _update(self) -> RobotState:
        """Wait for the next cycle and return the robot's state then."""

    @abstractmethod
    def _close(self) -> None:
        """Stop the robot and release its connection."""

    # -- state -------------------------------------------------------------
    def _poll(self) -> RobotState:
        if self._closed:
            raise RuntimeError("robot is disconnected")
        self._state = self._update()
        return self._state

    def _latest(self) -> RobotState:
        return self._state if self._state is not None else self._poll()

    @property
    def state(self) -> RobotState:
        """The state from the last poll (polls once if there was none)."""
        return self._latest()

    # -- the paper's Table 1 --------------------------------------------
    def move(self, distance: float) -> None:
        """Drive ``distance`` metres straight ahead (negative: backwards).

        Raises
        ------
        ValueError
            If ``distance`` is not finite or beyond +-32.767 m (the protocol's
            range); the robot's motion is then left as it was.
        """
        d = check_argument("move: distance (m)", distance, _WIRE)
        start = self._latest().pose.copy()
        self._send("MOVE", d)
        self._move_start = start
        self._move_distance = d

    def setheading(self, theta: float) -> None:
        """Turn to the absolute heading ``theta`` (rad, odometry frame).

        Raises
        ------
        ValueError
            If ``theta`` is not finite (nothing is stored or sent then).
        """
        target = wrap_angle(check_argument("setheading: theta (rad)", theta))
        self._send("HEAD", target)
        self._heading_target = target

    def setdeltaheading(self, dtheta: float) -> None:
        """Turn by ``dtheta`` radians from the current heading (positive: left).

        Raises
        ------
        ValueError
            If ``dtheta`` is not finite.
        """
        d = check_argument("setdeltaheading: dtheta (rad)", dtheta)
        self.setheading(self._latest().pose[2] + d)

    def setvel(self, v: float) -> None:
        """Drive at ``v`` m/s until told otherwise (cancels a move).

        Raises
        ------
        ValueError
            If ``v`` is not finite or beyond +-32.767 m/s.
        """
        v = check_argument("setvel: v (m/s)", v, _WIRE)
        self._send("VEL", v)
        self._move_start = None

    def setrotvel(self, w: float) -> None:
        """Turn at ``w`` rad/s until told otherwise (cancels a heading).

        Raises
        ------
        ValueError
            If ``w`` is not finite or beyond the protocol's 32767 deg/s.
        """
        w = check_argument("setrotvel: w (rad/s)", w, _WIRE_ROT)
        self._send("RVEL", w)
        self._heading_target = None

    def stop(self) -> None:
        """Stop translation and rotation (cancels any move or heading)."""
        self._move_start = None
        self._heading_target = None
        self._send("STOP")

    def set_max_velocity(self, v: float) -> None:
        """Limit the translational speed of later motions, m/s (>= 0)."""
        v = check_argument("set_max_velocity: v (m/s)", v, _WIRE, nonnegative=True)
        self._send("SETV", v)

    def set_max_rot_velocity(self, w: float) -> None:
        """Limit the rotational speed of later motions, rad/s (>= 0)."""
        w = check_argument(
            "set_max_rot_velocity: w (rad/s)", w, _WIRE_ROT, nonnegative=True
        )
        self._send("SETRV", w)

    def ismovedone(self) -> bool:
        """Poll once; True when the last `move` is within 40 mm of its distance.

        True as well when no move is under way.
        """
        st = self._poll()
        if self._move_start is None:
            return True
        travelled = math.hypot(*(st.pose[:2] - self._move_start[:2]))
        return abs(travelled - abs(self._move_distance)) < MOVE_DONE_TOLERANCE

    def isheadingdone(self) -> bool:
        """Poll once; True when the heading is within 3 degrees of its target.

        True as well when no heading is under way.
        """
        st = self._poll()
        if self._heading_target is None:
            return True
        return abs(wrap_angle(st.pose[2] - self._heading_target)) < (
            HEADING_DONE_TOLERANCE
        )

    def readsonar(self) -> np.ndarray:
        """Poll once; the eight front sonar ranges, shape (8,), m (5 m: no echo)."""
        return self._poll().sonar.copy()

    def readlaser(self) -> np.ndarray:
        """Poll once; the laser scan, shape (n_beams,), m, right to left.

        Raises
        ------
        NotImplementedError
            If this backend has no laser (before polling).
        """
        if not self._has_laser():
            raise NotImplementedError(f"{type(self).__name__} has no laser")
        self._poll()
        return self._read_laser()

    def _has_laser(self) -> bool:
        """Whether `readlaser` works on this backend (default: no laser)."""
        return False

    def _read_laser(self) -> np.ndarray:
        """Return the laser scan of the last cycle (backends with a laser)."""
        raise NotImplementedError(f"{type(self).__name__} has no laser")

    def pose(self) -> np.ndarray:
        """Poll once; the odometry pose ``(x, y, theta)``, m and rad."""
        return self._poll().pose.copy()

    def wait_move_done(self, timeout: float = 30.0) -> None:
        """Poll until `ismovedone`; `RobotTimeout` after ``timeout`` s."""
        self._wait(self.ismovedone, timeout, "move")

    def wait_heading_done(self, timeout: float = 30.0) -> None:
        """Poll until `isheadingdone`; `RobotTimeout` after ``timeout`` s."""
        self._wait(self.isheadingdone, timeout, "heading")

    def _wait(self, done, timeout: float, what: str) -> None:
        t0 = self._latest().time
        wall0 = time.monotonic()
        while not done():
            if self._state.time - t0 > timeout or time.monotonic() - wall0 > timeout:
                raise RobotTimeout(f"{what} not done after {timeout} s")

    def disconnect(self) -> None:
        """Stop the robot and close the connection (safe to call twice)."""
        if not self._closed:
            self._closed = True
            self._close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.disconnect()
