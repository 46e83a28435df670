"""Recording a filter's run from outside, as plain data (cf. filterpy's Saver).

`History.record` takes what a runner knows after each step (the true pose,
the filter, the time the step took); `History.arrays` returns NumPy arrays
and `History.to_dict` plain lists for JSON. The filter never records itself;
it says what its last step did (`StepInfo`, `MCL.info`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["History", "StepInfo", "localized_step"]


@dataclass(frozen=True)
class StepInfo:
    """What one `MCL.step` did.

    Attributes
    ----------
    n_particles : int
        Particles weighted this step.
    ess : float
        Effective sample size after weighting.
    resampled : bool
        Whether the set was resampled.
    n_after : int
        Particles after resampling (the next step's count).
    injected, regenerated : int
        Random particles added by augmented MCL, and by the admissibility
        check.
    log_mean_likelihood : float
        Log of the scan's mean likelihood under the prior weights.
    """

    n_particles: int
    ess: float
    resampled: bool
    n_after: int
    injected: int
    regenerated: int
    log_mean_likelihood: float


@dataclass
class History:
    """Per-step record of a localization run.

    Attributes
    ----------
    true_pose, estimate : list of numpy.ndarray, each shape (3,)
        Ground truth and the filter's estimate, m and rad.
    n_particles : list of int
        Particles weighted at each step.
    ess : list of float
        Effective sample size after weighting.
    time_ms : list of float
        Wall time of the filter step, ms (not reproducible, unlike the rest).
    """

    true_pose: list = field(default_factory=list)
    estimate: list = field(default_factory=list)
    n_particles: list = field(default_factory=list)
    ess: list = field(default_factory=list)
    time_ms: list = field(default_factory=list)

    def record(self, true_pose, mcl, time_ms: float = float("nan")) -> None:
        """Append one step: the truth, and the filter's estimate and stats.

        Parameters
        ----------
        true_pose : array_like, shape (3,)
            The robot's true pose after the step, m and rad.
        mcl : MCL
            The filter, just stepped (its ``last_estimate`` and ``info``).
        time_ms : float
            How long the step took, ms.
        """
        self.true_pose.append(np.array(true_pose, dtype=float))
        self.estimate.append(np.array(mcl.last_estimate, dtype=float))
        info = mcl.info
        self.n_particles.append(int(info.n_particles if info else mcl.n))
        self.ess.append(float(info.ess if info else mcl.ess))
        self.time_ms.append(float(time_ms))

    def __len__(self) -> int:
        return len(self.true_pose)

    @property
    def error(self) -> np.ndarray:
        """Position error per step, m, shape (T,)."""
        t = np.reshape(self.true_pose, (-1, 3))
        e = np.reshape(self.estimate, (-1, 3))
        return np.hypot(t[:, 0] - e[:, 0], t[:, 1] - e[:, 1])

    def arrays(self) -> dict[str, np.ndarray]:
        """All fields as arrays, plus ``error`` and ``step`` (1-based)."""
        return {
            "step": np.arange(1, len(self) + 1),
            "true_pose": np.reshape(self.true_pose, (-1, 3)),
            "estimate": np.reshape(self.estimate, (-1, 3)),
            "error": self.error,
            "n_particles": np.asarray(self.n_particles, dtype=np.int64),
            "ess": np.asarray(self.ess, dtype=float),
            "time_ms": np.asarray(self.time_ms, dtype=float),
        }

    def to_dict(self) -> dict[str, list]:
        """Plain lists (JSON-ready)."""
        return {k: v.tolist() for k, v in self.arrays().items()}

    def localized_step(self, tolerance: float = 0.5) -> int | None:
        """See `localized_step`."""
        return localized_step(self.error, tolerance)


def localized_step(errors, tolerance: float = 0.5) -> int | None:
    """First step (1-based) from which the error stays within ``tolerance`` to the end.

    Parameters
    ----------
    errors : array_like, shape (T,)
        Position error per step, m.
    tolerance : float
        m.

    Returns
    -------
    int or None
        None if the last step's error exceeds ``tolerance`` (or no steps).
    """
    e = np.asarray(errors, dtype=float)
    if len(e) == 0 or not e[-1] <= tolerance:
        return None
    bad = np.flatnonzero(~(e <= tolerance))
    return int(bad[-1]) + 2 if len(bad) else 1
