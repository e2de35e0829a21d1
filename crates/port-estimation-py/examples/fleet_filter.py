"""A fleet's logs filtered on Dask, one task per log, and the same logs filtered in one process.

Writes ``--vehicles`` synthetic straddle-carrier logs (Parquet, columns ``k, u1..u8, y1..y4``: the
eight steering angles and the four measured states, noise inside its ellipsoidal bounds), filters
them with the set-membership filter serially and on a Dask cluster, checks that the outputs are
the same bytes, and prints the throughput in steps per second.

    python examples/fleet_filter.py                                  # 8 logs x 100 000 steps, 2 local workers
    python examples/fleet_filter.py --vehicles 32 --steps 250000 --workers 2
    python examples/fleet_filter.py --scheduler tcp://scheduler:8786 --out /shared/fleet   # a real cluster

On a real cluster every worker needs ``port_estimation`` and ``pyarrow`` installed and must see
``--out`` at the same path (a shared file system): the logs are written there and each worker
reads its logs and writes its estimates there.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import port_estimation as pe
from port_estimation import fleet

Q, R, P0 = np.eye(4) * 1e-8, np.eye(4) * 1e-6, np.eye(4) * 1e-2


def inside(rng: np.random.Generator, shape: np.ndarray, count: int) -> np.ndarray:
    """``count`` points uniformly inside the ellipsoid ``{z : z' shape^-1 z <= 1}``."""
    z = rng.normal(size=(count, shape.shape[0]))
    z *= (rng.uniform(size=(count, 1)) ** (1 / shape.shape[0])) / np.linalg.norm(z, axis=1, keepdims=True)
    return z @ np.linalg.cholesky(shape).T


def write_logs(model: pe.Model, directory: Path, vehicles: int, steps: int) -> list[Path]:
    a, b, c = model.A, model.B, model.C
    paths = []
    for v in range(vehicles):
        rng = np.random.default_rng(v)
        t = np.arange(steps) * 1e-3
        us = 0.03 * np.sin(2 * np.pi * (0.2 + 0.05 * v) * t)[:, None] * np.ones(8) + rng.uniform(-0.005, 0.005, (steps, 8))
        w, noise = inside(rng, Q, steps), inside(rng, R, steps)
        x, ys = np.zeros(4), np.empty((steps, 4))
        for k in range(steps):
            x = a @ x + b @ us[k] + w[k]
            ys[k] = c @ x + noise[k]
        path = directory / f"carrier-{v:04d}.parquet"
        fleet.write_log(path, np.arange(steps), us, ys)
        paths.append(path)
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--vehicles", type=int, default=8)
    parser.add_argument("--steps", type=int, default=100_000, help="steps per log")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the local cluster")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (instead of a local cluster)")
    parser.add_argument("--estimator", default="smf", help="a registry name (see port_estimation.estimators())")
    parser.add_argument("--out", type=Path, help="working directory (default: a temporary one)")
    args = parser.parse_args()

    from dask.distributed import Client, LocalCluster

    out = args.out or Path(tempfile.mkdtemp(prefix="fleet-"))
    model = pe.Model.carrier(speed=6.0, load=1)
    t0 = time.perf_counter()
    paths = write_logs(model, out / "logs", args.vehicles, args.steps)
    print(f"{len(paths)} logs of {args.steps} steps written to {out / 'logs'} in {time.perf_counter() - t0:.1f} s")
    common = dict(model=model, estimator=args.estimator, P0=P0, Q=Q, R=R)
    total = args.vehicles * args.steps

    t0 = time.perf_counter()
    serial = fleet.filter_logs(paths, out / "serial", **common)
    t_serial = time.perf_counter() - t0

    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    workers = len(client.scheduler_info()["workers"])
    client.run(lambda: __import__("port_estimation"))  # import on every worker before timing
    t0 = time.perf_counter()
    parallel = fleet.filter_logs(paths, out / "dask", client=client, **common)
    t_dask = time.perf_counter() - t0
    client.close()
    if cluster is not None:
        cluster.close()

    failed = [s for s in serial + parallel if s["status"] != "ok"]
    for s in failed:
        print(f"failed: {s['error']}")
    if failed:
        raise SystemExit(f"{len(failed)} of {len(serial) + len(parallel)} runs of a log failed")
    same = all(Path(s["output"]).read_bytes() == Path(d["output"]).read_bytes() for s, d in zip(serial, parallel))
    unclean = sum(s["unclean"] for s in serial)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    print(f"{'run':<24}{'seconds':>10}{'steps/s':>14}")
    print(f"{'serial (1 process)':<24}{t_serial:>10.2f}{total / t_serial:>14,.0f}")
    print(f"{f'dask ({workers} workers)':<24}{t_dask:>10.2f}{total / t_dask:>14,.0f}")
    print(f"outputs identical: {same}; steps not clean: {unclean} of {total}")
    if not same:
        raise SystemExit("the Dask outputs differ from the serial ones")


if __name__ == "__main__":
    main()
