"""EKF-SLAM with point landmarks and a range-bearing sensor.

The state is the robot pose and every landmark found so far,
``mu = (x, y, theta, m1x, m1y, m2x, m2y, ...)``, with its full covariance
``P``. The pieces are plain functions a lab can ask students to write:

- `ekf_predict`: the odometry arc ``(ds, dtheta)`` with the simulator's slip
  variances (`robotlib.mapping.motion.arc_noise_cov`), Jacobians in closed
  form, only the robot's rows and columns of ``P`` touched;
- `ekf_update`: one range-bearing observation of a landmark in the state;
- `ekf_add_landmark`: a new landmark, initialised from one observation;
- `associate`: nearest neighbour by Mahalanobis distance with a gate (for
  unknown data association).

`EKFSLAM` strings them together; `nees` is the robot pose's normalised
estimation error squared against the truth (3 degrees of freedom), so the
filter's consistency can be checked. Landmarks come from a world file
(`world_landmarks`: the walls' corners) and are seen by `observe_landmarks`
(range, field of view, walls in the way, noise). Imports the world, the
ray caster and the motion model; never plots.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._random import as_rng
from ..sensing import cast_rays
from ..sim import OdometryNoise
from ..world import World
from ..world.geometry import wrap_angle
from .motion import arc_increment, arc_noise_cov

__all__ = [
    "RangeBearingSensor",
    "world_landmarks",
    "observe_landmarks",
    "ekf_predict",
    "ekf_update",
    "ekf_add_landmark",
    "associate",
    "EKFSLAM",
    "EKFResult",
    "run_ekfslam",
    "nees",
    "chi2_band",
]


@dataclass(frozen=True)
class RangeBearingSensor:
    """A sensor that measures range and bearing to point landmarks.

    Attributes
    ----------
    max_range : float
        Landmarks further away are not seen, m.
    fov : float
        Full field of view centred on the heading, rad.
    range_std, bearing_std : float
        Noise standard deviations, m and rad.
    """

    max_range: float = 5.0
    fov: float = math.pi
    range_std: float = 0.05
    bearing_std: float = math.radians(2.0)

    @property
    def R(self) -> np.ndarray:  # noqa: N802 (the textbook's name)
        """Measurement noise covariance (2, 2)."""
        return np.diag([self.range_std**2, self.bearing_std**2])


def world_landmarks(world: World) -> np.ndarray:
    """Return the corners of a world's walls as landmarks (M, 2), m (each once)."""
    ends = np.concatenate([world.segments[:, :2], world.segments[:, 2:]])
    return np.unique(np.round(ends, 3), axis=0)


def observe_landmarks(
    landmarks,
    pose,
    sensor: RangeBearingSensor | None = None,
    walls=None,
    rng: np.random.Generator | int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Noisy range and bearing to the landmarks the robot can see.

    Parameters
    ----------
    landmarks : array_like, shape (M, 2)
        True landmark positions, m.
    pose : array_like, shape (3,)
        True robot pose, m and rad.
    sensor : RangeBearingSensor, optional
    walls : World or array_like (K, 4), optional
        If given, a landmark hidden behind a wall (more than 5 cm before it
        along the line of sight) is not seen.
    rng : numpy.random.Generator, int or None
        Noise (two normals per landmark in the world, seen or not, so the
        stream does not depend on what is visible).

    Returns
    -------
    ids : numpy.ndarray of int, shape (k,)
        Indexes of the landmarks seen.
    z : numpy.ndarray, shape (k, 2)
        Their ranges (m) and bearings (rad, wrapped).
    """
    sensor = RangeBearingSensor() if sensor is None else sensor
    rng = as_rng(rng)
    lm = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    noise = rng.standard_normal((len(lm), 2))
    x, y, th = (float(v) for v in pose)
    d = np.hypot(lm[:, 0] - x, lm[:, 1] - y)
    b = wrap_angle(np.arctan2(lm[:, 1] - y, lm[:, 0] - x) - th)
    seen = (d <= sensor.max_range) & (np.abs(b) <= sensor.fov / 2) & (d > 0.05)
    if walls is not None and seen.any():
        k = np.flatnonzero(seen)
        ranges = cast_rays(walls, [x, y, th], b[k], sensor.max_range)[0]
        seen[k] = ranges >= d[k] - 0.05
    ids = np.flatnonzero(seen)
    z = np.column_stack(
        [
            d[ids] + sensor.range_std * noise[ids, 0],
            wrap_angle(b[ids] + sensor.bearing_std * noise[ids, 1]),
        ]
    )
    return ids, z


def ekf_predict(mu, P, ds: float, dth: float, noise: OdometryNoise, inflate=1.0):
    """EKF prediction for the odometry arc ``(ds, dth)``; returns new ``(mu, P)``.

    The robot moves ``ds`` along the mid-angle ``theta + dth / 2`` and turns
    ``dth``; the true arc has covariance `arc_noise_cov` (times
    ``inflate**2``). Landmarks do not move.
    """
    mu = np.array(mu, dtype=float)
    P = np.array(P, dtype=float)
    mid = mu[2] + 0.5 * dth
    c, s = math.cos(mid), math.sin(mid)
    mu[0] += ds * c
    mu[1] += ds * s
    mu[2] = wrap_angle(mu[2] + dth)
    G = np.array([[1.0, 0.0, -ds * s], [0.0, 1.0, ds * c], [0.0, 0.0, 1.0]])
    V = np.array([[c, -0.5 * ds * s], [s, 0.5 * ds * c], [0.0, 1.0]])
    Q = V @ arc_noise_cov(ds, dth, noise, inflate) @ V.T
    P[:3, :] = G @ P[:3, :]
    P[:, :3] = P[:, :3] @ G.T
    P[:3, :3] += Q
    return mu, P


def _expected(mu, j):
    """Return landmark ``j``'s expected ``(range, bearing)`` and Jacobian (2, n)."""
    lx, ly = mu[3 + 2 * j], mu[4 + 2 * j]
    dx, dy = lx - mu[0], ly - mu[1]
    q = dx * dx + dy * dy
    r = math.sqrt(q)
    zhat = np.array([r, wrap_angle(math.atan2(dy, dx) - mu[2])])
    H = np.zeros((2, len(mu)))
    H[:, :3] = [[-dx / r, -dy / r, 0.0], [dy / q, -dx / q, -1.0]]
    H[:, 3 + 2 * j : 5 + 2 * j] = [[dx / r, dy / r], [-dy / q, dx / q]]
    return zhat, H


def ekf_update(mu, P, z, j: int, R):
    """EKF update with observation ``z = (range, bearing)`` of landmark ``j``.

    Returns the new ``(mu, P)`` (``P - K S K^T``, symmetrised: O(n^2)).
    """
    mu = np.asarray(mu, dtype=float)
    P = np.asarray(P, dtype=float)
    zhat, H = _expected(mu, j)
    nu = np.asarray(z, dtype=float) - zhat
    nu[1] = wrap_angle(nu[1])
    PHt = P @ H.T
    S = H @ PHt + R
    K = PHt @ np.linalg.inv(S)
    mu = mu + K @ nu
    mu[2] = wrap_angle(mu[2])
    P = P - K @ S @ K.T
    P = 0.5 * (P + P.T)
    return mu, P


def ekf_add_landmark(mu, P, z, R):
    """Append a landmark seen at ``z = (range, bearing)``; returns ``(mu, P)``."""
    mu = np.asarray(mu, dtype=float)
    P = np.asarray(P, dtype=float)
    r, b = float(z[0]), float(z[1])
    a = mu[2] + b
    c, s = math.cos(a), math.sin(a)
    new = np.array([mu[0] + r * c, mu[1] + r * s])
    Gx = np.array([[1.0, 0.0, -r * s], [0.0, 1.0, r * c]])
    Gz = np.array([[c, -r * s], [s, r * c]])
    n = len(mu)
    P2 = np.zeros((n + 2, n + 2))
    P2[:n, :n] = P
    cross = Gx @ P[:3, :]
    P2[n:, :n] = cross
    P2[:n, n:] = cross.T
    P2[n:, n:] = Gx @ P[:3, :3] @ Gx.T + Gz @ R @ Gz.T
    return np.concatenate([mu, new]), P2


def associate(mu, P, z, R, gate: float = 9.21, new: float = 20.0) -> int:
    """Nearest landmark by Mahalanobis distance, for unknown association.

    Returns the landmark's index when its squared distance is within
    ``gate`` (chi-square, 2 dof: 9.21 is 99 %); -1 (a new landmark) when
    every landmark is beyond ``new``; -2 (ambiguous: ignore the reading) in
    between.
    """
    n_lm = (len(mu) - 3) // 2
    best, best_j = np.inf, -1
    for j in range(n_lm):
        zhat, H = _expected(mu, j)
        nu = np.asarray(z, dtype=float) - zhat
        nu[1] = wrap_angle(nu[1])
        S = H @ P @ H.T + R
        d2 = float(nu @ np.linalg.solve(S, nu))
        if d2 < best:
            best, best_j = d2, j
    if best <= gate:
        return best_j
    return -1 if best > new else -2


def nees(mu, P, true_pose) -> float:
    """Normalised estimation error squared of the robot pose (3 dof)."""
    e = np.asarray(mu[:3], dtype=float) - np.asarray(true_pose, dtype=float)
    e[2] = wrap_angle(e[2])
    return float(e @ np.linalg.solve(np.asarray(P)[:3, :3], e))


def chi2_band(dof: int, p: float = 0.95) -> tuple[float, float]:
    """Two-sided chi-square interval of ``dof`` degrees of freedom (Wilson-Hilferty).

    For an average of M runs' NEES with n dof each, use ``dof = M n`` and
    divide the bounds by M.
    """
    zq = {0.95: 1.959964, 0.99: 2.575829}[p]
    k = float(dof)
    f = 2.0 / (9.0 * k)
    return (k * (1 - f - zq * math.sqrt(f)) ** 3, k * (1 - f + zq * math.sqrt(f)) ** 3)


class EKFSLAM:
    """EKF-SLAM from a start pose, with known or unknown data association.

    Parameters
    ----------
    start : array_like, shape (3,)
        The start pose (known exactly: the map's frame).
    sensor : RangeBearingSensor, optional
    motion : OdometryNoise, optional
        Slip the prediction assumes.
    inflate : float
        Motion noise standard deviations times this.
    known : bool
        Observations come with landmark ids (else `associate` decides).
    gate, new : float
        `associate`'s thresholds.
    """

    def __init__(
        self, start, sensor=None, motion=None, inflate=1.0, known=True,
        gate=9.21, new=20.0,
    ):  # fmt: skip
        self.mu = np.asarray(start, dtype=float).copy()
        self.P = np.eye(3) * 1e-9  # the start is known (tiny: P stays invertible)
        self.sensor = RangeBearingSensor() if sensor is None else sensor
        self.motion = OdometryNoise() if motion is None else motion
        self.inflate = float(inflate)
        self.known = bool(known)
        self.gate, self.new = float(gate), float(new)
        self.ids: list[int] = []  # the true id of each state landmark (known)
        self._odo = None

    @property
    def pose(self) -> np.ndarray:
        """The robot pose estimate (3,)."""
        return self.mu[:3].copy()

    @property
    def landmarks(self) -> np.ndarray:
        """Landmark estimates (M, 2), in the order they were added."""
        return self.mu[3:].reshape(-1, 2).copy()

    def predict(self, odometry) -> None:
        """Predict to the odometry pose (3,) (the first call only remembers it)."""
        odo = np.asarray(odometry, dtype=float)
        if self._odo is not None:
            ds, dth = arc_increment(self._odo, odo)
            self.mu, self.P = ekf_predict(
                self.mu, self.P, ds, dth, self.motion, self.inflate
            )
        self._odo = odo.copy()

    def correct(self, z, ids=None) -> None:
        """Take observations ``z`` (k, 2), with true ``ids`` (k,) if known."""
        R = self.sensor.R
        for q, zq in enumerate(np.asarray(z, dtype=float).reshape(-1, 2)):
            if self.known:
                tid = int(ids[q])
                j = self.ids.index(tid) if tid in self.ids else -1
            else:
                j = associate(self.mu, self.P, zq, R, self.gate, self.new)
                tid = -1
            if j == -1:
                self.mu, self.P = ekf_add_landmark(self.mu, self.P, zq, R)
                self.ids.append(tid)
            elif j >= 0:
                self.mu, self.P = ekf_update(self.mu, self.P, zq, j, R)

    def nees(self, true_pose) -> float:
        """NEES of the pose estimate against ``true_pose``."""
        return nees(self.mu, self.P, true_pose)


@dataclass(frozen=True, eq=False)
class EKFResult:
    """What `run_ekfslam` returns.

    Attributes
    ----------
    path : numpy.ndarray, shape (T, 3)
        Pose estimates, one per record.
    nees : numpy.ndarray, shape (T,)
        The pose's NEES per record.
    rms, odometry_rms : float
        Position RMS errors of the estimate and of odometry, m.
    landmark_rms : float
        RMS error of the landmarks found (known association), m; nan
        otherwise.
    filter : EKFSLAM
    """

    path: np.ndarray
    nees: np.ndarray
    rms: float
    odometry_rms: float
    landmark_rms: float
    filter: EKFSLAM


def run_ekfslam(
    log,
    landmarks=None,
    sensor: RangeBearingSensor | None = None,
    observe_every: int = 5,
    known: bool = True,
    rng: np.random.Generator | int | None = 0,
    **kw,
) -> EKFResult:
    """Run EKF-SLAM over a `robotlib.mapping.drive.DriveLog`.

    The log's odometry drives the prediction; every ``observe_every``
    records the landmarks visible from the true pose are observed
    (`observe_landmarks`, walls in the way).

    Parameters
    ----------
    log : DriveLog
        Best recorded every cycle (``every=1``): the prediction then follows
        the simulator's own slip model.
    landmarks : array_like (M, 2), optional
        Default: `world_landmarks` of the log's world.
    sensor : RangeBearingSensor, optional
    observe_every : int
        Records between observations.
    known : bool
        Known data association (else `associate`).
    rng : numpy.random.Generator, int or None
        The observation noise.
    **kw
        More `EKFSLAM` parameters.

    Returns
    -------
    EKFResult
    """
    from .metrics import trajectory_rms

    lm = world_landmarks(log.world) if landmarks is None else np.asarray(landmarks)
    rng = as_rng(rng)
    f = EKFSLAM(log.odometry[0], sensor=sensor, known=known, **kw)
    path, ne = [], []
    for t in range(len(log)):
        f.predict(log.odometry[t])
        if t % observe_every == 0:
            ids, z = observe_landmarks(lm, log.truth[t], f.sensor, log.world, rng)
            f.correct(z, ids)
        path.append(f.pose)
        ne.append(f.nees(log.truth[t]))
    path = np.array(path)
    if known and f.ids:
        err = f.landmarks - lm[np.array(f.ids)]
        lm_rms = float(np.sqrt(np.mean(np.sum(err**2, axis=1))))
    else:
        lm_rms = float("nan")
    return EKFResult(
        path=path,
        nees=np.array(ne),
        rms=trajectory_rms(path, log.truth),
        odometry_rms=trajectory_rms(log.odometry, log.truth),
        landmark_rms=lm_rms,
        filter=f,
    )
