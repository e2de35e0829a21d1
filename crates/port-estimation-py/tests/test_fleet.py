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


def _outlier_log(tmp_path: Path, model, q, r, row: int) -> Path:
    """A log whose measurement at ``row`` is far outside its bound (the filter refuses that step)."""
    (path,) = _logs(tmp_path / "bad", model, 1, 400, q, r)
    k, us, ys = fleet.read_log(path, inputs=8, measurements=4)
    ys[row] += 10.0
    bad = tmp_path / "logs" / "vehicle-bad.parquet"
    fleet.write_log(bad, k, us, ys)
    return bad


@pytest.fixture
def cluster(tmp_path):
    """A Dask scheduler and two worker processes started on their own, reached by address."""
    import json
    import subprocess
    import sys
    import time

    pytest.importorskip("distributed")
    dask = Path(sys.executable).parent / "dask"
    file = tmp_path / "scheduler.json"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": tmp_path}
    processes = [
        subprocess.Popen([dask, "scheduler", "--port", "0", "--no-dashboard", "--scheduler-file", file], **quiet)
    ]
    try:
        deadline = time.monotonic() + 60
        while not file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(file.read_text())["address"]
        worker = [dask, "worker", address, "--nworkers", "2", "--nthreads", "1", "--no-dashboard"]
        processes.append(subprocess.Popen(worker, **quiet))
        yield address
    finally:
        for p in reversed(processes):
            p.terminate()
        for p in processes:
            p.wait(timeout=30)


def test_a_fleet_on_a_cluster_filters_every_log_and_names_the_one_that_fails(tmp_path, carrier, cluster):
    distributed = pytest.importorskip("distributed")
    model, q, r, p0 = carrier
    paths = _logs(tmp_path, model, 15, 300, q, r)
    paths.insert(7, _outlier_log(tmp_path, model, q, r, row=200))
    kwargs = {"model": model, "estimator": "smf", "P0": p0, "Q": q, "R": r, "chunk_rows": 64}
    # An earlier run's output of the bad log must not stay looking current.
    stale = tmp_path / "dask" / "vehicle-bad.parquet"
    stale.parent.mkdir()
    stale.write_bytes(b"an earlier run's output")
    serial = fleet.filter_logs(paths, tmp_path / "serial", **kwargs)
    with distributed.Client(cluster, timeout=60) as client:
        client.wait_for_workers(2, timeout=60)
        parallel = fleet.filter_logs(paths, tmp_path / "dask", client=client, **kwargs)
    for summaries in (serial, parallel):
        assert [s["status"] for s in summaries] == ["ok"] * 7 + ["error"] + ["ok"] * 8
        failed = summaries[7]
        assert failed["log"] == str(paths[7]) and failed["row"] == 200 and failed["output"] is None
        assert failed["error"].startswith(f"InconsistentDataError: {paths[7]}: row 200: "), failed["error"]
        assert all(s["steps"] == 300 for i, s in enumerate(summaries) if i != 7)
    for folder in ("serial", "dask"):
        assert sorted(p.name for p in (tmp_path / folder).iterdir()) == sorted(p.name for p in paths if p != paths[7])
    for s, d in zip(serial, parallel):
        if s["output"] is not None:
            assert Path(s["output"]).read_bytes() == Path(d["output"]).read_bytes()


def test_a_log_that_fails_raises_with_its_path_and_row_and_leaves_nothing(tmp_path, carrier):
    model, q, r, p0 = carrier
    bad = _outlier_log(tmp_path, model, q, r, row=200)
    out = tmp_path / "out.parquet"
    out.write_bytes(b"an earlier run's output")
    with pytest.raises(pe.InconsistentDataError) as info:
        fleet.filter_log(bad, out, model=model, estimator="smf", P0=p0, Q=q, R=r, chunk_rows=64)
    assert info.value.row == 200 and info.value.log == str(bad)
    assert str(info.value).startswith(f"{bad}: row 200: ")
    assert not out.exists() and list(tmp_path.glob(".out.parquet.*")) == []


def test_corrupt_and_empty_logs(tmp_path, carrier):
    model, q, r, p0 = carrier
    kwargs = {"model": model, "estimator": "smf", "P0": p0, "Q": q, "R": r}
    corrupt = tmp_path / "corrupt.parquet"
    corrupt.write_text("k,u1\n0,1\n")
    (summary,) = fleet.filter_logs([corrupt], tmp_path / "out", **kwargs)
    assert summary["status"] == "error" and str(corrupt) in summary["error"], summary
    assert summary["row"] is None
    # A log without rows: an output without rows, with the columns.
    empty = tmp_path / "empty.parquet"
    fleet.write_log(empty, np.zeros(0, dtype=np.int64), np.zeros((0, 8)), np.zeros((0, 4)))
    (summary,) = fleet.filter_logs([empty], tmp_path / "out", **kwargs)
    assert summary["status"] == "ok" and summary["steps"] == 0
    table = pq.read_table(summary["output"])
    assert table.num_rows == 0 and table.column_names[:2] == ["k", "xhat1"]


def test_a_run_result_pickles(carrier):
    import pickle

    model, q, r, p0 = carrier
    rng = np.random.default_rng(4)
    log = pe.SetMembershipFilter(model, P0=p0, Q=q, R=r).run(rng.uniform(-0.05, 0.05, (20, 8)), np.zeros((20, 4)))
    back = pickle.loads(pickle.dumps(log))
    assert len(back) == 20 and back.kind == log.kind and back.status == log.status
    for name in ("center", "lower", "upper", "trace", "clean"):
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name))
    assert back.details.keys() == log.details.keys()
    np.testing.assert_array_equal(back.details["tau1"], log.details["tau1"])


def test_a_task_streams_its_log_in_bounded_memory(tmp_path, carrier):
    # The peak memory of filtering a log does not grow with its length (pieces of the default
    # 8192 rows, row groups of 65536): a log 8 times longer costs less than 48 MB more at the
    # peak (measured: within the allocators' noise of 20 MB), where loading it whole would cost
    # more than 250 MB more.
    import subprocess
    import sys

    if not Path("/proc/self/status").exists():
        pytest.skip("needs /proc/self/status (Linux) to read a process's peak memory")
    script = """
import sys, port_estimation as pe
from port_estimation import fleet
model = pe.Model.carrier(speed=6.0, load=1)
s = fleet.filter_log(sys.argv[1], sys.argv[2], model=model, estimator="kf", P0=1e-2, Q=1e-8, R=1e-2)
# This process's own peak (ru_maxrss would count the parent's pages at the fork).
peak = next(line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM:"))
print(s["steps"], peak)
"""
    peaks = []
    rng = np.random.default_rng(0)
    for rows in (100_000, 800_000):
        log, out = tmp_path / f"log{rows}.parquet", tmp_path / f"out{rows}.parquet"
        fleet.write_log(log, np.arange(rows), rng.uniform(-0.05, 0.05, (rows, 8)), rng.normal(0.0, 1e-4, (rows, 4)))
        done = subprocess.run([sys.executable, "-c", script, log, out], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        steps, peak = done.stdout.split()
        assert int(steps) == rows
        peaks.append(int(peak) / 1024)  # MiB (VmHWM is in kB)
    assert peaks[1] - peaks[0] < 48, peaks


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


BAGS = Path(__file__).resolve().parents[2] / "ros-bag" / "tests" / "fixtures"


def test_ros2_bags_are_logs_too(tmp_path):
    # The JSON fixture bag: input v, outputs x, valid, wz (a pose at 10 Hz with a dropout, a speed
    # and gyro at 25 Hz), read at 50 ms; its estimates equal a run on read_bag's arrays.
    model = pe.Model(np.eye(2), np.array([[0.05], [0.0]]), np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 1.0]]))
    kw = dict(x0=np.zeros(2), P0=np.eye(2) * 100.0, Q=np.eye(2), R=np.eye(3) * 1e6)
    mapping = dict(
        inputs={"v": "/speed_json:v"},
        outputs={"x": "/pose_json:x", "valid": "/pose_json:valid", "wz": "/speed_json:gyro[2]"},
        ts=0.05,
    )
    bag = str(BAGS / "json.mcap")
    [summary] = fleet.filter_logs([bag], tmp_path / "out", model=model, estimator="kf", bag=mapping, chunk_rows=7, **kw)
    assert summary["status"] == "ok" and summary["output"].endswith("json.parquet"), summary
    import pyarrow.parquet as pq

    table = pq.read_table(summary["output"])
    log = pe.read_bag(bag, **mapping)
    want = pe.Estimator("kf", model, **kw).run(log.u, log.y, measured=log.measured)
    assert summary["steps"] == len(log) and not np.all(log.measured)
    np.testing.assert_array_equal(table.column("k").to_numpy(), log.k + 1)
    for i in range(2):
        np.testing.assert_array_equal(table.column(f"xhat{i + 1}").to_numpy(), want.center[:, i])
    # Without the mapping, or with one that does not fit the estimator: the log's error, named.
    [no_map] = fleet.filter_logs([bag], tmp_path / "x", model=model, estimator="kf", **kw)
    assert no_map["status"] == "error" and "bag=dict" in no_map["error"] and bag in no_map["error"]
    short = dict(mapping, outputs={"x": "/pose_json:x"})
    [wrong] = fleet.filter_logs([bag], tmp_path / "y", model=model, estimator="kf", bag=short, **kw)
    assert wrong["status"] == "error" and "1 outputs" in wrong["error"], wrong


def test_a_model_files_log_table_maps_the_bags(tmp_path):
    # The model file's [log] table is the mapping: as model= (its own table) or as bag=.
    from test_bags import ROS2_INPUTS, ROS2_MODEL, ROS2_OUTPUTS

    import pyarrow.parquet as pq

    bag = str(BAGS / "ros2_zstd.mcap")
    mf = pe.parse_model(ROS2_MODEL, "ros2.toml")
    [by_file] = fleet.filter_logs([bag], tmp_path / "a", model=mf, estimator="ekf", chunk_rows=64)
    mapping = dict(inputs=ROS2_INPUTS, outputs=ROS2_OUTPUTS, ts=0.01)
    [by_hand] = fleet.filter_logs([bag], tmp_path / "b", model=mf, estimator="ekf", bag=mapping, chunk_rows=64)
    plain = pe.parse_model(ROS2_MODEL.split("[log]")[0], "plain.toml")
    [as_bag] = fleet.filter_logs([bag], tmp_path / "c", model=plain, estimator="ekf", bag=mf, chunk_rows=64)
    assert by_file["status"] == by_hand["status"] == as_bag["status"] == "ok", (by_file, by_hand, as_bag)
    want = pq.read_table(by_hand["output"])
    assert pq.read_table(by_file["output"]).equals(want) and pq.read_table(as_bag["output"]).equals(want)
    log = mf.read_bag(bag)
    run = mf.estimator("ekf").run(log.u, log.y, measured=log.measured)
    np.testing.assert_array_equal(want.column("xhat2").to_numpy(), run.center[:, 1])
    # A model file without a table: the bag's error names both ways of mapping it; bag= must have a table.
    [none] = fleet.filter_logs([bag], tmp_path / "d", model=plain, estimator="ekf")
    assert none["status"] == "error" and "[log] table" in none["error"] and "bag=dict" in none["error"], none
    with pytest.raises(ValueError, match=r"plain\.toml: the model file has no \[log\] table"):
        fleet.filter_logs([bag], tmp_path / "e", model=mf, estimator="ekf", bag=plain)
    with pytest.raises(TypeError, match="bag must be"):
        fleet.filter_logs([bag], tmp_path / "e", model=mf, estimator="ekf", bag=3)
