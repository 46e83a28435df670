"""``robotlib bench map`` (also ``slam``): mapping and SLAM, speed and quality.

Prints, in one run: one sonar grid update (8 cones) and one laser scan
update against plain NumPy versions of the same work; grid FastSLAM steps
(30 particles, laser, the loop world's grid) as they come in a run, and one
step repeated on restored maps (cold caches), and its weighing against
NumPy; known-pose map F1 in the office (sonar, laser); grid FastSLAM in the
loop world over seeds (trajectory RMS, map F1; sonar: map error against
odometry-pose mapping); EKF-SLAM's average NEES over seeds against the 95 %
chi-square band. A peer (the Robotics Toolbox for Python's EKF) is timed
when installed, else skipped with a message. Asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace

import numpy as np

from ..mapping import (
    GridFastSLAM,
    OccupancyGrid,
    inverse_sonar_model,
    map_laser,
    map_score,
    map_sonar,
    record_drive,
    run_fastslam,
)
from ..mapping.ekfslam import chi2_band, run_ekfslam
from ..mapping.fastslam_settings import SONAR_PARTICLES, SONAR_SETTINGS
from ..sensing import SonarModel
from ..sensing.laser import laser_poses

__all__ = ["add_arguments", "run"]


def _out(line: str) -> None:
    print(line)  # noqa: T201 (a benchmark prints)


def _time(fn, min_time: float = 0.2) -> float:
    """Median seconds per call of ``fn`` (warm), over at least ``min_time``."""
    fn()
    times, total = [], 0.0
    while total < min_time or len(times) < 5:
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        times.append(dt)
        total += dt
    return float(np.median(times))


def _numpy_sonar_update(L, cells, pose, ranges, sonar):
    c, s = np.cos(pose[2]), np.sin(pose[2])
    for (ax, ay, ah), z in zip(sonar.sensors, ranges, strict=True):
        sp = (pose[0] + c * ax - s * ay, pose[1] + s * ax + c * ay, pose[2] + ah)
        L += inverse_sonar_model(cells, sp, z, sonar)
    np.clip(L, -6.0, 6.0, out=L)


def _numpy_weigh(maps, origin, res, lposes, angles, ranges, max_range, p_rand):
    hit = ranges < max_range
    a = lposes[:, 2:3] + angles[hit][None, :]
    px = lposes[:, 0:1] + ranges[hit] * np.cos(a)
    py = lposes[:, 1:2] + ranges[hit] * np.sin(a)
    j = np.floor((px - origin[0]) / res).astype(int)
    i = np.floor((py - origin[1]) / res).astype(int)
    n, ny, nx = maps.shape
    best = np.full(i.shape, -np.inf)
    rows = np.arange(n)[:, None]
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            ii, jj = i + di, j + dj
            ok = (ii >= 0) & (ii < ny) & (jj >= 0) & (jj < nx)
            v = np.where(
                ok, maps[rows, np.clip(ii, 0, ny - 1), np.clip(jj, 0, nx - 1)], 0
            )
            best = np.maximum(best, v)
    p = 1 - 1 / (1 + np.exp(best))
    return np.log(p_rand + (1 - p_rand) * p).sum(axis=1)


def _run_steps(f, log, t0: int, n: int) -> dict:
    """Time ``n`` steps of ``f`` on the log from record ``t0``, then undo them.

    Returns the median wall time and the CPU time a step (ms) and how many
    steps resampled. The filter's state is restored after (maps included).
    """
    saved = (f.maps.copy(), f.particles.copy(), f.logw.copy(), f._odo.copy(),
             f._diff.copy(), f.resampled, len(f._poses), f.copied)  # fmt: skip
    times, r0 = [], f.resampled
    c0 = time.process_time()
    for i in range(t0, t0 + n):
        w0 = time.perf_counter()
        f.step(log.odometry[i], log.laser[i])
        times.append(time.perf_counter() - w0)
    cpu = (time.process_time() - c0) / n
    res = {"n": n, "median_ms": 1e3 * float(np.median(times)), "cpu_ms": 1e3 * cpu,
           "resampled": f.resampled - r0}  # fmt: skip
    f.maps[:], f.particles, f.logw, f._odo, f._diff = saved[:5]
    f.resampled, f.copied = saved[5], saved[7]
    del f._poses[saved[6] :], f._parents[saved[6] :]
    return res


def speed(out: dict) -> None:
    """Time the kernels against NumPy."""
    log = record_drive("loop", seed=0, every=2)
    world = log.world
    sonar = SonarModel()
    t = len(log) // 3
    g = OccupancyGrid.for_world(world, 0.05)
    cells = np.stack(np.meshgrid(
        g.origin[0] + (np.arange(g.shape[1]) + 0.5) * 0.05,
        g.origin[1] + (np.arange(g.shape[0]) + 0.5) * 0.05,
    ), axis=-1)  # fmt: skip
    k = _time(lambda: g.update_sonar(log.truth[t], log.sonar[t], sonar))
    L = np.zeros(g.shape)
    n = _time(lambda: _numpy_sonar_update(L, cells, log.truth[t], log.sonar[t], sonar))
    out["sonar_update_us"] = k * 1e6
    out["sonar_update_numpy_us"] = n * 1e6
    _out(f"sonar grid update (8 cones, 5 cm cells): {k * 1e6:8.1f} us   "
          f"NumPy {n * 1e6:9.1f} us   x{n / k:6.1f}")  # fmt: skip
    g10 = OccupancyGrid.for_world(world, 0.1)
    k10 = _time(lambda: g10.update_sonar(log.truth[t], log.sonar[t], sonar))
    out["sonar_update_10cm_us"] = k10 * 1e6
    _out(f"sonar grid update (8 cones, 10 cm cells, the sonar maps' cells): "
         f"{k10 * 1e6:8.1f} us")  # fmt: skip
    k = _time(lambda: g.update_laser(log.truth[t], log.laser[t]))
    out["laser_update_us"] = k * 1e6
    _out(f"laser grid update (181 beams):           {k * 1e6:8.1f} us")
    f = GridFastSLAM.for_world(
        world, 0.05, start=log.odometry[0], n_particles=30, rng=0
    )
    for i in range(t):
        f.step(log.odometry[i], log.laser[i])
    # steps of the run itself, as they come (resampling ones included): each
    # particle's maps stay where the last step left them (warm caches)
    run = _run_steps(f, log, t, 80)
    out["fastslam_run_step_ms"] = run["median_ms"]
    out["fastslam_run_step_cpu_ms"] = run["cpu_ms"]
    _out(f"FastSLAM step, 30 particles, laser, {run['n']} steps of the run "
         f"({run['resampled']} resampling): median {run['median_ms']:6.2f} ms, "
         f"CPU {run['cpu_ms']:6.2f} ms a step")  # fmt: skip
    state = (f.maps.copy(), f.particles.copy(), f.logw.copy(), f._odo.copy())
    diff0 = f._diff.copy()
    settings = f.settings
    resampled = []

    def one_step(whole=False):
        f.maps[:], f.particles, f.logw, f._odo = (
            state[0],
            state[1].copy(),
            state[2].copy(),
            state[3].copy(),
        )
        # whole: forget where the maps differ, so resampling copies whole maps
        f._diff, f._diff_maps = diff0.copy(), (None if whole else f.maps)
        r = f.resampled
        f.step(log.odometry[t], log.laser[t])
        resampled.append(f.resampled - r)

    copy = _time(lambda: f.maps.__setitem__(slice(None), state[0]))
    step = _time(one_step) - copy
    whole = _time(lambda: one_step(True)) - copy
    out["fastslam_step_whole_copies_ms"] = whole * 1e3
    out["fastslam_step_resamples"] = bool(resampled[-1])
    f.settings = replace(settings, resample_below=2.0)  # made to resample
    rs = _time(one_step) - copy
    rs_whole = _time(lambda: one_step(True)) - copy
    f.settings = settings
    out["fastslam_resampling_step_ms"] = rs * 1e3
    out["fastslam_resampling_step_whole_copies_ms"] = rs_whole * 1e3
    out["fastslam_step_ms"] = step * 1e3
    out["fastslam_grid"] = list(f.maps.shape)
    lp = np.ascontiguousarray(laser_poses(f.particles, f.laser))
    w = _time(lambda: f.weigh_laser(f.particles, log.laser[t]))
    wn = _time(lambda: _numpy_weigh(
        f.maps, f.origin, 0.05, lp, f.laser.angles[::2], log.laser[t][::2],
        f.laser.max_range, f.settings.p_rand,
    ))  # fmt: skip
    out["fastslam_weigh_us"] = w * 1e6
    out["fastslam_weigh_numpy_us"] = wn * 1e6
    _out(f"  one step again and again, the maps restored before each (cold "
         f"caches), {f.maps.shape[1]} x "
          f"{f.maps.shape[2]}: {step * 1e3:6.2f} ms (copying where maps differ); "
          f"{whole * 1e3:6.2f} ms copying whole maps (resamples: "
          f"{'yes' if out['fastslam_step_resamples'] else 'no'})")  # fmt: skip
    _out(f"  the same step made to resample:        {rs * 1e3:6.2f} ms (copying where "
          f"maps differ); {rs_whole * 1e3:6.2f} ms copying whole maps")  # fmt: skip
    _out(f"  of which weighing:                     {w * 1e6:8.1f} us   "
          f"NumPy {wn * 1e6:9.1f} us   x{wn / w:6.1f}")  # fmt: skip


def quality(out: dict, seeds: int, ekf_seeds: int, first: int = 0,
            streams: int = 1, sonar_particles: int = 30,
            sonar_kw: dict | None = None) -> None:  # fmt: skip
    """Map and trajectory quality over seeds ``first .. first + seeds - 1``.

    Sonar FastSLAM runs ``streams`` times per log, with the filter's seeds
    ``seed + 1000 k``: its outcome depends much on the filter's own draws.
    ``sonar_kw``: `SONAR_SETTINGS` changed for the sonar runs.
    """
    sonar_kw = sonar_kw or {}
    sonar_settings = replace(SONAR_SETTINGS, **sonar_kw)
    log = record_drive("office", seed=0, every=2)
    w = log.world
    s = map_score(map_sonar(w, log.truth, log.sonar, 0.1), w, 0.1)
    la = map_score(map_laser(w, log.truth, log.laser, 0.05), w, 0.05)
    out["office_known_pose"] = {"sonar_f1": s.f1, "laser_f1": la.f1}
    _out(
        f"office, known poses: sonar F1 {s.f1:.3f} (10 cm), laser F1 {la.f1:.3f} (5 cm)"
    )
    rows, per_stream = [], []
    walls = sonar_settings.sonar_walls
    for seed in range(first, first + seeds):
        log = record_drive("loop", seed=seed, every=2)
        a = run_fastslam(log, 30, "laser", rng=seed)
        bs = [run_fastslam(log, sonar_particles, "sonar", rng=seed + 1000 * k,
                           settings=sonar_settings)
              for k in range(streams)]  # fmt: skip
        per_stream.append([(b.rms, b.score.mean_distance) for b in bs])
        odo = map_score(
            map_sonar(log.world, log.odometry, log.sonar, 0.1), log.world, 0.1
        )
        odo_w = map_score(
            map_sonar(log.world, log.odometry, log.sonar, 0.1, walls=walls),
            log.world, 0.1,
        )  # fmt: skip
        b = bs[0]
        rows.append([a.rms, a.score.f1, a.odometry_rms, b.rms, b.score.mean_distance,
                     odo.mean_distance, odo_w.mean_distance])  # fmt: skip
        _out(f"  loop seed {seed}: laser RMS {a.rms:.3f} m F1 {a.score.f1:.3f} | "
              f"odometry RMS {a.odometry_rms:.2f} m | sonar RMS {b.rms:.2f} m, map "
              f"error {b.score.mean_distance:.3f} m vs odometry map "
              f"{odo.mean_distance:.3f} m ({odo_w.mean_distance:.3f} m mapped as "
              f"FastSLAM maps)")  # fmt: skip
    r = np.array(rows)
    ps = np.array(per_stream)  # (seeds, streams, 2)
    out["fastslam_loop"] = {
        "seeds": seeds, "first_seed": first, "sonar_particles": sonar_particles,
        "sonar_kw": sonar_kw,
        "sonar_streams": streams,
        "sonar_rms_per_stream": ps[:, :, 0].mean(axis=0).tolist(),
        "sonar_map_error_per_stream": ps[:, :, 1].mean(axis=0).tolist(),
        "odometry_sonar_map_error_same_mapper_mean": r[:, 6].mean(),
        "laser_rms_mean": r[:, 0].mean(),
        "laser_rms_max": r[:, 0].max(),
        "laser_f1_min": r[:, 1].min(), "odometry_rms_mean": r[:, 2].mean(),
        "sonar_rms_mean": r[:, 3].mean(), "sonar_map_error_mean": r[:, 4].mean(),
        "odometry_sonar_map_error_mean": r[:, 5].mean(),
    }  # fmt: skip
    _out(f"FastSLAM loop, {seeds} seeds: laser RMS max {r[:, 0].max():.3f} m, F1 min "
          f"{r[:, 1].min():.3f}; sonar RMS mean {r[:, 3].mean():.2f} m, map error "
          f"{r[:, 4].mean():.3f} m vs {r[:, 5].mean():.3f} m (odometry), ratio "
          f"{r[:, 4].mean() / r[:, 5].mean():.3f} (odometry mapped as FastSLAM "
          f"maps: {r[:, 6].mean():.3f} m, ratio "
          f"{r[:, 4].mean() / r[:, 6].mean():.3f})")  # fmt: skip
    if streams > 1:
        rms_k, err_k = ps[:, :, 0].mean(axis=0), ps[:, :, 1].mean(axis=0)
        _out(f"  sonar, {sonar_particles} particles, {streams} filter streams: RMS "
             f"mean {rms_k.mean():.3f} m (per stream "
             f"{', '.join(f'{v:.2f}' for v in rms_k)}), map error / odometry's "
             f"{err_k.mean() / r[:, 5].mean():.3f} (same mapper: "
             f"{err_k.mean() / r[:, 6].mean():.3f})")  # fmt: skip
    if ekf_seeds < 1:
        return
    nees = []
    for seed in range(ekf_seeds):
        log = record_drive("loop", seed=seed, every=1, laser=False)
        nees.append(run_ekfslam(log, rng=seed).nees)
    T = min(map(len, nees))
    anees = np.mean([n[:T] for n in nees], axis=0)[1:]
    lo, hi = (v / ekf_seeds for v in chi2_band(3 * ekf_seeds))
    inside = float(np.mean((anees >= lo) & (anees <= hi)))
    out["ekf"] = {"seeds": ekf_seeds, "anees_mean": float(anees.mean()),
                  "band": [lo, hi], "share_of_steps_in_band": inside}  # fmt: skip
    _out(f"EKF-SLAM, {ekf_seeds} seeds: average NEES {anees.mean():.2f}, 95 % band "
          f"[{lo:.2f}, {hi:.2f}], steps in band {inside:.0%}")  # fmt: skip


def peer(out: dict, steps: int = 500, landmarks: int = 20) -> None:
    """Time the Robotics Toolbox's EKF-SLAM and ours on its own simulated run.

    The toolbox simulates a bicycle on a random path among ``landmarks``
    landmarks and runs its EKF-SLAM (one range-bearing reading a step, known
    association) for ``steps`` steps; then `ekf_predict`, `ekf_update` and
    `ekf_add_landmark` take the same odometry and readings. Skipped, with a
    message, when the toolbox is not installed (``pip install
    roboticstoolbox-python``). No grid FastSLAM is on PyPI to compare with
    (the plain NumPy weighing above is that comparison).
    """
    try:
        from roboticstoolbox import (
            EKF,
            Bicycle,
            LandmarkMap,
            RandomPath,
            RangeBearingSensor,
        )  # fmt: skip
    except ImportError:
        _out("peer: the Robotics Toolbox for Python is not installed "
             "(pip install roboticstoolbox-python); skipped")  # fmt: skip
        out["peer"] = None
        return
    import warnings

    from ..mapping.ekfslam import ekf_add_landmark, ekf_predict, ekf_update
    from ..sim import OdometryNoise

    V = np.diag([0.02, np.deg2rad(0.5)]) ** 2
    W = np.diag([0.1, np.deg2rad(1)]) ** 2
    robot = Bicycle(covar=V, animation=None)
    robot.control = RandomPath(workspace=10, seed=0)
    lm = LandmarkMap(landmarks, workspace=10, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        sensor = RangeBearingSensor(robot=robot, map=lm, covar=W, animate=False,
                                    seed=0)  # fmt: skip
        ekf = EKF(robot=(robot, V), P0=np.diag([1e-9] * 3), sensor=(sensor, W),
                  animate=False, x0=(0, 0, 0))  # fmt: skip
        t0 = time.perf_counter()
        ekf.run(T=steps * robot.dt)
        theirs = (time.perf_counter() - t0) / len(ekf.history)
    hist = ekf.history
    noise = OdometryNoise()

    def ours():
        mu, P, ids = np.zeros(3), np.eye(3) * 1e-9, {}
        for h in hist:
            mu, P = ekf_predict(mu, P, float(h.odo[0]), float(h.odo[1]), noise)
            if h.z is None or h.lm is None:
                continue
            if h.lm in ids:
                mu, P = ekf_update(mu, P, h.z, ids[h.lm], W)
            else:
                ids[h.lm] = len(ids)
                mu, P = ekf_add_landmark(mu, P, h.z, W)
        return mu

    mine = _time(ours) / len(hist)
    out["peer"] = {"name": "roboticstoolbox EKF-SLAM", "steps": len(hist),
                   "landmarks": landmarks, "theirs_ms": theirs * 1e3,
                   "ours_ms": mine * 1e3}  # fmt: skip
    _out(f"peer: EKF-SLAM step, {landmarks} landmarks, {len(hist)} steps of the "
         f"Robotics Toolbox's own run: toolbox {theirs * 1e3:.3f} ms, robotlib "
         f"{mine * 1e3:.3f} ms, x{theirs / mine:.1f}")  # fmt: skip
    _out("peer: no grid FastSLAM is installable from PyPI; the FastSLAM weighing "
         "is compared with plain NumPy above")  # fmt: skip


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``robotlib bench map``."""
    parser.add_argument(
        "--seeds", type=int, default=2, help="FastSLAM seeds (10: the issue's)"
    )
    parser.add_argument(
        "--ekf-seeds", type=int, default=5, help="EKF seeds (20: the issue's)"
    )
    parser.add_argument(
        "--speed-only", action="store_true", help="skip the quality runs"
    )
    parser.add_argument(
        "--first-seed", type=int, default=0, help="first FastSLAM seed (10: held out)"
    )
    parser.add_argument(
        "--streams", type=int, default=1,
        help="sonar FastSLAM runs per log, filter seeds seed + 1000 k",
    )  # fmt: skip
    parser.add_argument(
        "--sonar-particles", type=int, default=SONAR_PARTICLES,
        help="sonar FastSLAM particles",
    )  # fmt: skip
    parser.add_argument(
        "--sonar-incidence", type=float, default=None,
        help="sonar FastSLAM: echoes mark walls by incidence (rad) in each map",
    )  # fmt: skip
    parser.add_argument(
        "--quality-only", action="store_true", help="skip the speed runs"
    )
    parser.add_argument("--json", help="write the numbers to this file")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; return 0."""
    out: dict = {}
    if not args.quality_only:
        speed(out)
        peer(out)
    if not args.speed_only:
        kw = {}
        if args.sonar_incidence is not None:
            kw["sonar_incidence"] = args.sonar_incidence
        quality(out, args.seeds, args.ekf_seeds, args.first_seed, args.streams,
                args.sonar_particles, kw)  # fmt: skip
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(out, fh, indent=1, default=float)
    return 0
