"""The fleet batch: Parquet logs in, Parquet estimates out, the same bytes on a Dask cluster of two
worker processes as in one process."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import on_boundary

import port_estimation as pe
from port_estimation import fleet

pq = pytest.importorskip("pyarrow.parquet")


def _logs(tmp_path: Path, model: pe.Model, count: int, steps: int, q, r) -> list[Path]:
    n, p, m = model.dims
    paths = []
    for v in range(count):
        rng = np.random.default_rng(1000 + v)
        x = np.zeros(n)
        us = rng.uniform(-0.05, 0.05, size=(steps, p))
        ys = np.zeros((steps, m))
        for k in range(steps):
            x = model.f(x, us[k]) + on_boundary(rng, q) * rng.uniform()
            ys[k] = model.h(x, us[k]) + on_boundary(rng, r) * rng.uniform()
        path = tmp_path / "logs" / f"vehicle-{v:03d}.parquet"
        fleet.write_log(path, np.arange(5, 5 + steps), us, ys)
        paths.append(path)
    return paths


@pytest.fixture(scope="module")
def carrier():
    return pe.Model.carrier(speed=6.0, load=1), np.eye(4) * 1e-8, np.eye(4) * 1e-6, np.eye(4) * 1e-2


def test_a_log_round_trips_and_its_estimates_match_run(tmp_path, carrier):
    model, q, r, p0 = carrier
    (path,) = _logs(tmp_path, model, 1, 200, q, r)
    k, us, ys = fleet.read_log(path, inputs=8, measurements=4)
    assert k[0] == 5 and us.shape == (200, 8) and ys.shape == (200, 4)
    summary = fleet.filter_log(path, tmp_path / "out.parquet", model=model, estimator="smf", P0=p0, Q=q, R=r)
    assert summary["steps"] == 200
    table = pq.read_table(tmp_path / "out.parquet")
    assert table.column_names[:5] == ["k", "xhat1", "xhat2", "xhat3", "xhat4"]
    assert {"tau1", "status", "clean", "trace", "lo4", "hi4"} <= set(table.column_names)
    direct = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r).run(us, ys)
    np.testing.assert_array_equal(table.column("xhat2").to_numpy(), direct.center[:, 1])
    np.testing.assert_array_equal(table.column("hi3").to_numpy(), direct.upper[:, 2])
    assert table.column("status").to_pylist() == direct.status
    assert table.column("k").to_pylist() == list(range(6, 206))
    # Pieces give the same file.
    fleet.filter_log(path, tmp_path / "pieces.parquet", model=model, estimator="smf", P0=p0, Q=q, R=r, chunk_rows=33)
    assert pq.read_table(tmp_path / "pieces.parquet").equals(table)


def test_malformed_logs_are_named(tmp_path, carrier):
    model, q, r, p0 = carrier
    (path,) = _logs(tmp_path, model, 1, 10, q, r)
    k, us, ys = fleet.read_log(path, inputs=8, measurements=4)
    gap = tmp_path / "gap.parquet"
    fleet.write_log(gap, np.r_[k[:4], k[5:]], np.r_[us[:4], us[5:]], np.r_[ys[:4], ys[5:]])
    with pytest.raises(ValueError, match="gap.parquet: row 4: k jumps from 8 to 10"):
        fleet.filter_log(gap, tmp_path / "o.parquet", model=model, estimator="smf", P0=p0, Q=q, R=r)
    with pytest.raises(ValueError, match="missing y5"):
        fleet.read_log(path, inputs=8, measurements=5)
    assert not (tmp_path / "o.parquet").exists()


def test_a_model_file_brings_its_settings(tmp_path):
    text = (
        "a = [[1.0, 0.01], [0.0, 0.99]]\nb = [[0.0], [0.01]]\nc = [[1.0, 0.0]]\n"
        "q = [[1e-4, 0.0], [0.0, 1e-4]]\nr = [[1e-2]]\np0 = [[1.0, 0.0], [0.0, 1.0]]\nx0 = [0.0, 0.0]\n"
    )
    (tmp_path / "model.toml").write_text(text)
    fleet.write_log(tmp_path / "log.parquet", np.arange(50), np.ones((50, 1)), 0.01 * np.arange(50).reshape(-1, 1))
    (summary,) = fleet.filter_logs(
        [tmp_path / "log.parquet"], tmp_path / "out", model=tmp_path / "model.toml", estimator="kf"
    )
    assert summary["steps"] == 50 and summary["unclean"] == 0
    with pytest.raises(ValueError, match="brings its own"):
        fleet.filter_logs([tmp_path / "log.parquet"], tmp_path / "o2", model=tmp_path / "model.toml", estimator="kf", Q=1.0)


def test_the_dask_run_equals_the_serial_run_bit_for_bit(tmp_path, carrier):
    distributed = pytest.importorskip("distributed")
    model, q, r, p0 = carrier
    paths = _logs(tmp_path, model, 6, 400, q, r)
    serial = fleet.filter_logs(paths, tmp_path / "serial", model=model, estimator="smf", P0=p0, Q=q, R=r)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
    ) as cluster, distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        parallel = fleet.filter_logs(
            paths, tmp_path / "dask", model=model, estimator="smf", P0=p0, Q=q, R=r, client=client
        )
    assert [s["steps"] for s in parallel] == [s["steps"] for s in serial] == [400] * 6
    for s, d in zip(serial, parallel):
        assert Path(s["output"]).name == Path(d["output"]).name
        assert Path(s["output"]).read_bytes() == Path(d["output"]).read_bytes()


def test_an_output_never_replaces_a_log(tmp_path, carrier):
    model, q, r, p0 = carrier
    (path,) = _logs(tmp_path, model, 1, 10, q, r)
    before = path.read_bytes()
    kwargs = {"model": model, "estimator": "smf", "P0": p0, "Q": q, "R": r}
    with pytest.raises(ValueError, match="would overwrite the log"):
        fleet.filter_logs([path], path.parent, **kwargs)
    with pytest.raises(ValueError, match="would overwrite the log"):
        fleet.filter_log(path, path, **kwargs)
    # The same file under another name (a hard link) is the same log.
    link = tmp_path / "elsewhere" / path.name
    link.parent.mkdir()
    link.hardlink_to(path)
    with pytest.raises(ValueError, match="would overwrite the log"):
        fleet.filter_logs([path], link.parent, **kwargs)
    assert path.read_bytes() == before
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="chunk_rows must be a positive integer"):
            fleet.filter_log(path, tmp_path / "o.parquet", chunk_rows=bad, **kwargs)
    assert not (tmp_path / "o.parquet").exists()
