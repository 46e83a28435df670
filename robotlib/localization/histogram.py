"""Histogram (grid) localization: the discrete Bayes filter before particles.

The belief is a probability per cell of a fixed grid (Thrun, Probabilistic
Robotics, table 4.1 and section 8.2):

- predict: shift the belief by the odometry increment and blur it with the
  motion noise (a convolution, mass-preserving; what leaves the grid is
  lost and the rest renormalised);
- update: multiply by the likelihood of the scan at each cell, normalise.

Procedural pieces (what Lab 1 asks students to write): `shift_kernel`,
`predict_1d`, `update`. Filters composed of them and of any sensor model
with a ``log_likelihood(poses, z)`` method (`BeamSensorModel`, ...):

- `HistogramFilter1D`: position along a straight line (a corridor's centre
  line), the heading taken from the odometry;
- `GridFilter`: position on a 2-D grid over the world's free space, times
  ``n_headings`` heading layers (grid localization).

Imports the world and nothing above the estimators; never plots.
"""

from __future__ import annotations

import math

import numpy as np

from ..world import World
from ..world.geometry import wrap_angle
from .motion import odometry_increment

__all__ = [
    "shift_kernel",
    "predict_1d",
    "update",
    "HistogramFilter1D",
    "GridFilter",
]


def shift_kernel(
    shift: float, sigma: float, resolution: float
) -> tuple[int, np.ndarray]:
    """Cell offsets and weights of a Gaussian motion of ``shift`` m, ``sigma`` m.

    Weight ``k`` is the Gaussian's mass over cell offset ``kmin + k``, that
    is over ``[(kmin + k - 1/2) r, (kmin + k + 1/2) r]`` for the cell side
    ``r``; offsets cover ``shift +- 6 sigma`` (at least the nearest cell).

    Parameters
    ----------
    shift : float
        Mean displacement, m.
    sigma : float
        Standard deviation, m (0: all mass in the nearest cell).
    resolution : float
        Cell side, m.

    Returns
    -------
    kmin : int
        Offset (cells) of the first weight.
    weights : numpy.ndarray, shape (K,)
        Sum to 1.
    """
    if not resolution > 0:
        raise ValueError(f"resolution must be positive, got {resolution}")
    if sigma < 0:
        raise ValueError(f"sigma must be non-negative, got {sigma}")
    centre = shift / resolution
    if sigma == 0:
        return int(math.floor(centre + 0.5)), np.ones(1)
    s = sigma / resolution
    kmin = int(math.floor(centre - 6 * s + 0.5))
    kmax = int(math.floor(centre + 6 * s + 0.5))
    edges = (np.arange(kmin, kmax + 2) - 0.5 - centre) / (s * math.sqrt(2.0))
    cdf = 0.5 * (1.0 + np.array([math.erf(e) for e in edges]))
    w = np.diff(cdf)
    return kmin, w / w.sum()


def _convolve_axis(belief: np.ndarray, kmin: int, w: np.ndarray, axis: int):
    """``out[i] = sum_k w[k] belief[i - kmin - k]`` along ``axis``, zero outside."""
    out = np.zeros_like(belief)
    n = belief.shape[axis]
    for k, wk in enumerate(w):
        off = kmin + k
        if abs(off) >= n or wk == 0.0:
            continue
        src = [slice(None)] * belief.ndim
        dst = [slice(None)] * belief.ndim
        src[axis] = slice(max(0, -off), n - max(0, off))
        dst[axis] = slice(max(0, off), n - max(0, -off))
        out[tuple(dst)] += wk * belief[tuple(src)]
    return out


def predict_1d(belief, shift: float, sigma: float, resolution: float) -> np.ndarray:
    """Move a 1-D belief by ``shift`` m with Gaussian noise ``sigma`` m.

    Parameters
    ----------
    belief : array_like, shape (n,)
        Probability per cell (sums to 1).
    shift, sigma : float
        Mean displacement and its standard deviation, m.
    resolution : float
        Cell side, m.

    Returns
    -------
    numpy.ndarray, shape (n,)
        The predicted belief, normalised (mass moved off the grid is lost;
        all lost: uniform).
    """
    b = np.asarray(belief, dtype=float)
    if b.ndim != 1:
        raise ValueError(f"belief must be 1-D, got shape {b.shape}")
    kmin, w = shift_kernel(shift, sigma, resolution)
    return _normalise(_convolve_axis(b, kmin, w, 0))


def update(belief, likelihood) -> np.ndarray:
    """Bayes' rule on a grid: ``belief * likelihood``, normalised.

    Parameters
    ----------
    belief, likelihood : array_like, same shape
        Prior per cell and ``p(z | cell)`` (non-negative, any scale).

    Returns
    -------
    numpy.ndarray
        The posterior; uniform over the prior's support if the product is 0
        everywhere.
    """
    b = np.asarray(belief, dtype=float)
    lk = np.asarray(likelihood, dtype=float)
    if b.shape != lk.shape:
        raise ValueError(f"belief {b.shape} and likelihood {lk.shape} differ")
    if np.any(lk < 0) or not np.all(np.isfinite(lk)):
        raise ValueError("likelihoods must be finite and non-negative")
    post = b * lk
    if post.sum() <= 0:
        post = (b > 0).astype(float)
    return _normalise(post)


def _normalise(b: np.ndarray) -> np.ndarray:
    total = b.sum()
    if total <= 0:
        return np.full_like(b, 1.0 / b.size)
    return b / total


def _likelihood(sensor, poses: np.ndarray, z) -> np.ndarray:
    """``p(z | pose)`` up to a factor, from the sensor's log-likelihood."""
    ll = np.asarray(sensor.log_likelihood(np.ascontiguousarray(poses), z), float)
    return np.exp(ll - ll.max())


class HistogramFilter1D:
    """Position along a straight line, on a grid of cells.

    The robot moves along the line ``y = y`` (m) in world coordinates; the
    state is its ``x``. Each step shifts the belief by the odometry's
    ``dx`` with noise ``sigma = sqrt(sigma_min^2 + (noise_per_m |dx|)^2)``, then
    weighs each cell by the scan's likelihood at ``(x_cell, y, theta_odo)``.

    Parameters
    ----------
    world : World
        The map.
    sensor : object
        A sensor model with ``log_likelihood(poses (N, 3), z (S,)) -> (N,)``.
    y : float
        The line, m.
    x_range : tuple of float, optional
        First and last cell centre, m (default: the world's bounds, a robot
        radius in).
    resolution : float
        Cell side, m.
    noise_per_m : float
        Motion noise per metre travelled (standard deviation, m/m).
    sigma_min : float
        Motion noise of every step, m.
    """

    def __init__(
        self,
        world: World,
        sensor,
        y: float,
        x_range: tuple[float, float] | None = None,
        resolution: float = 0.1,
        noise_per_m: float = 0.1,
        sigma_min: float = 0.05,
    ):
        if x_range is None:
            xmin, _, xmax, _ = world.bounds
            x_range = (xmin + 0.3, xmax - 0.3)
        n = int(round((x_range[1] - x_range[0]) / resolution)) + 1
        self.world = world
        self.sensor = sensor
        self.y = float(y)
        self.resolution = float(resolution)
        self.x = x_range[0] + resolution * np.arange(n)
        self.noise_per_m = float(noise_per_m)
        self.sigma_min = float(sigma_min)
        self.belief = np.full(n, 1.0 / n)

    def predict(self, dx: float) -> None:
        """Shift the belief by ``dx`` m (with noise)."""
        sigma = math.hypot(self.sigma_min, self.noise_per_m * dx)
        self.belief = predict_1d(self.belief, dx, sigma, self.resolution)

    def likelihood(self, z, theta: float) -> np.ndarray:
        """Return the scan's likelihood at each cell, heading ``theta``, shape (n,)."""
        poses = np.column_stack(
            [self.x, np.full_like(self.x, self.y), np.full_like(self.x, theta)]
        )
        return _likelihood(self.sensor, poses, z)

    def step(self, odo_prev, odo_now, z) -> float:
        """Predict with the odometry increment, update with the scan ``z`` (S,).

        Returns
        -------
        float
            The estimate: the most probable cell's ``x``, m.
        """
        odo_prev = np.asarray(odo_prev, float)
        odo_now = np.asarray(odo_now, float)
        self.predict(float(odo_now[0] - odo_prev[0]))
        self.belief = update(self.belief, self.likelihood(z, float(odo_now[2])))
        return self.estimate()

    def estimate(self) -> float:
        """Return the most probable cell's ``x``, m."""
        return float(self.x[int(np.argmax(self.belief))])


class GridFilter:
    """Grid localization: a 2-D position grid times heading layers.

    The belief has shape ``(n_headings, ny, nx)`` over the world's admissible
    cells (`World.free_space`); heading layer ``k`` stands for
    ``theta_k = -pi + 2 pi k / n_headings`` (rad). Predict decomposes the
    odometry increment as ``rot1, trans, rot2`` (`odometry_increment`); in
    each layer the belief moves by ``trans`` along ``theta_k + rot1`` and is
    blurred (``sigma = sqrt(sigma_min^2 + (noise_per_m trans)^2)``, m, both
    axes), then the layers turn by ``rot1 + rot2`` (split between the two
    nearest layers, and blurred by ``turn_noise`` rad per rad plus one
    layer's width). Update weighs every admissible cell and heading by the
    scan's likelihood.

    Parameters
    ----------
    world : World
        The map.
    sensor : object
        A sensor model with ``log_likelihood(poses (N, 3), z (S,)) -> (N,)``.
    resolution : float
        Cell side, m.
    n_headings : int
        Heading layers.
    noise_per_m, sigma_min, turn_noise : float
        Motion noise (see above).
    """

    def __init__(
        self,
        world: World,
        sensor,
        resolution: float = 0.2,
        n_headings: int = 36,
        noise_per_m: float = 0.1,
        sigma_min: float = 0.05,
        turn_noise: float = 0.1,
    ):
        free = world.free_space(resolution)
        self.world = world
        self.sensor = sensor
        self.resolution = float(free.resolution)
        self.free = np.asarray(free.data, dtype=bool)
        self.n_headings = int(n_headings)
        self.headings = -math.pi + 2 * math.pi * np.arange(n_headings) / n_headings
        self.noise_per_m = float(noise_per_m)
        self.sigma_min = float(sigma_min)
        self.turn_noise = float(turn_noise)
        centres = np.asarray(free.centres(), dtype=float)  # (ny, nx, 2)
        self.xy = centres
        iy, ix = np.nonzero(self.free)
        k = np.repeat(np.arange(self.n_headings), len(iy))
        self._index = (k, np.tile(iy, self.n_headings), np.tile(ix, self.n_headings))
        self._poses = np.column_stack(
            [centres[self._index[1], self._index[2]], self.headings[k]]
        )
        self.belief = np.zeros((self.n_headings, *self.free.shape))
        self.belief[:, self.free] = 1.0
        self.belief /= self.belief.sum()

    @property
    def n_cells(self) -> int:
        """Admissible poses the filter weighs (cells times headings)."""
        return len(self._poses)

    def predict(self, odo_prev, odo_now) -> None:
        """Move the belief by the odometry increment between two poses."""
        rot1, trans, rot2 = odometry_increment(odo_prev, odo_now)
        r = self.resolution
        sigma = math.hypot(self.sigma_min, self.noise_per_m * trans)
        out = np.empty_like(self.belief)
        for k, th in enumerate(self.headings):
            layer = self.belief[k]
            a = th + rot1
            for axis, shift in ((1, trans * math.cos(a)), (0, trans * math.sin(a))):
                kmin, w = shift_kernel(shift, sigma, r)
                layer = _convolve_axis(layer, kmin, w, axis)
            out[k] = layer
        width = 2 * math.pi / self.n_headings
        turn = wrap_angle(rot1 + rot2)
        tsig = math.hypot(width / 2, self.turn_noise * abs(turn))
        kmin, w = shift_kernel(turn, tsig, width)
        turned = np.zeros_like(out)
        for j, wj in enumerate(w):
            turned += wj * np.roll(out, kmin + j, axis=0)
        turned[:, ~self.free] = 0.0
        self.belief = _normalise(turned)

    def likelihood(self, z) -> np.ndarray:
        """Return the scan's likelihood, the belief's shape (0 off the free space)."""
        lk = np.zeros_like(self.belief)
        lk[self._index] = _likelihood(self.sensor, self._poses, z)
        return lk

    def step(self, odo_prev, odo_now, z) -> np.ndarray:
        """Predict, update with the scan ``z`` (S,); return `estimate`."""
        self.predict(odo_prev, odo_now)
        self.belief = update(self.belief, self.likelihood(z))
        return self.estimate()

    def estimate(self) -> np.ndarray:
        """Return the most probable cell and heading, ``(x, y, theta)``, m and rad."""
        k, i, j = np.unravel_index(int(np.argmax(self.belief)), self.belief.shape)
        return np.array([*self.xy[i, j], self.headings[k]])

    def weighted_poses(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the admissible poses (N, 3) and their probabilities (N,)."""
        return self._poses, self.belief[self._index]

    def position_belief(self) -> np.ndarray:
        """Return the belief summed over headings, shape ``(ny, nx)``."""
        return self.belief.sum(axis=0)
