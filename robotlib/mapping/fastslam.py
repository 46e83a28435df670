"""Grid FastSLAM: a Rao-Blackwellised particle filter, each particle with its map.

Each particle is a pose and a log-odds occupancy grid of its own. A step
(Probabilistic Robotics, table 13.1, on grids):

1. move every particle by the odometry increment plus slip noise
   (`robotlib.mapping.motion.sample_arc_motion`);
2. weigh it by the scan's likelihood in its own map (`weigh_laser`: the
   end-point model; `weigh_sonar`: a beam model, the echo against the
   nearest confirmed wall in the cone; both raised to a ``temperature``
   because beams are not independent); with the laser and
   ``proposal="gaussian"``, GMapping's scan-matched proposal
   (`GridFastSLAM.propose_laser`, `robotlib.mapping.proposal`) does 1 and 2;
3. when the effective sample size falls below ``resample_below * N``,
   resample (low-variance) and copy the survivors' maps over the maps of
   the particles that died, in place, so the filter holds exactly N maps
   (30 particles on a 400 x 400 grid: 19 MB); a copy covers only the box
   where the two maps may differ (`robotlib.mapping.sharing.MapDiff`: the
   cells written since they split), the same bits as a whole copy;
4. add the scan to every particle's map at its pose.

Each step records the particles and who descended from whom, so
`GridFastSLAM.best_path` is the whole trajectory of the best particle's
lineage, and `GridFastSLAM.mean_path` the weighted mean of every lineage
(the posterior mean trajectory, smoothed by the later readings), whose map
`GridFastSLAM.mean_map` builds. Seeded: the same ``rng`` gives the same
run, bit for bit. Imports the sensing models, the localization resampler
and this package's kernels; never plots.
"""

from __future__ import annotations

import numpy as np

from .._config import readonly
from .._random import as_rng
from ..localization.resampling import effective_sample_size, systematic_resample
from ..sensing import SonarModel
from ..sensing.laser import LaserModel, laser_poses
from ..world import World
from . import (
    _kernels,
    _kernels_copy,
    _kernels_match,
    _kernels_proposal,
    _kernels_window,
)
from .fastslam_settings import FastSLAMSettings
from .motion import apply_arc, arc_increment, arc_noise_cov, sample_arc_motion
from .occupancy import OccupancyGrid
from .proposal import (
    gaussian_draw,
    motion_log_prior,
    proposal_offsets,
    scan_normals,
    to_map_frame,
)
from .resampling import normalise_log_weights, resample_maps, resample_parents
from .sharing import MapDiff
from .sonar_walls import incidence_marks, sonar_groups, update_sonar_marks

PARALLEL_MIN = 64
"""Particle count from which the per-particle kernels run over threads (below,
a thread pool's wake-up costs more than it saves, the more so on a busy
machine)."""

__all__ = [
    "PARALLEL_MIN",
    "GridFastSLAM",
    "constrained_fit",
    "pinned_directions",
    "normalise_log_weights",
    "resample_maps",
    "resample_parents",
]


def pinned_directions(curvature, ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Return a fit's principal position directions and which of them it pins.

    Parameters
    ----------
    curvature : array_like, shape (N, 3)
        ``(cxx, cxy, cyy)``: a score's (or a match's information's) curvature
        in position, per m^2 (any common scale).
    ratio : float
        A direction counts as pinned when its curvature is positive and at
        least this share of the largest one's.

    Returns
    -------
    vec : numpy.ndarray, shape (N, 2, 2)
        Unit directions as columns, the weaker first.
    keep : numpy.ndarray of bool, shape (N, 2)
        Whether each direction is pinned.
    """
    c = np.asarray(curvature, dtype=float).reshape(-1, 3)
    h = np.stack([c[:, [0, 1]], c[:, [1, 2]]], axis=1)
    lam, vec = np.linalg.eigh(h)  # ascending: the weaker direction first
    return vec, (lam > 0) & (lam >= ratio * lam[:, 1:])


def constrained_fit(poses, fits, curvature, ratio: float) -> np.ndarray:
    """Keep each fit's move only along the directions its score pins.

    Parameters
    ----------
    poses, fits : numpy.ndarray, shape (N, 3)
        The motion's samples and their scan fits, m and rad.
    curvature : numpy.ndarray, shape (N, 3)
        ``(cxx, cxy, cyy)``: the fit score's curvature in position at each
        fit (`robotlib.mapping._kernels_match.fit_curvature_many`), per m^2.
    ratio : float
        A principal direction counts as pinned when its curvature is at least
        this share of the largest one's (and positive).

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        The fits' headings; positions: the sample's, moved by the fit's
        displacement projected on the pinned directions. Along a blank
        corridor the scan pins the heading and the across position only, and
        its fit drifts towards the cells the map has seen most often; there
        the sample (the odometry's increment with its noise) is kept.
    """
    vec, keep = pinned_directions(curvature, ratio)
    d = fits[:, :2] - poses[:, :2]
    along = np.einsum("nk,nkj->nj", d, vec) * keep  # components in the eigenbasis
    out = np.array(fits, dtype=float)
    out[:, :2] = poses[:, :2] + np.einsum("nj,nkj->nk", along, vec)
    return out


class GridFastSLAM:
    """Grid FastSLAM with a laser or a sonar ring.

    Parameters
    ----------
    shape, origin, resolution
        The maps' cells: ``(ny, nx)``, lower-left corner (m), side (m).
    start : array_like, shape (3,)
        The start pose; the map frame is the odometry frame at the start.
    n_particles : int
        Particles (and maps).
    sensor : {"laser", "sonar"}
        Which readings `step` takes.
    settings : FastSLAMSettings, optional
        Every other knob, with its default (`FastSLAMSettings()`; for the
        sonar, `robotlib.mapping.fastslam_settings.SONAR_SETTINGS` is tuned).
        The attribute may be replaced between steps; ``sonar_walls`` is read
        here only.
    laser, sonar : LaserModel, SonarModel, optional
        The robot's sensors (default: the simulator's).
    rng : numpy.random.Generator, int or None
        Motion noise and resampling.
    """

    def __init__(
        self,
        shape,
        origin,
        resolution: float,
        start,
        n_particles: int = 30,
        sensor: str = "laser",
        settings: FastSLAMSettings | None = None,
        *,
        laser: LaserModel | None = None,
        sonar: SonarModel | None = None,
        rng: np.random.Generator | int | None = None,
    ):
        if sensor not in ("laser", "sonar"):
            raise ValueError(f"sensor must be 'laser' or 'sonar', got {sensor!r}")
        if n_particles < 1:
            raise ValueError("n_particles must be at least 1")
        self.settings = FastSLAMSettings() if settings is None else settings
        if not isinstance(self.settings, FastSLAMSettings):
            kind = type(self.settings).__name__
            raise TypeError(f"settings must be a FastSLAMSettings, got {kind}")
        self.sensor = sensor
        self.laser = LaserModel() if laser is None else laser
        self.sonar = SonarModel() if sonar is None else sonar
        walls = self.settings.sonar_walls
        self._wall_groups = sonar_groups(len(self.sonar.sensors), walls)
        self._default_marks = np.zeros(len(self.sonar.sensors), dtype=bool)
        for k, marks in self._wall_groups:
            self._default_marks[slice(None) if k is None else k] = marks
        self._angle_cache: dict = {}
        self._lp_last = None
        self.rng = as_rng(rng)
        self.origin = (float(origin[0]), float(origin[1]))
        self.resolution = float(resolution)
        n = int(n_particles)
        self.maps = np.zeros((n, *(int(v) for v in shape)), dtype=np.float32)
        self.particles = np.tile(np.asarray(start, dtype=float), (n, 1))
        self.logw = np.zeros(n)
        self.path_loglik = np.zeros(n)
        self.resampled = 0
        self._poses: list[np.ndarray] = [self.particles.copy()]
        self._parents: list[np.ndarray] = [np.arange(n)]
        self._odo: np.ndarray | None = None
        self.copied = 0
        self._diff = MapDiff(n)
        self._diff_maps = self.maps
        self._win = np.empty((n, 0, 3))
        self._win_scans = np.empty((0, len(self.sonar.sensors)))

    @classmethod
    def for_world(cls, world: World, resolution: float = 0.05, **kw) -> GridFastSLAM:
        """Return a filter on ``world.occupancy_grid``'s cells, from its start pose."""
        truth = world.occupancy_grid(resolution)
        kw.setdefault("start", world.start)
        return cls(truth.shape, truth.origin, resolution, **kw)

    @property
    def match(self) -> bool:
        """Whether the laser's scans are matched (`FastSLAMSettings.match`)."""
        return self.settings.match and self.sensor == "laser"

    @property
    def window(self) -> int:
        """Records kept out of the maps (`FastSLAMSettings.window`; sonar only)."""
        return self.settings.window if self.sensor == "sonar" else 0

    @property
    def n(self) -> int:
        """Number of particles."""
        return len(self.particles)

    @property
    def weights(self) -> np.ndarray:
        """Normalised weights (N,)."""
        return normalise_log_weights(self.logw)

    # -- the pieces -------------------------------------------------------
    def _kernel(self, name: str, module=_kernels):
        """Return ``module``'s serial or threaded kernel ``name`` (N particles)."""
        return getattr(module, name + ("_parallel" if self.n >= PARALLEL_MIN else ""))

    def _geometry(self):
        return (*self.origin, self.resolution)

    def _angles(self, step: int = 1) -> np.ndarray:
        """Every ``step``-th beam direction of the laser (contiguous, kept)."""
        if self._angle_cache.get("laser") is not self.laser:
            self._angle_cache = {"laser": self.laser}
        if step not in self._angle_cache:
            self._angle_cache[step] = np.ascontiguousarray(self.laser.angles[::step])
        return self._angle_cache[step]

    def _laser_poses(self, poses) -> np.ndarray:
        """`laser_poses` of ``poses`` (N, 3), kept for the last poses asked for."""
        p, copy, lp, laser = self._lp_last or (None, None, None, None)
        if p is poses and laser is self.laser and np.array_equal(copy, poses):
            return lp
        lp = np.ascontiguousarray(laser_poses(poses, self.laser))
        self._lp_last = (poses, np.array(poses, dtype=float), lp, self.laser)
        return lp

    def weigh_laser(self, poses, scan) -> np.ndarray:
        """Log-likelihood (N,) of a laser scan in each particle's map at ``poses``."""
        lp = self._laser_poses(poses)
        k = self.settings.beam_step
        out = np.empty(len(lp))
        self._kernel("laser_loglik_many")(
            self.maps, *self._geometry(), lp, self._angles(k),
            np.ascontiguousarray(np.asarray(scan, dtype=float)[::k]),
            self.laser.max_range, self.settings.p_rand, out,
        )  # fmt: skip
        return out

    def weigh_sonar(self, poses, ranges) -> np.ndarray:
        """Log-likelihood (N,) of a sonar ring reading in each particle's map."""
        out = np.empty(len(poses))
        s = self.settings
        if s.sonar_likelihood == "beam":
            self._kernel("sonar_beam_loglik_many")(
                self.maps, *self._geometry(), np.ascontiguousarray(poses, dtype=float),
                readonly(self.sonar.sensors), np.ascontiguousarray(ranges, dtype=float),
                self.sonar.cone / 2, self.sonar.max_range, 5, s.sonar_sigma,
                s.p_rand, s.sonar_occ, s.sonar_unknown, out,
                s.sonar_range_to == "centre",
            )  # fmt: skip
            return out
        self._kernel("sonar_loglik_many")(
            self.maps, *self._geometry(), np.ascontiguousarray(poses, dtype=float),
            readonly(self.sonar.sensors), np.ascontiguousarray(ranges, dtype=float),
            self.sonar.cone / 2, self.sonar.max_range, 5, self.settings.p_rand, out,
        )  # fmt: skip
        return out

    def match_laser(self, poses, scan) -> np.ndarray:
        """Fit each pose (N, 3) to the scan in its particle's map; return the fits.

        With ``settings.match_degenerate`` > 0, a fit moves a pose only along
        the directions its score pins (`constrained_fit`).
        """
        s = self.settings
        k = s.match_beam_step
        poses = np.ascontiguousarray(poses, dtype=float)
        args = (
            np.asarray(self.laser.mount, dtype=float), self._angles(k),
            np.ascontiguousarray(np.asarray(scan, dtype=float)[::k]),
            self.laser.max_range,
        )  # fmt: skip
        out = np.empty((len(poses), 3))
        self._kernel("match_laser_many")(
            self.maps, *self._geometry(), poses, *args, *s.match_step, s.match_levels,
            *s.match_prior, out,
        )  # fmt: skip
        if s.match_degenerate <= 0.0:
            return out
        curv = np.empty((len(poses), 3))
        self._kernel("fit_curvature_many", _kernels_match)(
            self.maps, *self._geometry(), out, *args, self.resolution, curv
        )
        return constrained_fit(poses, out, curv, s.match_degenerate)

    def propose_laser(self, odo_prev, odo_now, scan) -> np.ndarray:
        """Draw every particle's pose from GMapping's proposal; return ``log eta``.

        Moves `particles` (`robotlib.mapping.proposal`: the odometry's
        prediction, fitted to the scan in the particle's own map with the
        motion prior, then a draw from the Gaussian about the fit). Returns
        the log weight factors (N,): the proposal's normalisers, the
        likelihood's temperature included.
        """
        s = self.settings
        ds, dth = arc_increment(odo_prev, odo_now)
        pred = apply_arc(self.particles, ds, dth)
        sd = np.sqrt(np.diag(arc_noise_cov(ds, dth, s.motion, s.inflate)))
        fxy, fth = s.proposal_floor
        sig = np.array([max(sd[0], fxy), max(sd[0], fxy), max(sd[1], fth)])
        pts, nrm = scan_normals(
            self.laser.mount, self._angles(), scan, self.laser.max_range, s.beam_step
        )  # fmt: skip
        ends = tuple(np.ascontiguousarray(v) for v in (*pts.T, *nrm.T))
        field = (*ends, 0.0, s.proposal_sigma, s.p_rand)  # occupied: log-odds > 0
        fits = np.empty_like(pred)
        self._kernel("fit_pose_many", _kernels_proposal)(
            self.maps, *self._geometry(), pred, *field, s.temperature, sig,
            *s.match_step, s.match_levels, fits,
        )  # fmt: skip
        offsets = proposal_offsets(sig)
        cands = np.ascontiguousarray(to_map_frame(fits, offsets))
        ll = np.empty(cands.shape[:2])
        self._kernel("field_loglik_many", _kernels_proposal)(
            self.maps, *self._geometry(), cands, *field, ll
        )
        log_tau = s.temperature * ll + motion_log_prior(cands, pred, sig)
        normals = self.rng.standard_normal((self.n, 3))
        draw = gaussian_draw(fits, offsets, log_tau, sig / 4, normals)
        self.particles = draw[0]
        return draw[1]

    def update_maps(self, scan, poses=None, maps=None) -> None:
        """Add a reading to every particle's map at the particle's pose.

        ``poses`` (N, 3) and ``maps`` (N, ny, nx) default to the particles'
        and the filter's.
        """
        z = np.ascontiguousarray(np.asarray(scan, dtype=float))
        poses = self.particles if poses is None else np.ascontiguousarray(poses)
        maps = self.maps if maps is None else maps
        if maps is self.maps and self._diff_maps is self.maps:
            # (maps replaced from outside: resampling will copy whole maps)
            self._track_writes(poses, z)
        if self.sensor == "laser":
            m = self.settings.laser_model
            self._kernel("laser_update_many")(
                maps, *self._geometry(),
                self._laser_poses(poses), self._angles(), z, self.laser.max_range,
                m.l_occ, m.l_free, m.l_min, m.l_max,
            )  # fmt: skip
        elif self.settings.sonar_incidence is not None:
            self._update_sonar_incidence(maps, poses, z)
        else:
            m = self.settings.sonar_model
            for k, marks in self._wall_groups:
                sensors = self.sonar.sensors if k is None else self.sonar.sensors[k]
                self._kernel("sonar_update_many")(
                    maps, *self._geometry(), poses, readonly(sensors),
                    z if k is None else np.ascontiguousarray(z[k]),
                    self.sonar.cone / 2, self.sonar.max_range, m.thickness,
                    m.l_occ if marks else 0.0, m.l_free, m.sigma or 0.0,
                    m.max_weight, m.l_min, m.l_max,
                )  # fmt: skip

    def _update_sonar_incidence(self, maps, poses, z) -> None:
        """Add a ring reading, each echo marking walls by its incidence (``maps``)."""
        par = self.n >= PARALLEL_MIN
        marks = incidence_marks(
            maps, self._geometry(), poses, z, self.sonar, self.settings.sonar_incidence,
            self._default_marks, par,
        )  # fmt: skip
        update_sonar_marks(
            maps, self._geometry(), poses, z, marks, self.sonar,
            self.settings.sonar_model, par,
        )  # fmt: skip

    def _tracked_diff(self) -> MapDiff:
        """Return the maps' `MapDiff` (whole-grid boxes if ``maps`` was replaced)."""
        if self._diff_maps is not self.maps:
            self._diff = MapDiff(self.n, same=False, shape=self.maps.shape[1:])
            self._diff_maps = self.maps
        return self._diff

    def _track_writes(self, poses, z) -> None:
        """Widen the `MapDiff` boxes by the cells a reading at ``poses`` writes."""
        diff = self._diff
        ny, nx = self.maps.shape[1:]
        boxes = np.empty((len(poses), 4), dtype=np.int64)
        if self.sensor == "laser":
            _kernels_copy.laser_boxes(
                *self._geometry(), ny, nx,
                self._laser_poses(poses), self._angles(), z, self.laser.max_range,
                boxes,
            )  # fmt: skip
        else:
            reach = np.where(
                z < self.sonar.max_range, z + 0.5 * self.settings.sonar_model.thickness,
                self.sonar.max_range,
            ).max()  # fmt: skip
            offset = np.hypot(*self.sonar.sensors[:, :2].T).max()
            _kernels_copy.disc_boxes(
                *self._geometry(), ny, nx, poses, float(reach + offset), boxes
            )
        diff.wrote(boxes)

    def _push_window(self, scan) -> None:
        """Append the particles and ``scan`` to the window; map the overflow."""
        z = np.asarray(scan, dtype=float)[None, :]
        self._win = np.concatenate([self._win, self.particles[:, None, :]], axis=1)
        self._win_scans = np.concatenate([self._win_scans, z])
        if self._win.shape[1] > self.window:
            self.update_maps(self._win_scans[0], self._win[:, 0])
            self._win = self._win[:, 1:]
            self._win_scans = self._win_scans[1:]

    def _window_step(self, scan) -> np.ndarray:
        """Return the log-likelihoods (N,) of the windows' records."""
        wins = np.ascontiguousarray(self._win)
        scans = np.ascontiguousarray(self._win_scans)
        s = self.settings
        if s.window_weigh == "last":
            return self.weigh_sonar(self.particles, scan)
        ll = np.empty(self.n)
        self._kernel("window_loglik_many", _kernels_window)(
            self.maps, *self._geometry(), wins, readonly(self.sonar.sensors), scans,
            self.sonar.cone / 2,
            self.sonar.max_range, 5, s.sonar_sigma, s.p_rand, s.sonar_occ,
            s.sonar_unknown, ll, s.sonar_range_to == "centre",
        )  # fmt: skip
        return ll

    # -- one step -----------------------------------------------------------
    def step(self, odometry, scan) -> None:
        """Take one record: the odometry pose (3,) and the reading then.

        The first call only adds the reading to the maps.
        """
        odo = np.asarray(odometry, dtype=float)
        s = self.settings
        parents = np.arange(self.n)
        if self._odo is not None:
            if self.match and s.proposal == "gaussian":
                # the proposal's normaliser, its likelihood tempered already
                ll = tempered = self.propose_laser(self._odo, odo, scan)
            else:
                self.particles = sample_arc_motion(
                    self.particles, self._odo, odo, s.motion, s.inflate, self.rng
                )
                if self.sensor == "laser":
                    if self.match:
                        self.particles = self.match_laser(self.particles, scan)
                    ll = self.weigh_laser(self.particles, scan)
                elif self.window:
                    self._push_window(scan)
                    ll = self._window_step(scan)
                else:
                    ll = self.weigh_sonar(self.particles, scan)
                tempered = s.temperature * ll
            self.logw = self.logw + tempered
            self.path_loglik = self.path_loglik + ll
            self.logw -= self.logw.max()
            if effective_sample_size(self.weights) < s.resample_below * self.n:
                idx = systematic_resample(self.weights, rng=self.rng)
                parents = resample_parents(idx, self.n)
                self.copied += self._tracked_diff().resample(self.maps, parents)
                self.particles = self.particles[parents]
                self.path_loglik = self.path_loglik[parents]
                self._win = self._win[parents]
                self.logw = np.zeros(self.n)
                self.resampled += 1
        elif self.window:
            self._push_window(scan)
        self._odo = odo.copy()
        if not self.window:
            self.update_maps(scan)
        self._poses.append(self.particles.copy())
        self._parents.append(parents)

    # -- results ------------------------------------------------------------
    def best(self) -> int:
        """Index of the particle with the largest weight (or path likelihood)."""
        if self.settings.best_by == "path":
            return int(np.argmax(self.path_loglik))
        return int(np.argmax(self.logw))

    def best_map(self) -> OccupancyGrid:
        """Return the best particle's map (a copy, with its window's records)."""
        k = self.best()
        g = OccupancyGrid(self.maps.shape[1:], self.origin, self.resolution)
        g.logodds[:] = self.maps[k]
        for t in range(self._win.shape[1]):
            pose = self._win[k : k + 1, t]
            self.update_maps(self._win_scans[t], pose, g.logodds[None])
        return g

    def best_path(self) -> np.ndarray:
        """Return the best particle's lineage: its pose at every record, (T, 3).

        The first row is the start pose (before any record).
        """
        k = self.best()
        out = np.empty((len(self._poses), 3))
        for t in range(len(self._poses) - 1, -1, -1):
            out[t] = self._poses[t][k]
            k = int(self._parents[t][k])
        return out

    def paths(self) -> np.ndarray:
        """Return every particle's lineage, (N, T, 3); row 0 is the start pose."""
        out = np.empty((self.n, len(self._poses), 3))
        k = np.arange(self.n)
        for t in range(len(self._poses) - 1, -1, -1):
            out[:, t] = self._poses[t][k]
            k = self._parents[t][k]
        return out

    def mean_path(self) -> np.ndarray:
        """Return the posterior mean trajectory, (T, 3), row 0 the start pose.

        At every record, the mean of the particles' lineages (`paths`)
        weighted by the particles' weights now: each lineage is a sample of
        the whole trajectory given every reading, so this is the filter's
        smoothed estimate (positions averaged, headings by their mean
        direction), not the filtered pose of the time.
        """
        p = self.paths()
        w = self.weights
        out = np.empty(p.shape[1:])
        out[:, :2] = np.einsum("n,ntk->tk", w, p[:, :, :2])
        out[:, 2] = np.arctan2(w @ np.sin(p[:, :, 2]), w @ np.cos(p[:, :, 2]))
        return out

    def mean_map(self, scans) -> OccupancyGrid:
        """Return the map of `mean_path` from the run's readings (T, ...).

        ``scans`` are the readings `step` took, in order; each is added at
        its record's mean pose with the particles' own map update.
        """
        path = self.mean_path()[1:]
        if len(scans) != len(path):
            raise ValueError(f"{len(path)} records were taken, got {len(scans)} scans")
        g = OccupancyGrid(self.maps.shape[1:], self.origin, self.resolution)
        for t in range(len(path)):
            self.update_maps(scans[t], path[t : t + 1], g.logodds[None])
        return g
