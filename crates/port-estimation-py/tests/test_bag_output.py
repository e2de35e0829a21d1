"""Bags written by ``port-est filter --output est.mcap``, read back by an independent reader (Python's
``mcap`` and ``mcap-ros2-support``, pinned in requirements-test.txt): the estimates hold exactly the
numbers of the CSV output of the same run (bit for bit, the status included), stamped at the end of
each step's window (a fixed step, or the next driving message); ``--copy-topics`` copies the input's
messages unchanged (bytes, sequence, log and publish time), still decodable as ROS 2 messages.

The ``port-est`` binary is ``$PORT_EST``, or the newest of ``target/{debug,release}/port-est`` (the
Rust half of ``cargo xtask test`` builds the debug one); without one these tests are skipped.
"""

from __future__ import annotations

import csv
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import NonSeekingReader, make_reader
from mcap_ros2.decoder import DecoderFactory

import port_estimation as pe
from test_bags import FIXTURES, ROS2_INPUTS, ROS2_MODEL, ROS2_OUTPUTS, read_csv

ROOT = Path(__file__).resolve().parents[3]


def port_est() -> str:
    if os.environ.get("PORT_EST"):
        return os.environ["PORT_EST"]
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    found = [p for p in (target / "debug" / "port-est", target / "release" / "port-est") if p.is_file()]
    if not found:
        pytest.skip("no port-est binary (set PORT_EST or build it: cargo build -p port-est)")
    return str(max(found, key=lambda p: p.stat().st_mtime))


def run(tmp: Path, model: str, bag: Path, output: str, *extra: str) -> Path:
    (tmp / "m.toml").write_text(model)
    out = tmp / output
    args = [port_est(), "filter", "-m", str(tmp / "m.toml"), "-i", str(bag), "-o", str(out), *extra]
    done = subprocess.run(args, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return out


def csv_rows(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def file_order(path: Path):
    """(topic, schema name, sequence, log time, publish time, bytes) of every message, in file order."""
    with open(path, "rb") as f:
        return [
            (c.topic, s.name if s else "", m.sequence, m.log_time, m.publish_time, bytes(m.data))
            for s, c, m in NonSeekingReader(f).iter_messages(log_time_order=False)
        ]


def estimates(path: Path) -> list[tuple[int, dict]]:
    return [(m[3], json.loads(m[5])) for m in file_order(path) if m[0] == "/estimate"]


def assert_same_numbers(csv_path: Path, msgs: list[tuple[int, dict]], states: list[str], spread: list[str]) -> None:
    """Each message holds its CSV row's numbers bit for bit: ``xhat1..n`` as ``x``, then the spread
    columns (``sd1..n`` as ``std``, or ``lo1..n``, ``hi1..n`` as ``lower``, ``upper``), and the status."""
    header, rows = csv_rows(csv_path)
    assert len(msgs) == len(rows) > 10
    n = len(states)
    for i, ((_, m), row) in enumerate(zip(msgs, rows)):
        assert m["k"] == i and int(row[0]) == i + 1
        for g, group in enumerate(["x", *spread]):
            got = np.array([m[group][s] for s in states], dtype=np.float64)
            want = np.array([float(c) for c in row[1 + g * n : 1 + (g + 1) * n]])
            assert header[1 + g * n].startswith({"x": "xhat", "std": "sd", "lower": "lo", "upper": "hi"}[group])
            np.testing.assert_array_equal(got.view(np.uint64), want.view(np.uint64), f"row {i}, {group}")
        assert m["status"] == row[-1], f"row {i}"


STATES = ["lat", "v", "yaw_rate"]


@pytest.mark.parametrize(("estimator", "spread"), [("ekf", ["std"]), ("smf", ["lower", "upper"])])
def test_the_output_bag_holds_the_csv_numbers_at_the_window_ends(tmp_path, estimator, spread):
    bag = FIXTURES / "ros2_zstd.mcap"
    # The model's equations are linear (smf runs); the synthetic data are no process of it: flagged.
    flags = ("-e", estimator, "--on-inconsistent", "flag")
    csv_out = run(tmp_path, ROS2_MODEL, bag, "out.csv", *flags)
    out = run(tmp_path, ROS2_MODEL, bag, "out.mcap", *flags)
    msgs = estimates(out)
    assert_same_numbers(csv_out, msgs, STATES, spread)
    # Step k's estimate at the end of its window, t_k + ts (t_k from the fixture's reference rows).
    t_ns = read_csv("ros2_zstd.fixed_logtime.csv", 2)[2]
    assert len(t_ns) == len(msgs)
    for i, (t, m) in enumerate(msgs):
        assert t == t_ns[i] + 10_000_000 and m["t"] == t / 1e9
    assert any("+measured:" in m["status"] for _, m in msgs), "the GNSS dropout makes partial steps"


def test_per_driving_message_each_estimate_is_stamped_at_the_next_one(tmp_path):
    bag = FIXTURES / "ros2_zstd.mcap"
    model = ROS2_MODEL.replace("ts = 0.01", 'driving = "/imu"')
    csv_out = run(tmp_path, model, bag, "out.csv", "-e", "ekf")
    msgs = estimates(run(tmp_path, model, bag, "out.mcap", "-e", "ekf"))
    assert_same_numbers(csv_out, msgs, STATES, ["std"])
    # Row k is at an /imu message (the rows read_bag gives); its window ends at the next one.
    imu = [m[3] for m in file_order(bag) if m[0] == "/imu"]
    rows = pe.read_bag(bag, ROS2_INPUTS, ROS2_OUTPUTS, driving="/imu")
    assert len(msgs) == len(rows) and len(imu) > len(rows)
    assert [t for t, _ in msgs] == [imu[imu.index(t) + 1] for t in rows.t_ns]


def test_copied_topics_are_the_inputs_messages_unchanged(tmp_path):
    bag = FIXTURES / "ros2_zstd.mcap"
    out = run(tmp_path, ROS2_MODEL, bag, "out.mcap", "-e", "ekf", "--copy-topics")
    source, got = file_order(bag), file_order(out)
    assert [m for m in got if m[0] != "/estimate"] == source
    assert sum(m[0] == "/estimate" for m in got) == len(estimates(run(tmp_path, ROS2_MODEL, bag, "e.mcap", "-e", "ekf")))
    # Interleaved by log time (the input is in log-time order): the whole file is.
    times = [m[3] for m in got]
    assert times == sorted(times)
    # Decodable as ROS 2 messages from the copied schemas, the same values as the input's.
    def gyro(path: Path) -> list[float]:
        with open(path, "rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            return [msg.angular_velocity.z for _, _, _, msg in reader.iter_decoded_messages(topics=["/imu"])]

    assert gyro(out) == gyro(bag) and len(gyro(out)) > 100
    # Named topics only.
    out = run(tmp_path, ROS2_MODEL, bag, "some.mcap", "-e", "ekf", "--copy-topics", "/gnss/fix,/odom")
    assert [m for m in file_order(out) if m[0] != "/estimate"] == [m for m in source if m[0] in ("/gnss/fix", "/odom")]
