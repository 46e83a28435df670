"""The Pioneer 3-DX sonar model: cones, noise, specular misses and dropouts.

Each reading is the first echo inside a 30 degree cone, sampled by a few rays.
A ray that meets a wall at a grazing angle (beyond `SonarModel.specular_angle`
from the wall's normal) is reflected away and gives no echo; if no ray in the
cone echoes, the sonar reports either nothing (``max_range``) or the long path
of a reflected ray (multipath). Ranges get Gaussian noise proportional to the
range, and a reading drops out (``max_range``) at random. Every noise term is
a parameter; `SonarModel.ideal` switches them all off.

"No echo" is reported as ``max_range`` (5 m), as a Pioneer reports 5000 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .._config import readonly
from .._random import as_rng
from ..p3dx import SONAR_CONE, SONAR_MAX_RANGE, SONAR_MIN_RANGE, SONAR_POSES
from . import _kernels
from .raycast import _poses, _segments

__all__ = ["SonarModel", "expected_ranges", "simulate_ranges"]


@dataclass(frozen=True, eq=False)
class SonarModel:
    """Parameters of a sonar ring (defaults: a Pioneer 3-DX's eight front sonars).

    Attributes
    ----------
    sensors : numpy.ndarray, shape (S, 3)
        Sonar poses in the robot frame ``(x, y, heading)``, m and rad.
    cone : float
        Full opening angle of each cone, rad.
    n_rays : int
        Rays that sample each cone (1: a single ray on the axis).
    max_range, min_range : float
        Reported range limits, m; ``max_range`` also means "no echo".
    noise_std : float
        Standard deviation of the range noise as a fraction of the range
        (0.01 gives 1 cm at 1 m).
    specular_angle : float or None
        A ray meeting a wall further than this from the wall's normal reflects
        away, rad; None: every ray echoes.
    multipath_prob : float
        When no ray of a cone echoes, probability that the sonar reports the
        reflected ray's longer path instead of ``max_range``.
    dropout_prob : float
        Probability that a reading is lost (reported as ``max_range``).
    """

    sensors: np.ndarray = field(default_factory=lambda: SONAR_POSES)
    cone: float = SONAR_CONE
    n_rays: int = 7
    max_range: float = SONAR_MAX_RANGE
    min_range: float = SONAR_MIN_RANGE
    noise_std: float = 0.01
    specular_angle: float | None = math.radians(70.0)
    multipath_prob: float = 0.5
    dropout_prob: float = 0.01

    def __post_init__(self):
        s = np.ascontiguousarray(np.asarray(self.sensors, dtype=np.float64))
        if s.ndim != 2 or s.shape[1] != 3:
            raise ValueError(f"sensors must have shape (S, 3), got {s.shape}")
        s.setflags(write=False)
        object.__setattr__(self, "sensors", s)
        if self.n_rays < 1:
            raise ValueError("n_rays must be at least 1")
        if not 0 <= self.min_range < self.max_range:
            raise ValueError("need 0 <= min_range < max_range")
        for name in ("multipath_prob", "dropout_prob"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1]")
        if self.noise_std < 0:
            raise ValueError("noise_std must be non-negative")

    @classmethod
    def single_ray(cls, **changes) -> SonarModel:
        """Return MobileSim's sonar model: one ray on each sonar's axis.

        MobileSim (Stage) casts a single ray per sonar and reports the first
        wall it meets, at any angle: no cone, no specular misses, no
        multipath. robotlib's default cone is the better model of a real
        Pioneer (it sees walls off the axis, and misses ones met at a
        grazing angle); this option lets a run be compared with MobileSim's.
        ``changes`` override any other field (``noise_std``,
        ``dropout_prob``, ...).

        Examples
        --------
        >>> from robotlib.sim import Simulator
        >>> from robotlib.world import load_world
        >>> sim = Simulator(load_world("corridor"), seed=0,
        ...                 sonar=SonarModel.single_ray())
        """
        settings = {
            "n_rays": 1,
            "cone": 0.0,
            "specular_angle": None,
            "multipath_prob": 0.0,
            **changes,
        }
        return cls(**settings)

    @property
    def is_single_ray(self) -> bool:
        """Whether each sonar is one ray on its axis (MobileSim's model)."""
        return self.n_rays == 1

    def ideal(self) -> SonarModel:
        """Return the same ring with no noise, specular misses or dropouts."""
        return replace(
            self,
            noise_std=0.0,
            specular_angle=None,
            multipath_prob=0.0,
            dropout_prob=0.0,
        )

    @property
    def cos_specular(self) -> float:
        """Cosine of the specular angle (-1 when specular misses are off)."""
        return -1.0 if self.specular_angle is None else math.cos(self.specular_angle)


def _scan(walls, poses, model, uniforms, normals):
    p = _poses(poses)
    seg = _segments(walls)
    out = np.empty((len(p), len(model.sensors)))
    kernel = _kernels.sonar_scan_parallel if len(p) > 64 else _kernels.sonar_scan
    kernel(
        p,
        readonly(model.sensors),
        seg,
        int(model.n_rays),
        float(model.cone),
        float(model.max_range),
        float(model.min_range),
        model.cos_specular,
        float(model.noise_std),
        float(model.multipath_prob),
        float(model.dropout_prob),
        uniforms,
        normals,
        out,
    )
    return out


def expected_ranges(walls, poses, model: SonarModel | None = None) -> np.ndarray:
    """Noise-free sonar readings: each cone's first echo, or ``max_range``.

    Specular misses follow ``model.specular_angle`` (they are geometry, not
    noise); multipath, noise and dropouts are left out.

    Parameters
    ----------
    walls : World or array_like, shape (M, 4)
        A world or its obstacle segments, m.
    poses : array_like, shape (3,) or (K, 3)
        Robot poses ``(x, y, theta)``, m and rad.
    model : SonarModel, optional
        The sonar ring (default: a Pioneer 3-DX's).

    Returns
    -------
    numpy.ndarray, shape (K, S)
        Ranges in m, in ``[min_range, max_range]``.
    """
    model = SonarModel() if model is None else model
    p = _poses(poses)
    out = np.empty((len(p), len(model.sensors)))
    kernel = _kernels.expected_scan_parallel if len(p) > 64 else _kernels.expected_scan
    kernel(
        p,
        readonly(model.sensors),
        _segments(walls),
        int(model.n_rays),
        float(model.cone),
        float(model.max_range),
        float(model.min_range),
        model.cos_specular,
        out,
    )
    return out


def simulate_ranges(
    walls,
    poses,
    model: SonarModel | None = None,
    rng: np.random.Generator | int | None = None,
) -> np.ndarray:
    """Noisy sonar readings as a robot would report them.

    Parameters
    ----------
    walls : World or array_like, shape (M, 4)
        A world or its obstacle segments, m.
    poses : array_like, shape (3,) or (K, 3)
        Robot poses, m and rad.
    model : SonarModel, optional
        The sonar ring and its noise (default: a Pioneer 3-DX's).
    rng : numpy.random.Generator, int or None
        Randomness; the same seed gives the same readings, bit for bit.

    Returns
    -------
    numpy.ndarray, shape (K, S)
        Ranges in m, in ``[min_range, max_range]`` (``max_range``: no echo).
    """
    model = SonarModel() if model is None else model
    rng = as_rng(rng)
    k, s = len(_poses(poses)), len(model.sensors)
    uniforms = rng.random((k, s, 2))
    normals = rng.standard_normal((k, s))
    return _scan(walls, poses, model, uniforms, normals)
