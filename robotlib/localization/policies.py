"""When and how `MCL` resamples: the resampling policies, and augmented MCL's injection.

Each policy is a small frozen dataclass with ``indexes(mcl)``, returning the
indexes of the particles to keep (or ``None``: no resampling this step):

- `PaperResampling`: every step, multinomial selection, then the paper's
  resize ``N = int(N exp(-lambda Ip))`` with a floor;
- `ThresholdResampling`: a resampler from `robotlib.localization.resampling`
  run only when the effective sample size falls below a share of ``N``;
- `KLDResampling`: KLD-sampling, every step (or below an ESS threshold).

`AugmentedInjection` adds augmented MCL's random particles (Thrun, table 8.3).
A policy of your own needs only ``indexes(mcl)``, reading the filter's
``particles``, ``weights``, ``ess``, ``world`` and ``rng``. Imports the
localization's own pieces, never `robotlib.localization.mcl` (which
imports this module).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .kld import kld_resample
from .paper import RESIZE_FLOOR, dispersion_index, resize
from .resampling import RESAMPLERS, multinomial_resample

__all__ = [
    "PaperResampling",
    "ThresholdResampling",
    "KLDResampling",
    "AugmentedInjection",
]


@dataclass(frozen=True)
class PaperResampling:
    """The paper's resampling: select (multinomial) then resize.

    Attributes
    ----------
    lam : float
        The paper's lambda in ``N = int(N exp(-lambda Ip))``; 0 keeps ``N``.
    floor : int
        Smallest population the resize leaves (the paper gives none).
    """

    lam: float = 0.5
    floor: int = RESIZE_FLOOR

    def indexes(self, mcl) -> np.ndarray:
        """Indexes of the new particle set (the resize truncates i.i.d. draws)."""
        idx = multinomial_resample(mcl.weights, mcl.rng)
        ip = dispersion_index(mcl.particles[idx], mcl.world.size)
        return idx[: resize(len(idx), ip, self.lam, self.floor)]


@dataclass(frozen=True)
class ThresholdResampling:
    """Resample with a named resampler when ``ESS < threshold * N``.

    Attributes
    ----------
    method : str
        A key of `robotlib.localization.resampling.RESAMPLERS`
        (``"systematic"`` / ``"low_variance"``, ``"stratified"``,
        ``"multinomial"``, ``"residual"``).
    threshold : float
        Share of ``N``; 1.0 (or more) resamples every step.
    """

    method: str = "systematic"
    threshold: float = 0.5

    def __post_init__(self):
        if self.method not in RESAMPLERS:
            raise ValueError(f"unknown resampler {self.method!r}")

    def indexes(self, mcl) -> np.ndarray | None:
        """Indexes of the new set, or None to keep the weighted set."""
        n = len(mcl.weights)
        if mcl.ess >= self.threshold * n and self.threshold < 1.0:
            return None
        return RESAMPLERS[self.method](mcl.weights, mcl.rng)


@dataclass(frozen=True)
class KLDResampling:
    """KLD-sampling (see `robotlib.localization.kld`).

    Attributes
    ----------
    n_min, n_max : int
        Fewest and most particles.
    epsilon, delta : float
        KL bound and its confidence.
    bin_xy, bin_theta : float
        Bin sizes, m and rad.
    threshold : float
        Resample when ``ESS < threshold * N``; 1.0 resamples every step.
    """

    n_min: int = 300
    n_max: int = 10_000
    epsilon: float = 0.05
    delta: float = 0.01
    bin_xy: float = 0.5
    bin_theta: float = math.radians(15.0)
    threshold: float = 1.0

    def indexes(self, mcl) -> np.ndarray | None:
        """Indexes of the new set, or None to keep the weighted set."""
        n = len(mcl.weights)
        if self.threshold < 1.0 and mcl.ess >= self.threshold * n:
            return None
        return kld_resample(
            mcl.particles,
            mcl.weights,
            mcl.world.bounds,
            mcl.rng,
            self.n_min,
            self.n_max,
            self.epsilon,
            self.delta,
            self.bin_xy,
            self.bin_theta,
        )


@dataclass
class AugmentedInjection:
    """Augmented MCL: inject random particles when the likelihood drops.

    Short- and long-term averages of the mean likelihood ``w_avg`` of each
    scan, ``w_fast += alpha_fast (w_avg - w_fast)`` and ``w_slow +=
    alpha_slow (w_avg - w_slow)``, with ``alpha_slow << alpha_fast``; when
    resampling, each new particle is replaced by a uniformly drawn one with
    probability ``max(0, 1 - w_fast / w_slow)``. Both averages start at the
    first scan's ``w_avg``.

    With ``grow`` set (for a filter whose population adapts, KLD-sampling),
    the random particles are added instead: ``int(probability * grow)`` of
    them on top of the resampled set, weighted to carry that probability's
    share of the total (so they dilute the next scan's mean likelihood, the
    signal, no more than replacing would), so a filter tracking with a few hundred
    particles gets back a global filter's numbers once its scans stop
    agreeing with its pose (a kidnapping); KLD-sampling then shrinks the set
    again. ``min_probability`` ignores smaller drops (sonar noise).

    Attributes
    ----------
    alpha_slow, alpha_fast : float
        Smoothing rates, ``0 < alpha_slow < alpha_fast <= 1``.
    grow : int or None
        Add up to this many random particles instead of replacing (None:
        replace, Thrun's table 8.3).
    min_probability : float
        Inject nothing while the probability is below this.
    share : float or None
        With ``grow``: the added particles' share of the total weight, at
        most (None: the probability). A small share keeps a false alarm (a
        stretch where the sonar disagrees with the map at the right pose)
        from pulling the estimate away, and keeps the random particles from
        diluting the signal; a kidnapped filter's particles all score so
        badly that the random ones near the true pose still win.
    """

    alpha_slow: float = 0.05
    alpha_fast: float = 0.5
    w_slow: float = float("nan")
    w_fast: float = float("nan")
    grow: int | None = None
    min_probability: float = 0.0
    share: float | None = None

    def __post_init__(self):
        if not 0 < self.alpha_slow < self.alpha_fast <= 1:
            raise ValueError("need 0 < alpha_slow < alpha_fast <= 1")
        if self.grow is not None and self.grow < 1:
            raise ValueError("grow must be None or at least 1")

    def update(self, log_mean_likelihood: float) -> None:
        """Feed one scan's log mean likelihood."""
        w_avg = math.exp(log_mean_likelihood)
        if math.isnan(self.w_slow):
            self.w_slow = self.w_fast = w_avg
        else:
            self.w_slow += self.alpha_slow * (w_avg - self.w_slow)
            self.w_fast += self.alpha_fast * (w_avg - self.w_fast)

    @property
    def probability(self) -> float:
        """Probability that a resampled particle is replaced by a random one."""
        if not self.w_slow > 0:
            return 0.0
        p = max(0.0, 1.0 - self.w_fast / self.w_slow)
        return p if p >= self.min_probability else 0.0

    def reset(self) -> None:
        """Forget the averages."""
        self.w_slow = self.w_fast = float("nan")
