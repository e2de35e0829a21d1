"""Throughput of the whole-log call: measured and printed, never asserted.

1. The Kalman filter on a random system (n = 4, p = 2, m = 3) over ``--steps`` steps (default 10^6):
   ``KalmanFilter.run`` against filterpy's ``KalmanFilter`` (``predict``/``update`` per step) on the
   same data, and the per-step Python calls of this package; the estimates are compared.
2. The set-membership filter on the straddle carrier (n = 4, p = 8, m = 4): ``SetMembershipFilter.run``
   against ``port-est filter`` (the workspace's command line, reading and writing CSV) on the same
   log, and ``fleet.filter_log`` (Parquet in, Parquet out) as the end-to-end Python path.

    cargo build --release -p port-est
    python examples/benchmark.py [--steps 1000000] [--filterpy-steps 1000000] [--port-est target/release/port-est]
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import port_estimation as pe
from port_estimation import fleet

ROOT = Path(__file__).resolve().parents[3]


def best_of(repeat: int, fn) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def kalman(steps: int, filterpy_steps: int, python_steps: int) -> None:
    from filterpy.kalman import KalmanFilter as FilterpyKF

    rng = np.random.default_rng(0)
    n, p, m = 4, 2, 3
    a = rng.normal(size=(n, n))
    a *= 0.95 / max(abs(np.linalg.eigvals(a)))
    b, c = rng.normal(size=(n, p)), rng.normal(size=(m, n))
    q, r = np.eye(n) * 1e-3, np.eye(m) * 1e-2
    us = rng.normal(size=(steps, p))
    x, ys = np.zeros(n), np.empty((steps, m))
    w, v = rng.normal(size=(steps, n)) * np.sqrt(1e-3), rng.normal(size=(steps, m)) * 0.1
    for k in range(steps):
        x = a @ x + b @ us[k] + w[k]
        ys[k] = c @ x + v[k]
    model = pe.Model(a, b, c)

    def ours():
        return pe.KalmanFilter(model, Q=q, R=r).run(us, ys)

    t_run = best_of(3, ours)
    log = ours()

    kf = FilterpyKF(dim_x=n, dim_z=m, dim_u=p)
    kf.x, kf.P, kf.F, kf.B, kf.H, kf.Q, kf.R = np.zeros(n), np.eye(n), a, b, c, q, r
    centers = np.empty((filterpy_steps, n))
    t0 = time.perf_counter()
    for k in range(filterpy_steps):
        kf.predict(u=us[k])
        kf.update(ys[k])
        centers[k] = kf.x
    t_filterpy = time.perf_counter() - t0
    diff = np.abs(centers - log.center[:filterpy_steps]).max() / np.abs(centers).max()

    stepper = pe.KalmanFilter(model, Q=q, R=r)
    t0 = time.perf_counter()
    for k in range(python_steps):
        stepper.step(us[k], ys[k])
    t_steps = time.perf_counter() - t0

    rate_run, rate_fp, rate_steps = steps / t_run, filterpy_steps / t_filterpy, python_steps / t_steps
    print(f"Kalman filter, n={n}, p={p}, m={m}")
    print(f"  {'KalmanFilter.run':<34}{steps:>10} steps {t_run:>9.3f} s {rate_run:>14,.0f} steps/s")
    print(f"  {'filterpy predict/update':<34}{filterpy_steps:>10} steps {t_filterpy:>9.3f} s {rate_fp:>14,.0f} steps/s")
    print(f"  {'KalmanFilter.step per call':<34}{python_steps:>10} steps {t_steps:>9.3f} s {rate_steps:>14,.0f} steps/s")
    print(f"  run / filterpy: {rate_run / rate_fp:.0f}x;  largest relative difference of the means: {diff:.1e}")


def set_membership(steps: int, port_est: Path) -> None:
    rng = np.random.default_rng(1)
    model = pe.Model.carrier(speed=6.0, load=1)
    a, b, c = model.A, model.B, model.C
    q, r, p0 = np.eye(4) * 1e-8, np.eye(4) * 1e-6, np.eye(4) * 1e-2
    us = 0.03 * np.sin(np.arange(steps) * 2e-3)[:, None] * np.ones(8) + rng.uniform(-0.005, 0.005, (steps, 8))
    x, ys = np.zeros(4), np.empty((steps, 4))
    for k in range(steps):
        x = a @ x + b @ us[k] + np.sqrt(1e-8 / 4) * rng.uniform(-1, 1, 4)
        ys[k] = c @ x + np.sqrt(1e-6 / 4) * rng.uniform(-1, 1, 4)

    def ours():
        return pe.SetMembershipFilter(model, P0=p0, Q=q, R=r).run(us, ys)

    t_run = best_of(3, ours)
    print(f"Set-membership filter (two-multiplier), straddle carrier, n=4, p=8, m=4, {steps} steps")
    print(f"  {'SetMembershipFilter.run':<34}{t_run:>9.3f} s {steps / t_run:>14,.0f} steps/s")

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        matrix = lambda m: "[" + ", ".join("[" + ", ".join(repr(float(v)) for v in row) + "]" for row in m) + "]"
        (tmp / "model.toml").write_text(
            f"a = {matrix(a)}\nb = {matrix(b)}\nc = {matrix(c)}\nq = {matrix(q)}\nr = {matrix(r)}\n"
            f"p0 = {matrix(p0)}\nx0 = [0.0, 0.0, 0.0, 0.0]\n"
        )
        header = "k," + ",".join(f"u{i + 1}" for i in range(8)) + "," + ",".join(f"y{i + 1}" for i in range(4))
        rows = np.column_stack([np.arange(steps), us, ys])
        np.savetxt(tmp / "log.csv", rows, delimiter=",", header=header, comments="", fmt=["%d"] + ["%.17g"] * 12)
        fleet.write_log(tmp / "log.parquet", np.arange(steps), us, ys)
        mf = pe.read_model(tmp / "model.toml")
        t_fleet = best_of(3, lambda: fleet.filter_log(tmp / "log.parquet", tmp / "est.parquet", model=mf, estimator="smf"))
        print(f"  {'fleet.filter_log (Parquet in/out)':<34}{t_fleet:>9.3f} s {steps / t_fleet:>14,.0f} steps/s")
        if not port_est.exists():
            print(f"  port-est not found at {port_est}: cargo build --release -p port-est")
            return
        cmd = [str(port_est), "filter", "--model", str(tmp / "model.toml"), "--input", str(tmp / "log.csv")]
        t_cli = best_of(3, lambda: subprocess.run(cmd + ["--output", str(tmp / "out.csv")], check=True, capture_output=True))
        print(f"  {'port-est filter (CSV in/out)':<34}{t_cli:>9.3f} s {steps / t_cli:>14,.0f} steps/s")
        print(f"  port-est / run: {t_cli / t_run:.2f}x the time;  port-est / fleet.filter_log: {t_cli / t_fleet:.2f}x")
        out = np.genfromtxt(tmp / "out.csv", delimiter=",", names=True, usecols=(1, 2, 3, 4))
        ref = np.column_stack([out[name] for name in out.dtype.names])
        print(f"  largest difference of the centres, run vs port-est: {np.abs(ref - ours().center).max():.1e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--filterpy-steps", type=int, default=None, help="default: --steps")
    parser.add_argument("--python-steps", type=int, default=100_000, help="per-call steps of this package")
    parser.add_argument("--port-est", type=Path, default=ROOT / "target" / "release" / "port-est")
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, {platform.processor() or 'cpu'}, Python {platform.python_version()}")
    kalman(args.steps, args.filterpy_steps or args.steps, min(args.python_steps, args.steps))
    set_membership(args.steps, args.port_est)


if __name__ == "__main__":
    main()
