"""Grid FastSLAM: a Rao-Blackwellised particle filter, each particle with its map.

Each particle is a pose and a log-odds occupancy grid of its own. A step
(Probabilistic Robotics, table 13.1, on grids):

1. move every particle by the odometry increment plus slip noise
   (`robotlib.mapping.motion.sample_arc_motion`);
2. weigh it by the scan's likelihood in its own map (`weigh_laser`: the
   end-point model; `weigh_sonar`: a beam model, the echo against the
   nearest confirmed wall in the cone; both raised to a ``temperature``
   because beams are not independent);
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

from .._random import as_rng
from ..localization.resampling import effective_sample_size, systematic_resample
from ..sensing import SonarModel
from ..sensing.laser import LaserModel, laser_poses
from ..sim import OdometryNoise
from ..world import World
from . import _kernels, _kernels_copy, _kernels_window
from .motion import sample_arc_motion
from .occupancy import InverseLaserModel, InverseSonarModel, OccupancyGrid
from .resampling import normalise_log_weights, resample_maps, resample_parents
from .sharing import MapDiff
from .sonar_walls import incidence_marks, sonar_groups, update_sonar_marks

PARALLEL_MIN = 64
"""Particle count from which the per-particle kernels run over threads (below,
a thread pool's wake-up costs more than it saves, the more so on a busy
machine)."""

SONAR_WALL_SENSORS = (0, 3, 4, 7)
"""The P3-DX ring's sonars at +-90 and +-10 degrees: along a corridor or a
wall they meet the side walls and the walls ahead near their normal, where
the echo comes from the cone's axis (the +-30 and +-50 degree ones meet the
side walls 40-60 degrees off their normal, and echo from the cone's edge)."""

SONAR_DEFAULTS = {
    "temperature": 0.03,
    "inflate": 1.0,
    "resample_below": 0.5,
    "p_rand": 0.2,
    "sonar_sigma": 0.1,
    "sonar_walls": SONAR_WALL_SENSORS,
    "best_by": "path",
    "estimate": "mean",
}
"""`run_fastslam`'s defaults for the sonar (measured on the loop world: eight
wide cones tell little per record, so each weighs little; only the sonars
that meet walls near their normal mark walls, which leaves the known-pose
map's error at 0.067 m instead of 0.12 m, and an echo's range is then
trusted to 0.1 m about the map's). The run reports the posterior mean
trajectory and its map (``estimate="mean"``): on seeds 0-9 with 200
particles it cut the position RMS from 0.39 m (the best particle) to
0.29 m, filter streams k = 0-3 (session 7). The outcome depends much on
the filter's own draws: see the note of session 5 (``bench slam
--streams``)."""

SONAR_PARTICLES = 200
"""Particles the bench gives sonar FastSLAM. With `SONAR_DEFAULTS`, the loop
world's seeds 0-9, mean position RMS and map error over odometry mapping's,
filter seeds ``seed + 1000 k``, k = 0-3: 100 particles 0.33 m, 0.46; 200
particles 0.29 m, 0.43; held-out seeds 10-19, 200 particles, k = 0-1:
0.23 m, 0.39 (session 7; with the best particle instead of the mean,
session 6: 100 particles 0.45-0.58 m, 0.57-0.59)."""

__all__ = [
    "PARALLEL_MIN",
    "SONAR_DEFAULTS",
    "SONAR_PARTICLES",
    "SONAR_WALL_SENSORS",
    "GridFastSLAM",
    "normalise_log_weights",
    "resample_maps",
    "resample_parents",
]


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
    laser, sonar : optional
        The sensor models.
    laser_model, sonar_model : optional
        Their inverse models (map updates).
    motion : OdometryNoise, optional
        Slip assumed by the prediction (default: the simulator's).
    inflate : float
        Motion noise standard deviations times this.
    beam_step : int
        Weigh with every ``beam_step``-th laser beam.
    p_rand : float
        Floor of each beam's likelihood (a random reading).
    temperature : float
        Log-likelihoods times this before they are added to the weights.
    resample_below : float
        Resample when the effective sample size is below this share of N.
    match : bool
        Laser only: after the motion sample, fit each particle's pose to its
        own map by hill-climbing on the scan's end points (`match_laser`), a
        cheap version of GMapping's scan-matched proposal.
    match_step : tuple of float
        First hill-climbing steps, m and rad (halved ``match_levels`` times).
    match_levels : int
        How many times the steps are halved.
    match_beam_step : int
        Fit with every ``match_beam_step``-th beam.
    match_prior : tuple of float
        ``(w_xy, w_th)``: the fit's score less ``w_xy d^2 + w_th a^2`` for a
        move ``d`` m and a turn ``a`` rad from the motion's sample, so a
        scan that does not pin the pose along a corridor leaves it where the
        motion put it ((0, 0): none; without it, seed 9 of the bench's loop
        drives was pulled 0.9 m back along the west corridor).
    sonar_likelihood : {"beam", "endpoint"}
        Sonar weighing: the beam model (`_kernels.sonar_beam_loglik`) or the
        end-point model over the arc (as the laser's).
    sonar_sigma : float
        Beam model: standard deviation of an echo about the expected range, m.
    sonar_occ : float
        Beam model: log-odds above which a cell is a wall (confirmed by
        several echoes, so the arcs' stray cells do not count).
    sonar_unknown : float
        Beam model: weight of an echo from cells the map has not seen.
    sonar_walls : sequence of int, optional
        Sonar only: the sonars (indexes into ``sonar.sensors``) whose echoes
        mark the arc occupied in the particles' maps; the others' readings
        free their cones only. None: all. A cone that meets a wall obliquely
        echoes from its edge nearest the wall's normal, so its arc puts
        occupied cells in free space (a P3-DX in a corridor: the 30 and 50
        degree sonars, 0.1-0.3 m inside the corridor);
        `SONAR_WALL_SENSORS` are the ones that meet the walls it drives
        along or towards near their normal.
    sonar_incidence : float, optional
        Sonar only: choose per reading and particle, instead, which echoes mark
        walls: those whose wall in the particle's map (the log-odds gradient
        at the echo) is within this angle (rad) of facing the sonar; where
        the map shows no wall there yet, ``sonar_walls`` decides. None: off.
    window : int
        Sonar only: keep each particle's last ``window`` records out of its
        map (0: none) and weigh by them (``window_weigh``) in the map of the
        records before them; the oldest joins the map as a record arrives.
    window_weigh : {"window", "last"}
        Weigh by every record of the window (their log-likelihoods summed)
        or by the newest only.
    best_by : {"weight", "path"}
        Which particle `best` picks: the largest weight (the evidence since
        the last resampling) or the largest summed log-likelihood of every
        reading along its lineage (``path_loglik``, the whole run's evidence).
    sonar_range_to : {"entry", "centre"}
        Sonar beam model: a ray's expected range is where it enters its
        first wall cell, or that cell's centre (`_kernels.sonar_beam_loglik`).
    estimate : {"best", "mean"}
        What `run_fastslam` reports: the best particle's lineage and map, or
        the posterior mean trajectory (`mean_path`, the weighted mean of
        every particle's lineage) and its map (`mean_map`).
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
        laser: LaserModel | None = None,
        sonar: SonarModel | None = None,
        laser_model: InverseLaserModel | None = None,
        sonar_model: InverseSonarModel | None = None,
        motion: OdometryNoise | None = None,
        inflate: float = 1.5,
        beam_step: int = 2,
        p_rand: float = 0.1,
        temperature: float = 0.5,
        resample_below: float = 0.5,
        match: bool = True,
        match_step: tuple[float, float] = (0.04, 0.02),
        match_levels: int = 3,
        match_beam_step: int = 4,
        match_prior: tuple[float, float] = (300.0, 300.0),
        sonar_likelihood: str = "beam",
        sonar_sigma: float = 0.15,
        sonar_occ: float = 2.0,
        sonar_unknown: float = 0.5,
        sonar_walls=None,
        window: int = 0,
        window_weigh: str = "window",
        sonar_incidence: float | None = None,
        best_by: str = "weight",
        sonar_range_to: str = "entry",
        estimate: str = "best",
        rng: np.random.Generator | int | None = None,
    ):
        if sensor not in ("laser", "sonar"):
            raise ValueError(f"sensor must be 'laser' or 'sonar', got {sensor!r}")
        if n_particles < 1:
            raise ValueError("n_particles must be at least 1")
        if best_by not in ("weight", "path"):
            raise ValueError("best_by must be 'weight' or 'path'")
        self.best_by = best_by
        if sonar_range_to not in ("entry", "centre"):
            raise ValueError("sonar_range_to must be 'entry' or 'centre'")
        self.sonar_range_to = sonar_range_to
        if estimate not in ("best", "mean"):
            raise ValueError("estimate must be 'best' or 'mean'")
        self.estimate = estimate
        if sonar_likelihood not in ("beam", "endpoint"):
            raise ValueError("sonar_likelihood must be 'beam' or 'endpoint'")
        self.sensor = sensor
        self.sonar_likelihood = sonar_likelihood
        self.sonar_sigma = float(sonar_sigma)
        self.sonar_occ = float(sonar_occ)
        self.sonar_unknown = float(sonar_unknown)
        self.laser = LaserModel() if laser is None else laser
        self.sonar = SonarModel() if sonar is None else sonar
        self.laser_model = InverseLaserModel() if laser_model is None else laser_model
        self.sonar_model = InverseSonarModel() if sonar_model is None else sonar_model
        self.motion = OdometryNoise() if motion is None else motion
        self._wall_groups = sonar_groups(len(self.sonar.sensors), sonar_walls)
        self._default_marks = np.zeros(len(self.sonar.sensors), dtype=bool)
        for k, marks in self._wall_groups:
            self._default_marks[slice(None) if k is None else k] = marks
        self.sonar_incidence = sonar_incidence and float(sonar_incidence)
        self._angle_cache: dict = {}
        self._lp_last = None
        self.inflate = float(inflate)
        self.beam_step = int(beam_step)
        self.p_rand = float(p_rand)
        self.temperature = float(temperature)
        self.resample_below = float(resample_below)
        self.match = bool(match) and sensor == "laser"
        self.match_step = (float(match_step[0]), float(match_step[1]))
        self.match_levels = int(match_levels)
        self.match_beam_step = int(match_beam_step)
        self.match_prior = (float(match_prior[0]), float(match_prior[1]))
        self.window = int(window) if sensor == "sonar" else 0
        if window_weigh not in ("window", "last"):
            raise ValueError("window_weigh must be 'window' or 'last'")
        self.window_weigh = window_weigh
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
        k = self.beam_step
        out = np.empty(len(lp))
        self._kernel("laser_loglik_many")(
            self.maps, *self._geometry(), lp, self._angles(k),
            np.ascontiguousarray(np.asarray(scan, dtype=float)[::k]),
            self.laser.max_range, self.p_rand, out,
        )  # fmt: skip
        return out

    def weigh_sonar(self, poses, ranges) -> np.ndarray:
        """Log-likelihood (N,) of a sonar ring reading in each particle's map."""
        out = np.empty(len(poses))
        if self.sonar_likelihood == "beam":
            self._kernel("sonar_beam_loglik_many")(
                self.maps, *self._geometry(), np.ascontiguousarray(poses, dtype=float),
                self.sonar.sensors, np.ascontiguousarray(ranges, dtype=float),
                self.sonar.cone / 2, self.sonar.max_range, 5, self.sonar_sigma,
                self.p_rand, self.sonar_occ, self.sonar_unknown, out,
                self.sonar_range_to == "centre",
            )  # fmt: skip
            return out
        self._kernel("sonar_loglik_many")(
            self.maps, *self._geometry(), np.ascontiguousarray(poses, dtype=float),
            self.sonar.sensors, np.ascontiguousarray(ranges, dtype=float),
            self.sonar.cone / 2, self.sonar.max_range, 5, self.p_rand, out,
        )  # fmt: skip
        return out

    def match_laser(self, poses, scan) -> np.ndarray:
        """Fit each pose (N, 3) to the scan in its particle's map; return the fits."""
        k = self.match_beam_step
        out = np.empty((len(poses), 3))
        self._kernel("match_laser_many")(
            self.maps, *self._geometry(), np.ascontiguousarray(poses, dtype=float),
            np.asarray(self.laser.mount, dtype=float), self._angles(k),
            np.ascontiguousarray(np.asarray(scan, dtype=float)[::k]),
            self.laser.max_range, *self.match_step, self.match_levels,
            *self.match_prior, out,
        )  # fmt: skip
        return out

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
            m = self.laser_model
            self._kernel("laser_update_many")(
                maps, *self._geometry(),
                self._laser_poses(poses), self._angles(), z, self.laser.max_range,
                m.l_occ, m.l_free, m.l_min, m.l_max,
            )  # fmt: skip
        elif self.sonar_incidence is not None:
            self._update_sonar_incidence(maps, poses, z)
        else:
            m = self.sonar_model
            for k, marks in self._wall_groups:
                self._kernel("sonar_update_many")(
                    maps, *self._geometry(), poses,
                    self.sonar.sensors if k is None else self.sonar.sensors[k],
                    z if k is None else np.ascontiguousarray(z[k]),
                    self.sonar.cone / 2, self.sonar.max_range, m.thickness,
                    m.l_occ if marks else 0.0, m.l_free, m.sigma or 0.0,
                    m.max_weight, m.l_min, m.l_max,
                )  # fmt: skip

    def _update_sonar_incidence(self, maps, poses, z) -> None:
        """Add a ring reading, each echo marking walls by its incidence (``maps``)."""
        par = self.n >= PARALLEL_MIN
        marks = incidence_marks(
            maps, self._geometry(), poses, z, self.sonar, self.sonar_incidence,
            self._default_marks, par,
        )  # fmt: skip
        update_sonar_marks(
            maps, self._geometry(), poses, z, marks, self.sonar, self.sonar_model, par
        )

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
                z < self.sonar.max_range, z + 0.5 * self.sonar_model.thickness,
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
        if self.window_weigh == "last":
            return self.weigh_sonar(self.particles, scan)
        ll = np.empty(self.n)
        self._kernel("window_loglik_many", _kernels_window)(
            self.maps, *self._geometry(), wins, self.sonar.sensors, scans,
            self.sonar.cone / 2,
            self.sonar.max_range, 5, self.sonar_sigma, self.p_rand, self.sonar_occ,
            self.sonar_unknown, ll, self.sonar_range_to == "centre",
        )  # fmt: skip
        return ll

    # -- one step -----------------------------------------------------------
    def step(self, odometry, scan) -> None:
        """Take one record: the odometry pose (3,) and the reading then.

        The first call only adds the reading to the maps.
        """
        odo = np.asarray(odometry, dtype=float)
        parents = np.arange(self.n)
        if self._odo is not None:
            self.particles = sample_arc_motion(
                self.particles, self._odo, odo, self.motion, self.inflate, self.rng
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
            self.logw = self.logw + self.temperature * ll
            self.path_loglik = self.path_loglik + ll
            self.logw -= self.logw.max()
            if effective_sample_size(self.weights) < self.resample_below * self.n:
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
        if self.best_by == "path":
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
