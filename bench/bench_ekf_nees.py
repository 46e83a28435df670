"""Laser EKF and UKF consistency on office drives: the NEES band, the error, divergence.

``python bench/bench_ekf_nees.py [--seeds 20] [--steps 150] [--variants NAME ...]
[--md FILE]``

Each seed records an office drive (`robotlib.mapping.drive.record_drive`,
a record every 0.5 s, every 4th kept: 2 s between updates) and draws the
start from the initial covariance (0.3 m, 0.3 m, 0.1 rad). Every variant
runs the same drives from the same starts, every tenth beam:

- ``EKF 5 cm``: one linearisation, 5 cm per beam, 3-sigma gate (the
  defaults before the iterated update);
- ``EKF sensor``: one linearisation, the sensor's own 5.8 mm, 2-sigma gate;
- ``IEKF, no NIS refusal``: the iterated update, every fit kept unless it
  loses all beams or fits worse than the prior's mean;
- ``IEKF sensor``: the iterated update (`laser_update`'s defaults: a fit
  whose NIS is beyond the chi-square's 1e-3 tail is refused too);
- ``oracle``: one linearisation at the true pose (not a filter: how far the
  linearisation point alone explains the inconsistency);
- ``UKF 5 cm``: one unscented update, 5 cm per beam, 3-sigma gate (the
  UKF's defaults before the iterated posterior linearisation; the old one
  also dropped beams whose sigma points' ranges bent by more than 5 cm);
- ``UKF sensor``: one unscented update at the sensor's 5.8 mm;
- ``IPLF sensor``: `ukf_laser_update`'s defaults (iterated posterior
  linearisation, the EKF's refusals).

The UKF variants predict with `ukf_predict`, the others with `ekf_predict`.

Printed per variant: the share of steps (the first 10 left out) whose NEES
is within its two-sided 95 % band, above it and below it; the mean position
error; seeds with at least 90 % in band; seeds that diverge (more than
0.3 m off on the last step); the first update's largest position error;
CPU ms per update (wall-clock sensitive: give the load with it).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from robotlib.localization import ekf, ukf
from robotlib.mapping.drive import record_drive
from robotlib.world import load_world, wrap_angle

START_STD = np.array([0.3, 0.3, 0.1])


def _oracle(mu, P, scan, world, model, beams, truth):
    """One EKF step with the ranges and slopes taken at the true pose."""
    zt, H, smooth = ekf._slopes(world, truth, model, beams)
    off = mu - truth
    off[2] = wrap_angle(off[2])
    sigma = ekf.laser_sigma(model)
    nu = scan[beams] - zt - H @ off
    spread = np.sqrt(np.einsum("bi,ij,bj->b", H, P, H) + sigma**2)
    ok = (scan[beams] < model.max_range) & smooth & (np.abs(nu) <= 2.0 * spread)
    if not ok.any():
        return mu, P
    mu, P, _ = ekf._update(mu, P, nu[ok], H[ok], np.eye(int(ok.sum())) * sigma**2)
    return mu, P


ONE_5CM = dict(sigma=0.05, gate=3.0, iterations=1, refuse=0.0)
VARIANTS = {
    "EKF 5 cm": (ekf.laser_update, ONE_5CM),
    "EKF sensor": (ekf.laser_update, dict(iterations=1, refuse=0.0)),
    "IEKF, no NIS refusal": (ekf.laser_update, dict(refuse=0.0)),
    "IEKF sensor": (ekf.laser_update, {}),
    "oracle": (None, None),
    "UKF 5 cm": (ukf.ukf_laser_update, ONE_5CM),
    "UKF sensor": (ukf.ukf_laser_update, dict(iterations=1, refuse=0.0)),
    "IPLF sensor": (ukf.ukf_laser_update, {}),
}


def run(seeds: int, steps: int, variants=tuple(VARIANTS)) -> dict:
    world = load_world("office")
    lo, hi = ekf.nis_band(3)
    rows = {name: [] for name in variants}
    for seed in range(seeds):
        log = record_drive("office", seed=seed, every=5, laser=True).every(4)
        n = min(steps, len(log.truth))
        start = log.truth[0] + np.random.default_rng(seed).normal(size=3) * START_STD
        beams = np.arange(0, log.laser_model.n_beams, 10)
        for name in variants:
            update, kw = VARIANTS[name]
            is_ukf = update is ukf.ukf_laser_update
            predict = ukf.ukf_predict if is_ukf else ekf.ekf_predict
            mu, P = start.copy(), np.diag(START_STD**2)
            ne, err, cpu = [], [], 0.0
            for k in range(n):
                if k:
                    mu, P = predict(mu, P, log.odometry[k - 1], log.odometry[k])
                t0 = time.process_time()
                if kw is None:
                    mu, P = _oracle(
                        mu, P, log.laser[k], world, log.laser_model, beams, log.truth[k]
                    )
                else:
                    mu, P, _, _ = update(
                        mu, P, log.laser[k], world, log.laser_model, beams, **kw
                    )
                cpu += time.process_time() - t0
                ne.append(ekf.nees(mu, P, log.truth[k]))
                err.append(np.hypot(*(mu[:2] - log.truth[k, :2])))
            ne = np.array(ne[10:])
            band = np.mean((ne >= lo) & (ne <= hi))
            rows[name].append(
                dict(
                    band=band,
                    above=np.mean(ne > hi),
                    below=np.mean(ne < lo),
                    error=np.mean(err[10:]),
                    good=band >= 0.9,
                    diverged=err[-1] > 0.3,
                    first=err[0],
                    ms=1e3 * cpu / n,
                )  # fmt: skip
            )
    return rows


def table(rows: dict) -> str:
    out = [
        "| variant | in band | above | below | mean error mm | seeds >= 90 % "
        "| diverged | first update's worst error m | CPU ms/update |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, runs in rows.items():
        m = {k: np.mean([r[k] for r in runs]) for k in runs[0]}
        out.append(
            f"| {name} | {m['band']:.0%} | {m['above']:.0%} | {m['below']:.0%} "
            f"| {1e3 * m['error']:.1f} | {sum(r['good'] for r in runs)}/{len(runs)} "
            f"| {sum(r['diverged'] for r in runs)}/{len(runs)} "
            f"| {max(r['first'] for r in runs):.3f} | {m['ms']:.2f} |"
        )
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=None)
    ap.add_argument("--md", help="also write the table to this file")
    a = ap.parse_args()
    text = table(run(a.seeds, a.steps, tuple(a.variants or VARIANTS)))
    print(text)
    if a.md:
        with open(a.md, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
