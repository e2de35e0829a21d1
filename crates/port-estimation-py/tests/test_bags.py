"""ROS 2 bags (MCAP) as logs: ``read_bag`` gives the rows of the committed fixture bags
(``crates/ros-bag/tests/fixtures``, written by Python's ``mcap-ros2-support``) equal to their
reference CSVs bit for bit, masks included; a filter run on them equals the run on the CSV's
arrays; every bad argument, mapping and file raises the right exception, saying where.
"""

from __future__ import annotations

import csv
import pickle
import struct
from pathlib import Path

import numpy as np
import pytest

import port_estimation as pe

FIXTURES = Path(__file__).resolve().parents[2] / "ros-bag" / "tests" / "fixtures"
T0 = 1_700_000_000_123_456_789  # make_bags.py's first stamp (ns)

ROS2_INPUTS = {"a": "/imu:linear_acceleration.x", "delta": ("/cmd_vel", "twist.angular.z")}
ROS2_OUTPUTS = {
    "gnss_lat": "/gnss/fix:latitude",
    "gnss_status": "/gnss/fix:status.status",
    "gyro": "/imu:angular_velocity.z",
    "wheel_speed": "/odom:twist.twist.linear.x",
    "gyro_var": "/imu:angular_velocity_covariance[8]",
}
JSON_INPUTS = {"v": "/speed_json:v"}
JSON_OUTPUTS = {"x": "/pose_json:x", "valid": "/pose_json:valid", "wz": "/speed_json:gyro[2]"}


def bag(name: str) -> str:
    return str(FIXTURES / name)


def read_csv(name: str, p: int):
    """The reference rows: header, k, t_ns, t, u (T, p), y (T, m; NaN where empty), measured."""
    with open(FIXTURES / name, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    m = len(header) - 3 - p
    k = np.array([int(r[0]) for r in body], dtype=np.int64)
    t_ns = np.array([int(r[1]) for r in body], dtype=np.int64)
    t = np.array([float(r[2]) for r in body])
    u = np.array([[float(c) for c in r[3 : 3 + p]] for r in body]).reshape(len(body), p)
    measured = np.array([[c != "" for c in r[3 + p :]] for r in body], dtype=bool).reshape(len(body), m)
    y = np.array([[float(c) if c else np.nan for c in r[3 + p :]] for r in body]).reshape(len(body), m)
    return header, k, t_ns, t, u, y, measured


def bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def assert_log_equals_csv(log: pe.BagLog, name: str) -> None:
    header, k, t_ns, t, u, y, measured = read_csv(name, len(log.inputs))
    assert header[3:] == log.inputs + log.outputs, name
    assert len(log) == len(k) > 0, name
    np.testing.assert_array_equal(log.k, k)
    np.testing.assert_array_equal(log.t_ns, t_ns)
    np.testing.assert_array_equal(bits(log.t), bits(t))
    np.testing.assert_array_equal(bits(log.u), bits(u))
    np.testing.assert_array_equal(log.measured, measured)
    np.testing.assert_array_equal(bits(log.y[measured]), bits(y[measured]))
    assert np.isnan(log.y[~measured]).all(), name
    assert log.u.dtype == log.y.dtype == np.float64 and log.measured.dtype == np.bool_ and log.k.dtype == np.int64


@pytest.mark.parametrize("name", ["ros2_zstd", "ros2_lz4", "ros2_none"])
def test_fixed_step_with_log_times_equals_the_csv(name):
    log = pe.read_bag(bag(f"{name}.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    assert_log_equals_csv(log, f"{name}.fixed_logtime.csv")
    assert log.header_stamped == {"/imu": False, "/cmd_vel": False, "/gnss/fix": False, "/odom": False}
    assert log.path == bag(f"{name}.mcap")


def test_header_stamps_fixed_step_and_per_message():
    log = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.05, stamps="header")
    assert_log_equals_csv(log, "ros2_zstd.fixed_header.csv")
    assert all(log.header_stamped.values())
    log = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, driving="/imu", stamps="header")
    assert_log_equals_csv(log, "ros2_zstd.imu_header.csv")
    log = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, driving="/imu")
    assert_log_equals_csv(log, "ros2_zstd.imu_logtime.csv")


def test_a_given_start_in_nanoseconds_or_seconds():
    log = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.02, start_ns=T0 + 500_000_000)
    assert_log_equals_csv(log, "ros2_zstd.fixed_start.csv")
    start = (T0 + 500_000_000) / 1e9  # not exact in float64: the nearest nanosecond of it
    by_seconds = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.02, start=start)
    assert by_seconds.t_ns[0] == round(start * 1e9)


def test_json_messages_with_and_without_a_schema():
    log = pe.read_bag(bag("json.mcap"), JSON_INPUTS, JSON_OUTPUTS, ts=0.05)
    assert_log_equals_csv(log, "json.fixed_logtime.csv")
    log = pe.read_bag(bag("json.mcap"), JSON_INPUTS, JSON_OUTPUTS, ts=0.05, stamps="header")
    assert_log_equals_csv(log, "json.fixed_header.csv")
    assert log.header_stamped == {"/speed_json": False, "/pose_json": True}


def test_the_arrays_are_what_run_takes_and_give_the_csv_runs_numbers():
    """A partial Kalman run (gyro at 100 Hz, wheel speed at 20 Hz) and a set-membership run (the
    gyro's topic only: all or nothing) equal the runs on the CSV's arrays bit for bit."""
    outputs = {"gyro": ROS2_OUTPUTS["gyro"], "wheel_speed": ROS2_OUTPUTS["wheel_speed"]}
    log = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, outputs, ts=0.01)
    _, _, _, _, u, y, measured = read_csv("ros2_zstd.fixed_logtime.csv", 2)
    cols = [2, 3]  # gyro, wheel_speed among the CSV's outputs
    model = pe.Model(A=[[0.95, 0.0], [0.0, 0.99]], B=[[0.0, 0.05], [0.01, 0.0]], C=[[1.0, 0.0], [0.0, 1.0]])

    def kf():
        f = pe.KalmanFilter(model, P0=1.0, Q=[0.1, 0.01], R=[0.1, 0.01])
        f.set_data_checks("off")  # the synthetic data is no process of this model
        return f

    runs = [kf().run(log.u, log.y, measured=log.measured), kf().run(u, y[:, cols], measured=measured[:, cols])]
    assert not runs[0].measured.all() and runs[0].measured.any()
    np.testing.assert_array_equal(bits(runs[0].center), bits(runs[1].center))
    np.testing.assert_array_equal(bits(runs[0].upper), bits(runs[1].upper))

    log = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, {"gyro": ROS2_OUTPUTS["gyro"]}, ts=0.01)
    one = pe.Model(A=[[0.9]], B=[[0.0, 0.1]], C=[[1.0]])

    def smf():
        return pe.SetMembershipFilter(one, P0=1.0, Q=0.05, R=0.5, inconsistency="flag")

    a = smf().run(log.u, log.y, measured=log.measured)
    b = smf().run(u, y[:, [2]], measured=measured[:, [2]])
    assert not log.measured.all()
    np.testing.assert_array_equal(bits(a.center), bits(b.center))
    np.testing.assert_array_equal(bits(a.lower), bits(b.lower))
    assert a.status == b.status


def test_the_log_is_read_only_and_pickles():
    log = pe.read_bag(bag("ros2_lz4.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    with pytest.raises(ValueError):
        log.u[0, 0] = 1.0
    back = pickle.loads(pickle.dumps(log))
    assert (back.inputs, back.outputs, back.path, back.header_stamped) == (
        log.inputs,
        log.outputs,
        log.path,
        log.header_stamped,
    )
    for name in ["k", "t_ns", "t", "u", "y", "measured"]:
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name))
    assert "BagLog(" in repr(log) and f"{len(log)} rows" in repr(log)


def test_outputs_only_give_an_empty_input_table():
    log = pe.read_bag(bag("json.mcap"), None, {"x": "/pose_json:x"}, ts=0.05)
    assert log.u.shape == (len(log), 0) and log.inputs == []
    kf = pe.KalmanFilter(pe.Model(A=[[1.0]], B=np.zeros((1, 0)), C=[[1.0]]), P0=100.0, Q=100.0, R=1.0)
    run = kf.run(log.u, log.y, measured=log.measured)
    assert len(run) == len(log)


def test_inspect_lists_topics_and_prints_the_table():
    info = pe.inspect_bag(bag("ros2_zstd.mcap"))
    assert [t["topic"] for t in info.topics] == ["/cmd_vel", "/gnss/fix", "/imu", "/odom"] and len(info) == 4
    imu = info.topics[2]
    assert imu["type"] == "sensor_msgs/msg/Imu"
    assert (imu["message_encoding"], imu["schema_encoding"], imu["count"]) == ("cdr", "ros2msg", 300)
    assert imu["rate_hz"] == pytest.approx(100.0, rel=1e-3)
    assert imu["first_ns"] < imu["last_ns"] and imu["first"] == imu["first_ns"] / 1e9
    assert "linear_acceleration.x" in imu["fields"] and "angular_velocity_covariance[0..=8]" in imu["fields"]
    assert imu["fields_error"] is None and info.error is None
    table = str(info).splitlines()
    assert table[0].split() == ["topic", "type", "encoding", "messages", "rate", "(Hz)", "first", "(s)", "last", "(s)"]
    for i, t in enumerate(info.topics):
        cells = table[1 + 2 * i].split()
        assert cells[:4] == [t["topic"], t["type"], "cdr/ros2msg", str(t["count"])]
        assert cells[4] == f"{t['rate_hz']:.2f}"
        assert cells[5] == f"{t['first_ns'] // 10**9}.{t['first_ns'] % 10**9:09d}"
        assert table[2 + 2 * i] == "    fields: " + ", ".join(t["fields"])

    info = pe.inspect_bag(bag("json.mcap"))
    speed = next(t for t in info.topics if t["topic"] == "/speed_json")
    assert (speed["type"], speed["message_encoding"], speed["schema_encoding"]) == ("", "json", "")
    assert "json/-" in str(info)


# --- errors -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kw, words",
    [
        ({}, "give one of ts="),
        ({"ts": 0.01, "driving": "/imu"}, "not both"),
        ({"ts": 0.0}, "positive"),
        ({"ts": float("nan")}, "positive"),
        ({"ts": 0.01, "stamps": "wall"}, "stamps"),
        ({"ts": 0.01, "reorder_window": -1.0}, "reorder_window"),
        ({"ts": 0.01, "start": 1.0, "start_ns": 1}, "not both"),
        ({"driving": "/imu", "start_ns": 1}, "fixed step"),
    ],
)
def test_bad_arguments_are_value_errors(kw, words):
    with pytest.raises(ValueError, match=words) as e:
        pe.read_bag(bag("ros2_none.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, **kw)
    assert type(e.value) is ValueError


@pytest.mark.parametrize(
    "inputs, words",
    [
        ({"a": "/imu"}, r'inputs\["a"\]: "/imu" is not "topic:field"'),
        ({"a": "/imu:x:y"}, "is not"),
        ({"a": ":x"}, "must not be empty"),
        ({"a": ("/imu",)}, r'inputs\["a"\]: got tuple'),
        ({"a": 3}, "got int"),
        ({1: "/imu:linear_acceleration.x"}, "keys must be strings"),
        (["/imu:linear_acceleration.x"], "must be a mapping"),
    ],
)
def test_bad_mappings_are_value_errors(inputs, words):
    with pytest.raises(ValueError, match=words):
        pe.read_bag(bag("ros2_none.mcap"), inputs, {}, ts=0.01)


def test_an_unknown_topic_lists_the_topics():
    path = bag("ros2_none.mcap")
    with pytest.raises(ValueError) as e:
        pe.read_bag(path, {"a": "/imu:linear_acceleration.x"}, {"gnss_x": "/gnss/odom:latitude"}, ts=0.01)
    assert type(e.value) is ValueError
    assert str(e.value) == (
        f"{path}: mapping `gnss_x`: no topic `/gnss/odom` in the bag; its topics: /cmd_vel, /gnss/fix, /imu, /odom"
    )
    with pytest.raises(ValueError, match="mapping `time base`: no topic `/clock`"):
        pe.read_bag(path, ROS2_INPUTS, ROS2_OUTPUTS, driving="/clock")


def test_an_unknown_field_lists_the_numeric_fields_and_keys_are_unique():
    path = bag("ros2_none.mcap")
    with pytest.raises(ValueError) as e:
        pe.read_bag(path, {"a": "/imu:linear_acceleration.w"}, {}, ts=0.01)
    text = str(e.value)
    assert text.startswith(f"{path}: mapping `a`: topic `/imu` has no numeric field `linear_acceleration.w`")
    assert "its numeric fields: header.stamp.sec" in text and "linear_acceleration.z" in text
    with pytest.raises(ValueError, match="bad field path"):
        pe.read_bag(path, {"a": "/imu:linear_acceleration..x"}, {}, ts=0.01)
    with pytest.raises(ValueError, match="string, not a number|is a string"):
        pe.read_bag(path, {"a": "/imu:header.frame_id"}, {}, ts=0.01)
    with pytest.raises(ValueError, match="the key `a` is mapped twice"):
        pe.read_bag(path, {"a": "/imu:linear_acceleration.x"}, {"a": "/imu:angular_velocity.z"}, ts=0.01)


def test_files_that_cannot_be_opened_or_are_not_mcap(tmp_path):
    missing = tmp_path / "missing.mcap"
    with pytest.raises(FileNotFoundError) as e:
        pe.read_bag(missing, ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    assert e.value.filename == str(missing)
    with pytest.raises(FileNotFoundError):
        pe.inspect_bag(missing)
    text = tmp_path / "x.mcap"
    text.write_bytes(b"hello, world")
    for call in [lambda: pe.read_bag(text, ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01), lambda: pe.inspect_bag(text)]:
        with pytest.raises(pe.BagError, match="not an MCAP file") as e:
            call()
        assert e.value.path == str(text) and e.value.rows_read == 0 and e.value.offset is None


def chunks(data: bytes) -> list[tuple[int, int]]:
    """The chunk records of an MCAP file: (byte offset, content length)."""
    out, pos = [], 8
    while pos + 9 <= len(data) - 8:
        op, length = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
        if op == 0x06:
            out.append((pos, length))
        if op == 0x02:  # data end
            break
        pos += 9 + length
    return out


@pytest.mark.parametrize("name", ["ros2_none", "ros2_lz4", "ros2_zstd"])
def test_a_truncated_bag_names_the_chunk_and_the_rows_read_before_it(tmp_path, name):
    data = (FIXTURES / f"{name}.mcap").read_bytes()
    full = pe.read_bag(bag(f"{name}.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    found = chunks(data)
    assert len(found) >= 2
    at, length = found[-1]
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: at + 9 + length // 2])
    with pytest.raises(pe.BagError) as e:
        pe.read_bag(cut, ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    err = e.value
    assert isinstance(err, ValueError)
    assert err.path == str(cut) and err.offset == at and err.topic is None and err.key is None
    assert len(full) / 3 < err.rows_read < len(full)
    assert str(err).startswith(f"{cut}: chunk at byte {at}") and "truncated" in str(err)
    assert str(err).endswith(f"({err.rows_read} rows read before it)")
    info = pe.inspect_bag(cut)
    assert info.error is not None and f"chunk at byte {at}" in info.error
    assert str(info).splitlines()[-1] == f"stopped early: {info.error}"


def test_a_damaged_chunk_is_named_by_its_offset(tmp_path):
    data = bytearray((FIXTURES / "ros2_zstd.mcap").read_bytes())
    at, length = chunks(bytes(data))[1]
    data[at + 9 + length - 100] ^= 0x5A  # inside the compressed records
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    with pytest.raises(pe.BagError, match=f"chunk at byte {at}") as e:
        pe.read_bag(bad, ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    assert e.value.offset == at and e.value.rows_read > 0


# The ROS 2 fixtures' model file: its [log] table is the mapping ROS2_INPUTS, ROS2_OUTPUTS at 10 ms.
ROS2_MODEL = (FIXTURES / "ros2_model.toml").read_text()


def test_a_model_files_log_table_reads_the_bag():
    """``ModelFile.read_bag`` reads through the file's ``[log]`` table (port-est's parser): the rows
    of the same mapping given to ``read_bag``, in the model's order whatever the table's order."""
    mf = pe.parse_model(ROS2_MODEL, "ros2.toml")
    assert mf.has_log and "[log]" in repr(mf)
    log = mf.read_bag(bag("ros2_zstd.mcap"))
    assert_log_equals_csv(log, "ros2_zstd.fixed_logtime.csv")
    assert (log.inputs, log.outputs) == (list(ROS2_INPUTS), list(ROS2_OUTPUTS))
    at_02 = pe.parse_model(ROS2_MODEL.replace("ts = 0.01", "ts = 0.02"), "ros2.toml")
    assert_log_equals_csv(at_02.read_bag(bag("ros2_zstd.mcap"), start_ns=T0 + 500_000_000), "ros2_zstd.fixed_start.csv")
    per_message = ROS2_MODEL.replace("ts = 0.01", 'driving = "/imu"\nstamps = "header"')
    assert_log_equals_csv(pe.parse_model(per_message).read_bag(bag("ros2_zstd.mcap")), "ros2_zstd.imu_header.csv")
    # The file's estimator runs on it as on the mapping's arrays.
    by_hand = pe.read_bag(bag("ros2_zstd.mcap"), ROS2_INPUTS, ROS2_OUTPUTS, ts=0.01)
    a = mf.estimator("ekf").run(log.u, log.y, measured=log.measured)
    b = mf.estimator("ekf").run(by_hand.u, by_hand.y, measured=by_hand.measured)
    np.testing.assert_array_equal(bits(a.center), bits(b.center))
    # A file without a [log] table, a start with one step per message, a bad table: ValueError naming the file.
    plain = pe.parse_model(ROS2_MODEL.split("[log]")[0], "plain.toml")
    assert not plain.has_log
    with pytest.raises(ValueError, match=r"plain\.toml: no \[log\] table"):
        plain.read_bag(bag("ros2_zstd.mcap"))
    with pytest.raises(ValueError, match="apply to a fixed step"):
        pe.parse_model(per_message).read_bag(bag("ros2_zstd.mcap"), start=1.0)
    with pytest.raises(ValueError, match=r"bad\.toml:\d+:\d+: .*no topic for `gyro_var`"):
        pe.parse_model(ROS2_MODEL.replace('gyro_var = { topic = "/imu", field = "angular_velocity_covariance[8]" }', ""), "bad.toml")
    with pytest.raises(ValueError, match="/nope"):
        pe.parse_model(ROS2_MODEL.replace('"/odom"', '"/nope"')).read_bag(bag("ros2_zstd.mcap"))
