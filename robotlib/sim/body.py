"""One simulated Pioneer 3-DX: its motion commands, odometry error, collisions, sonar.

`SimBody` keeps its true pose and its odometry pose apart: the odometry
integrates what the wheels did, the truth adds slip drawn from an
`OdometryNoise` model. Walls (and other robots) stop a body and set its stall
flag. Sonar readings come from `robotlib.sensing`'s cone model at the true
pose; a laser scan (`robotlib.sensing.laser`), only when asked for, from its
own random stream, so reading the laser changes no sonar or odometry number.
Imports the world, sensing and the robot's state record; never a backend or
anything above the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..p3dx import (
    AXLE_TRACK,
    CYCLE,
    DEFAULT_ACCELERATION,
    DEFAULT_MAX_ROT_VELOCITY,
    DEFAULT_MAX_VELOCITY,
    DEFAULT_ROT_ACCELERATION,
    MAX_ROT_VELOCITY,
    MAX_VELOCITY,
    ROBOT_LENGTH_FRONT,
    ROBOT_LENGTH_REAR,
    ROBOT_RADIUS,
    ROBOT_WIDTH,
)
from ..robot import RobotState
from ..robot.base import check_argument
from ..sensing import _kernels as _sensing_kernels
from ..sensing.laser import simulate_laser
from ..world import _kernels as _world_kernels
from ..world.geometry import wrap_angle

__all__ = ["OdometryNoise", "SimBody", "footprint_segments", "scene_obstacles"]


_STOPPED_V = 0.004
_STOPPED_W = math.radians(1.0)
_BISECTIONS = 6


@dataclass(frozen=True)
class OdometryNoise:
    """How the true motion strays from what the odometry measured.

    Per cycle, with the measured increment ``ds`` (m) and ``dtheta`` (rad),
    the true increment gets zero-mean Gaussian errors whose variances grow
    linearly with the motion (a random walk, independent of the cycle length):

    - translation: ``var = trans_per_m**2 * |ds|`` (m^2)
    - rotation: ``var = rot_per_rad**2 * |dtheta| + rot_per_m**2 * |ds|``
      (rad^2)

    On top of that random walk, ``ed`` and ``eb`` set Borenstein's
    systematic errors (unequal wheels, a wrong track; see `true_increment`),
    off (1.0) by default.

    Attributes
    ----------
    trans_per_m : float
        Translation error after 1 m of travel, standard deviation, m.
    rot_per_rad : float
        Heading error after turning 1 rad, standard deviation, rad.
    rot_per_m : float
        Heading error after 1 m of travel, standard deviation, rad.
    ed : float
        Right wheel diameter over left wheel diameter, ``D_R / D_L``
        (1: equal wheels).
    eb : float
        Real wheel track over the nominal one the odometry assumes
        (1: exact).
    """

    trans_per_m: float = 0.03
    rot_per_rad: float = 0.03
    rot_per_m: float = 0.02
    ed: float = 1.0
    eb: float = 1.0

    def __post_init__(self):
        if not (self.ed > 0 and self.eb > 0):
            raise ValueError(f"ed and eb must be positive, got {self.ed}, {self.eb}")

    @classmethod
    def none(cls) -> OdometryNoise:
        """Return a model with perfect odometry."""
        return cls(0.0, 0.0, 0.0)

    @property
    def systematic(self) -> bool:
        """Whether the wheels differ from the odometry's nominal geometry."""
        return self.ed != 1.0 or self.eb != 1.0

    def true_increment(self, ds: float, dth: float) -> tuple[float, float]:
        """Return the motion the wheels really make for a measured increment.

        The odometry counts encoder ticks and assumes two equal wheels of
        the nominal diameter and the nominal track `robotlib.p3dx.AXLE_TRACK`.
        With Borenstein's systematic errors (UMBmark, 1996) the right wheel's
        diameter is ``ed`` times the left's (their mean is nominal) and the
        real track is ``eb`` times the nominal one, so the same ticks move the
        robot differently.

        Parameters
        ----------
        ds : float
            Measured translation, m.
        dth : float
            Measured rotation, rad.

        Returns
        -------
        tuple of float
            The true translation (m) and rotation (rad), before random slip;
            ``(ds, dth)`` unchanged when there is no systematic error.
        """
        if not self.systematic:
            return ds, dth
        left = (ds - 0.5 * AXLE_TRACK * dth) * 2.0 / (self.ed + 1.0)
        right = (ds + 0.5 * AXLE_TRACK * dth) * 2.0 * self.ed / (self.ed + 1.0)
        return 0.5 * (left + right), (right - left) / (self.eb * AXLE_TRACK)


def _arc(pose: np.ndarray, ds: float, dth: float) -> None:
    """Move ``pose`` in place along an arc of length ``ds`` turning ``dth``."""
    mid = pose[2] + 0.5 * dth
    pose[0] += ds * math.cos(mid)
    pose[1] += ds * math.sin(mid)
    pose[2] = wrap_angle(pose[2] + dth)


def _ramp(current: float, target: float, accel: float, decel: float) -> float:
    """Velocity one cycle later, moving towards ``target`` within the limits."""
    speeding_up = abs(target) > abs(current) and target * current >= 0
    step = (accel if speeding_up else decel) * CYCLE
    return current + min(max(target - current, -step), step)


def _approach(remaining: float, vmax: float, decel: float) -> float:
    """Speed this cycle towards a goal ``remaining`` away, that stops on it.

    The discrete trapezoidal profile: driving at ``v = n * decel * CYCLE``
    this cycle and then slowing by ``decel * CYCLE`` a cycle covers
    ``decel * CYCLE**2 * (m + 1) * (m / 2 + f)`` with ``n = m + f`` (``m``
    whole, ``0 <= f < 1``); ``n`` solves that for the remaining distance, so
    the robot decelerates onto the goal without passing it and never
    reverses. Capped by ``vmax`` and by the speed that lands on the goal in
    one cycle.
    """
    r = abs(remaining)
    speed = min(vmax, r / CYCLE)
    unit = decel * CYCLE * CYCLE
    if unit > 0.0 and speed > 0.0:
        cycles = r / unit
        m = math.floor(0.5 * (math.sqrt(1.0 + 8.0 * cycles) - 1.0))
        f = cycles / (m + 1) - 0.5 * m
        if f < 0.0 and m > 0:
            m -= 1
            f = cycles / (m + 1) - 0.5 * m
        speed = min(speed, (m + min(max(f, 0.0), 1.0)) * decel * CYCLE)
    return math.copysign(speed, remaining)


def footprint_segments(pose: np.ndarray) -> np.ndarray:
    """Return the robot's rectangular outline as four segments (4, 4), m."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    hw = ROBOT_WIDTH / 2
    corners = [
        (ROBOT_LENGTH_FRONT, hw),
        (-ROBOT_LENGTH_REAR, hw),
        (-ROBOT_LENGTH_REAR, -hw),
        (ROBOT_LENGTH_FRONT, -hw),
    ]
    xy = [(pose[0] + c * x - s * y, pose[1] + s * x + c * y) for x, y in corners]
    return np.array([[*xy[i], *xy[(i + 1) % 4]] for i in range(4)])


def scene_obstacles(obstacles: np.ndarray, bodies, body) -> np.ndarray:
    """Return what ``body`` senses: the walls and every other body's outline.

    Parameters
    ----------
    obstacles : numpy.ndarray, shape (K, 4)
        The world's wall segments ``(x1, y1, x2, y2)``, m.
    bodies : sequence of SimBody
        Every robot of the simulator (``body`` among them).
    body : SimBody
        The robot that looks.

    Returns
    -------
    numpy.ndarray, shape (K + 4 (len(bodies) - 1), 4)
        ``obstacles`` itself when ``body`` is alone.
    """
    others = [footprint_segments(b.true_pose) for b in bodies if b is not body]
    if not others:
        return obstacles
    return np.ascontiguousarray(np.concatenate([obstacles, *others]))


class SimBody:
    """One simulated Pioneer 3-DX inside a `Simulator`.

    Create bodies with `Simulator.add_robot`. Commands take SI units (see
    `command`); `state` is what the robot reports after the last cycle.
    """

    def __init__(self, sim, pose, rng: np.random.Generator):
        self._sim = sim
        self._rng = rng
        self._initial = np.array(pose, dtype=float)
        self._laser_rng: np.random.Generator | None = None
        self._reset()

    def _reset(self) -> None:
        self.true_pose = self._initial.copy()
        self._odo = self._initial.copy()
        self._defaults()
        self.stalled = False
        self._sonar = np.full(len(self._sim.sonar.sensors), self._sim.sonar.max_range)

    def _defaults(self) -> None:
        """Stop; set a freshly opened Pioneer's limits; motors and sonar on."""
        self._v = 0.0
        self._w = 0.0
        self._vmax = DEFAULT_MAX_VELOCITY
        self._wmax = DEFAULT_MAX_ROT_VELOCITY
        self._accel = self._decel = DEFAULT_ACCELERATION
        self._raccel = self._rdecel = DEFAULT_ROT_ACCELERATION
        self._trans_goal: tuple[str, float] = ("vel", 0.0)
        self._move_from = self._odo[:2].copy()
        self._rot_goal: tuple[str, float] = ("vel", 0.0)
        self._motors = True
        self._sonar_on = True

    # -- commands ---------------------------------------------------------
    def command(self, name: str, value=None) -> None:
        """Apply a motion command, in SI units.

        Parameters
        ----------
        name : str
            ``MOVE`` (m), ``HEAD`` (rad, absolute, odometry frame), ``DHEAD``
            (rad, relative), ``VEL`` (m/s), ``RVEL`` (rad/s), ``VEL2``
            (``(left, right)`` wheel speeds, m/s), ``SETV`` (m/s), ``SETRV``
            (rad/s), ``SETA`` (m/s^2; negative sets the deceleration),
            ``SETRA`` (rad/s^2; negative sets the deceleration), ``STOP``.
        value : float, tuple or None
            The argument, as above.

        Raises
        ------
        ValueError
            For an unknown command, a missing argument or one that is not a
            finite number; the body's state is then left as it was.
        """
        name = name.upper()
        if name == "STOP":
            self._trans_goal = ("vel", 0.0)
            self._rot_goal = ("vel", 0.0)
            return
        if value is None:
            raise ValueError(f"command {name} needs a value")
        if name == "VEL2":
            left, right = (
                check_argument(f"{name}: wheel speed (m/s)", v) for v in value
            )
            self._trans_goal = ("vel", (left + right) / 2)
            self._rot_goal = ("vel", (right - left) / AXLE_TRACK)
            return
        value = check_argument(f"{name}: argument", value)
        if name == "MOVE":
            self._trans_goal = ("move", value)
            self._move_from = self._odo[:2].copy()
        elif name == "VEL":
            self._trans_goal = ("vel", value)
        elif name == "HEAD":
            self._rot_goal = ("head", wrap_angle(value))
        elif name == "DHEAD":
            self._rot_goal = ("head", wrap_angle(self._odo[2] + value))
        elif name == "RVEL":
            self._rot_goal = ("vel", value)
        elif name == "SETV":
            self._vmax = min(abs(value), MAX_VELOCITY)
        elif name == "SETRV":
            self._wmax = min(abs(value), MAX_ROT_VELOCITY)
        elif name == "SETA":
            if value >= 0:
                self._accel = value
            else:
                self._decel = -value
        elif name == "SETRA":
            if value >= 0:
                self._raccel = value
            else:
                self._rdecel = -value
        else:
            raise ValueError(f"unknown command {name!r}")

    def set_true_pose(self, pose) -> None:
        """Move the robot to ``pose`` (m, rad) without touching its odometry."""
        self.true_pose = np.array(pose, dtype=float)
        self.true_pose[2] = wrap_angle(self.true_pose[2])

    def reset_odometry(self) -> None:
        """Set the odometry pose to (0, 0, 0) here (a Pioneer's SETO)."""
        self._odo[:] = 0.0
        self._move_from = self._odo[:2].copy()

    def begin_session(self) -> None:
        """Start a new client's session, as a Pioneer does when a client opens it.

        The robot stops where it is; speed limits, accelerations, motors and
        sonar go back to their start-up defaults, whatever the previous
        client set; the odometry restarts at (0, 0, 0) here. The true pose is
        kept (`set_true_pose` moves it).
        """
        self._defaults()
        self.reset_odometry()

    def enable_motors(self, on: bool) -> None:
        """Switch the motors on or off; off stops the robot at once."""
        self._motors = bool(on)
        if not on:
            self._v = self._w = 0.0

    def enable_sonar(self, on: bool) -> None:
        """Switch the sonar ring on or off; off reports no echo on every sonar."""
        self._sonar_on = bool(on)
        if not on:
            self._sonar[:] = self._sim.sonar.max_range

    def scan_laser(self) -> np.ndarray:
        """Return a laser scan at the true pose now, shape (n_beams,), m.

        The noise comes from a stream of its own (spawned from this body's
        on first use), so scanning leaves the sonar and odometry noise as
        they would be without a laser.
        """
        if self._laser_rng is None:
            self._laser_rng = self._rng.spawn(1)[0]
        sim = self._sim
        obstacles = scene_obstacles(sim.sensed_obstacles, sim.bodies, self)
        return simulate_laser(
            obstacles, self.true_pose, self._sim.laser, self._laser_rng
        )[0]

    # -- reports ----------------------------------------------------------
    @property
    def moving(self) -> bool:
        """Whether the robot moves faster than 4 mm/s or 1 deg/s."""
        return abs(self._v) >= _STOPPED_V or abs(self._w) >= _STOPPED_W

    @property
    def state(self) -> RobotState:
        """What the robot reports after the last cycle (odometry, not truth)."""
        return RobotState(
            pose=self._odo.copy(),
            velocity=(self._v, self._w),
            sonar=self._sonar.copy(),
            stalled=self.stalled,
            time=self._sim.time,
            motors_enabled=self._motors,
        )

    # -- one cycle ----------------------------------------------------------
    def _control(self) -> tuple[float, float]:
        """Velocities the controller commands this cycle."""
        kind, goal = self._trans_goal
        if kind == "move":
            travelled = math.hypot(*(self._odo[:2] - self._move_from))
            v_target = _approach(
                goal - math.copysign(travelled, goal), self._vmax, self._decel
            )
        else:
            v_target = min(max(goal, -self._vmax), self._vmax)
        kind, goal = self._rot_goal
        if kind == "head":
            w_target = _approach(
                wrap_angle(goal - self._odo[2]), self._wmax, self._rdecel
            )
        else:
            w_target = min(max(goal, -self._wmax), self._wmax)
        v = _ramp(self._v, v_target, self._accel, self._decel)
        w = _ramp(self._w, w_target, self._raccel, self._rdecel)
        return v, w

    def _advance(self, obstacles: np.ndarray, others: list[np.ndarray]) -> None:
        """Move one cycle: controller, slip, collisions, odometry."""
        noise = self._rng.standard_normal(2)
        if not self._motors:
            self._v = self._w = 0.0
            self.stalled = False
            return
        v, w = self._control()
        ds, dth = v * CYCLE, w * CYCLE
        model = self._sim.odometry
        wheel_ds, wheel_dth = model.true_increment(ds, dth)
        true_ds = wheel_ds + noise[0] * model.trans_per_m * math.sqrt(abs(ds))
        true_dth = wheel_dth + noise[1] * math.sqrt(
            model.rot_per_rad**2 * abs(dth) + model.rot_per_m**2 * abs(ds)
        )
        fraction = self._free_fraction(true_ds, true_dth, obstacles, others)
        self.stalled = fraction < 1.0
        _arc(self.true_pose, true_ds * fraction, true_dth)
        _arc(self._odo, ds * fraction, dth)
        self._v = v * fraction if not self.stalled else 0.0
        self._w = w

    def _clear(self, pose: np.ndarray, obstacles, others) -> bool:
        if _world_kernels.nearest_distance(pose[0], pose[1], obstacles) <= ROBOT_RADIUS:
            return False
        return all(math.hypot(*(pose[:2] - o[:2])) > 2 * ROBOT_RADIUS for o in others)

    def _free_fraction(self, ds, dth, obstacles, others) -> float:
        """Largest share of this cycle's translation that keeps the robot clear."""
        trial = self.true_pose.copy()
        _arc(trial, ds, dth)
        if ds == 0.0 or self._clear(trial, obstacles, others):
            return 1.0
        lo, hi = 0.0, 1.0
        for _ in range(_BISECTIONS):
            mid = 0.5 * (lo + hi)
            trial[:] = self.true_pose
            _arc(trial, ds * mid, dth)
            if self._clear(trial, obstacles, others):
                lo = mid
            else:
                hi = mid
        return lo

    def _sense(self, obstacles: np.ndarray) -> None:
        """Take this cycle's sonar readings at the true pose."""
        model = self._sim.sonar
        n = len(model.sensors)
        uniforms = self._rng.random((1, n, 2))
        normals = self._rng.standard_normal((1, n))
        if not self._sonar_on:
            return
        out = np.empty((1, n))
        _sensing_kernels.sonar_scan(
            self.true_pose[None, :],
            model.sensors,
            obstacles,
            model.n_rays,
            model.cone,
            model.max_range,
            model.min_range,
            model.cos_specular,
            model.noise_std,
            model.multipath_prob,
            model.dropout_prob,
            uniforms,
            normals,
            out,
        )
        self._sonar = out[0]
