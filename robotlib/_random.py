"""The one conversion of a seed, a generator or ``None`` into a NumPy generator.

Every stochastic function of robotlib takes ``rng`` and passes it through
`as_rng`. Imports nothing of robotlib.
"""

from __future__ import annotations

import numpy as np

__all__ = ["as_rng"]


def as_rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    """Return a NumPy ``Generator`` from a generator, a seed or ``None``.

    Parameters
    ----------
    rng : numpy.random.Generator, int or None
        An existing generator (returned as is), a seed, or ``None`` for fresh
        OS entropy.

    Returns
    -------
    numpy.random.Generator
    """
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(rng)
