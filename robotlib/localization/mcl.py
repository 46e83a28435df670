"""The `MCL` object: a particle filter composed of models and a resampler.

A motion model, a sensor model and a resampling policy make the filter.
One `MCL.step` is the textbook's loop:

1. predict: move every particle by the odometry increment plus noise;
2. update: weight each particle by the scan's likelihood (``w <- w p(z|x)``,
   normalised);
3. estimate: the weighted mean pose (circular mean of the heading);
4. resample when the policy says so (optionally injecting random
   particles: augmented MCL), and replace particles that left the
   admissible area (the paper's step 3).

When the sensor model offers a fused kernel (a model on a cone table) and
the motion model is the odometry model, steps 1-3 run in that one kernel,
chosen when the filter is built; it computes what `predict`, `update` and
`estimate` compute, from the same draws. `MCL.paper` builds the paper's
filter exactly; `MCL.best` the strongest configuration this project offers.
The resampling policies are in `robotlib.localization.policies`.
"""

from __future__ import annotations

import math

import numpy as np

from ..world import World
from .estimates import mode_estimate
from .history import StepInfo
from .motion import (
    PARALLEL_MIN,
    OdometryMotionModel,
    _particles,
    noise_std,
    odometry_increment,
)
from .paper import ADMISSIBLE_RADIUS, REGEN_WEIGHT, RESIZE_FLOOR, estimate, on_grid
from .policies import (
    AugmentedInjection,
    KLDResampling,
    PaperResampling,
    ThresholdResampling,
)
from .sensors import BeamParameters, BeamSensorModel, PaperSensorModel

__all__ = ["BEST", "MCL", "StepInfo"]


class MCL:
    """Monte Carlo localization, by composition.

    Parameters
    ----------
    world : World
        The map (admissible area, random particles, bins).
    sensor : object
        A sensor model with ``log_likelihood(particles, z) -> (N,)``
        (`robotlib.localization.sensors`).
    motion : object, optional
        A motion model with ``sample(particles, odo_prev, odo_now, rng)``
        (default `OdometryMotionModel`).
    resampling : object, optional
        A policy with ``indexes(mcl) -> ndarray | None`` (default
        `ThresholdResampling` with low-variance resampling at ESS < N/2).
    n : int
        Initial particle count.
    injection : AugmentedInjection, optional
        Random injection (augmented MCL); None for none.
    check : bool
        Replace particles off the admissible area after each step (the
        paper's step 3).
    regen_weight : float
        Relative weight of a replaced particle.
    admissible_radius, resolution : float
        The admissible area: clearance from walls and cell side, m.
    rng : numpy.random.Generator, int or None
        The filter's own randomness (``default_rng(rng)``).
    init : array_like, shape (3,), optional
        Start with particles around this pose (tracking) instead of uniform
        over the admissible area (global localization).
    init_std : tuple of float
        Standard deviations ``(x, y, theta)`` around ``init``, m and rad.
    estimator : str
        ``"mean"``: the weighted mean pose (`robotlib.localization.paper.estimate`);
        ``"mode"``: the weighted mean of the heaviest place
        (`robotlib.localization.estimates.mode_estimate`), which a cloud
        split over several places (a global start, a kidnapping) does not
        drag between them.
    """

    def __init__(
        self,
        world: World,
        sensor,
        motion=None,
        resampling=None,
        n: int = 300,
        injection: AugmentedInjection | None = None,
        check: bool = True,
        regen_weight: float = REGEN_WEIGHT,
        admissible_radius: float = ADMISSIBLE_RADIUS,
        resolution: float = 0.05,
        rng: np.random.Generator | int | None = None,
        init=None,
        init_std=(0.1, 0.1, 0.05),
        estimator: str = "mean",
    ):
        if n < 1:
            raise ValueError("n must be at least 1")
        if estimator not in ("mean", "mode"):
            raise ValueError(f"estimator must be 'mean' or 'mode', got {estimator!r}")
        self.estimator = estimator
        self.world = world
        self.sensor = sensor
        self.motion = OdometryMotionModel() if motion is None else motion
        self.resampling = ThresholdResampling() if resampling is None else resampling
        self.injection = injection
        self.check = bool(check)
        self.regen_weight = float(regen_weight)
        self.admissible_radius = float(admissible_radius)
        self.resolution = float(resolution)
        self.rng = np.random.default_rng(rng)
        self.map_diagonal = math.hypot(*world.size)
        self.admissible = world.free_space(self.resolution, self.admissible_radius)
        self.n_initial = int(n)
        self.init_std = tuple(float(s) for s in init_std)
        self.reset(init)

    # -- set up ---------------------------------------------------------------
    @property
    def sensor(self):
        """The sensor model; setting it chooses the step's path again."""
        return self._sensor

    @sensor.setter
    def sensor(self, model) -> None:
        self._sensor = model
        self._choose_path()

    @property
    def motion(self):
        """The motion model; setting it chooses the step's path again."""
        return self._motion

    @motion.setter
    def motion(self, model) -> None:
        self._motion = model
        self._choose_path()

    def _choose_path(self) -> None:
        """Use the sensor's fused kernel when the models allow (see the module)."""
        fused = getattr(getattr(self, "_sensor", None), "fused", None)
        odometry = type(getattr(self, "_motion", None)) is OdometryMotionModel
        self._fused = fused if odometry else None

    @classmethod
    def paper(
        cls,
        world: World,
        n: int = 300,
        lam: float = 0.5,
        floor: int = RESIZE_FLOOR,
        fast: bool = False,
        rng: np.random.Generator | int | None = None,
        **kwargs,
    ) -> MCL:
        """Build the paper's filter.

        Innovation weights, multinomial selection, resize, admissibility check.

        Parameters
        ----------
        world : World
            The map.
        n : int
            Initial particles (the paper: 300).
        lam : float
            The resize's lambda.
        floor : int
            The resize's floor.
        fast : bool
            Expected readings from a `ConeTable` instead of cone casts.
        rng : numpy.random.Generator, int or None
            Randomness.
        **kwargs
            Passed to `MCL` (e.g. ``init``, ``motion``, ``regen_weight``).
        """
        return cls(
            world,
            PaperSensorModel(world, fast=fast),
            resampling=PaperResampling(lam, floor),
            n=n,
            rng=rng,
            **kwargs,
        )

    @classmethod
    def best(
        cls,
        world: World,
        fast: bool = True,
        rng: np.random.Generator | int | None = None,
        **kwargs,
    ) -> MCL:
        """Build the strongest configuration the project offers (see `BEST`).

        Beam model (tempered), KLD-sampling from 50,000 particles down to no
        fewer than 300, optional augmented MCL, the admissibility check.
        """
        options = {**BEST, **kwargs}
        n = options.pop("n")
        beam = BeamParameters(**options.pop("beam"))
        kld = options.pop("kld")
        aug = options.pop("augmented")
        return cls(
            world,
            BeamSensorModel(world, fast=fast, params=beam),
            resampling=KLDResampling(**kld),
            injection=AugmentedInjection(**aug) if aug is not None else None,
            n=n,
            rng=rng,
            **options,
        )

    def reset(self, init=None) -> None:
        """Start again: uniform particles, or around ``init`` (3,) if given."""
        n = self.n_initial
        if init is None:
            self.particles = self.world.sample_free_poses(
                n, self.rng, self.resolution, self.admissible_radius
            )
        else:
            pose = np.asarray(init, dtype=float)
            if pose.shape != (3,):
                raise ValueError(f"init must be a pose (3,), got {pose.shape}")
            p = pose + self.rng.standard_normal((n, 3)) * np.array(self.init_std)
            p[:, 2] = (p[:, 2] + np.pi) % (2 * np.pi) - np.pi
            self.particles = p
        self.weights = np.full(n, 1.0 / n)
        self.ess = float(n)
        self.log_mean_likelihood = float("nan")
        self.last_estimate = self.estimate()
        self.info: StepInfo | None = None
        if self.injection is not None:
            self.injection.reset()

    # -- the parts of a step --------------------------------------------------
    def step(self, odo_prev, odo_now, z) -> np.ndarray:
        """One filter step: predict, update, estimate, resample.

        Parameters
        ----------
        odo_prev, odo_now : array_like, shape (3,)
            The robot's odometry before and after its move, m and rad.
        z : array_like, shape (S,)
            The sonar scan taken after the move, m.

        Returns
        -------
        numpy.ndarray, shape (3,)
            The estimate after the update (before resampling).
        """
        if hasattr(self.sensor, "checked_scan"):  # a bad scan changes nothing
            z = self.sensor.checked_scan(z)
        n = self.n
        if self._fused is not None:
            self.last_estimate = self._fused_step(odo_prev, odo_now, z)
            if self.estimator == "mode":  # the kernel gives the mean
                self.last_estimate = self.estimate()
        else:
            self.predict(odo_prev, odo_now)
            self.update(z)
            self.last_estimate = self.estimate()
        ess, log_mean = self.ess, self.log_mean_likelihood
        resampled, injected, regenerated = self.resample()
        self.info = StepInfo(n, ess, resampled, self.n, injected, regenerated, log_mean)
        return self.last_estimate

    def predict(self, odo_prev, odo_now) -> None:
        """Move the particles by the odometry increment plus noise."""
        self.particles = self.motion.sample(self.particles, odo_prev, odo_now, self.rng)

    def update(self, z) -> float:
        """Weight the particles by readings ``z`` (S,), m; return the log mean lik.

        ``w_j <- w_j p(z | x_j)``, normalised; the log of the mean likelihood
        ``sum_j w_j p(z | x_j)`` (prior weights) feeds augmented MCL.
        """
        ll = np.asarray(self.sensor.log_likelihood(self.particles, z), dtype=float)
        if ll.shape != self.weights.shape:
            raise ValueError(f"log_likelihood gave shape {ll.shape}, not (N,)")
        if np.isnan(ll).any() or np.isposinf(ll).any():
            raise ValueError("the sensor model's log_likelihood gave NaN or +inf")
        top = ll.max()
        if top == -np.inf:  # no particle fits the scan: the weights stay
            self._weighed(self.weights, top)
            return top
        w = self.weights * np.exp(ll - top)
        total = w.sum()
        self._weighed(w / total, top + math.log(total / self.weights.sum()))
        return self.log_mean_likelihood

    def _fused_step(self, odo_prev, odo_now, z) -> np.ndarray:
        """`predict`, `update` and `estimate` in the sensor's fused kernel."""
        increment = odometry_increment(odo_prev, odo_now)
        std = noise_std(self.motion.alphas, *increment)
        normals = self.rng.standard_normal((self.n, 3))  # as `predict` draws
        serial, threaded = self._fused
        kernel = threaded if self.n >= PARALLEL_MIN else serial
        moved, weights, est = (
            np.empty_like(self.particles),
            np.empty(self.n),
            np.empty(3),
        )
        log_mean, ess = kernel(
            self.particles, self.weights, normals, *increment, *std,
            *self.sensor.fused_arguments(z), moved, weights, est,
        )  # fmt: skip
        self.particles = moved
        self._weighed(weights, log_mean, ess)
        return est

    def _weighed(self, weights, log_mean: float, ess: float | None = None) -> None:
        """Take the updated weights and what the update measured."""
        self.weights = weights
        self.ess = float(1.0 / np.dot(weights, weights) if ess is None else ess)
        self.log_mean_likelihood = float(log_mean)
        if self.injection is not None:
            self.injection.update(self.log_mean_likelihood)

    def estimate(self) -> np.ndarray:
        """Return the pose estimate (3,): per ``estimator``, the mean or the mode."""
        if self.estimator == "mode":
            return mode_estimate(self.particles, self.weights)
        return estimate(self.particles, self.weights)

    def resample(self) -> tuple[bool, int, int]:
        """Resample per the policy, inject, check admissibility.

        Returns
        -------
        tuple
            ``(resampled, injected, regenerated)``.
        """
        idx = self.resampling.indexes(self)
        if idx is not None:
            self.particles = self.particles[idx]
            self.weights = np.full(len(idx), 1.0 / len(idx))
        injected = 0 if self.injection is None else self._inject(idx is not None)
        regenerated = self._regenerate() if self.check else 0
        return idx is not None, injected, regenerated

    def _inject(self, resampled: bool) -> int:
        """Augmented MCL: random particles in proportion to the likelihood's drop.

        Replacing (Thrun, table 8.3) happens when the set is resampled; adding
        (``grow``) on any step, since a kidnapped filter's particles all fit
        the scans equally badly, its weights stay even and its policy may not
        resample for several steps.
        """
        inj, n = self.injection, self.n
        prob = inj.probability
        if prob <= 0:
            return 0
        if inj.grow is None:  # replace (Thrun, table 8.3)
            if not resampled:
                return 0
            mask = self.rng.random(n) < prob
            k = int(mask.sum())
            if k:
                self.particles[mask] = self._random_poses(k)
            return k
        k = int(prob * inj.grow)  # add, carrying the probability's share
        if k:
            share = prob if inj.share is None else min(prob, inj.share)
            self.particles = np.concatenate([self.particles, self._random_poses(k)])
            kept = self.weights * ((1.0 - share) / self.weights.sum())
            self.weights = np.concatenate([kept, np.full(k, share / k)])
        return k

    def _regenerate(self) -> int:
        """Draw afresh the particles off the admissible area (the paper's step 3)."""
        bad = ~on_grid(self.admissible, self.particles)
        k = int(bad.sum())
        if k:
            self.particles[bad] = self._random_poses(k)
            w = self.weights.copy()
            w[bad] = self.regen_weight * w.mean()
            self.weights = w / w.sum()
        return k

    def _random_poses(self, k: int) -> np.ndarray:
        return self.world.sample_free_poses(
            k, self.rng, self.resolution, self.admissible_radius
        )

    @property
    def n(self) -> int:
        """Current particle count."""
        return len(self.particles)

    def set_particles(self, particles, weights=None) -> None:
        """Replace the particle set (weights default to uniform)."""
        p = _particles(particles).copy()
        if weights is None:
            w = np.full(len(p), 1.0 / len(p))
        else:
            w = np.ascontiguousarray(weights, dtype=float) / np.sum(weights)
        if w.shape != (len(p),):
            raise ValueError("weights must have shape (N,)")
        self.particles, self.weights = p, w


BEST = {
    "n": 50_000,
    "beam": {"sigma_hit": 0.15, "exponent": 0.2},
    "kld": {"n_min": 300, "n_max": 50_000, "epsilon": 0.02, "threshold": 0.5},
    "augmented": None,
}
"""Settings of `MCL.best`: beam model tempered to a fifth, KLD-sampling
(epsilon 0.02) from 50,000 particles down to no fewer than 300 when
ESS < N/2, no random injection.

Chosen on ``corridor2`` and ``office`` (20 seeds each), never on
``corridor``: 10,000 or 20,000 particles at the start leave too few near
the true pose in a large world (a few in 10,000 within 0.3 m and 0.15 rad),
and the filter settles on a look-alike place (the half-turned corridor) it
cannot leave; 50,000 and a tighter KLD bound (more particles while the
posterior has several modes) localized 40 of 40 runs there. Augmented MCL
(alpha 0.02 / 0.2) changed no run, so it is left off.
"""
