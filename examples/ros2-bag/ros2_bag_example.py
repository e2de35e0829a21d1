#!/usr/bin/env python3
"""A ROS 2 bag in, estimates out as a bag, and a figure drawn from the output bag.

The yard tractor of ``examples/multi-rate`` (a kinematic bicycle at 100 Hz: GNSS at 10 Hz with a 5 s dropout,
compass at 10 Hz, gyro and wheel speed at every step) written as the ROS 2 bag its vehicle would record: standard
messages (``sensor_msgs/Imu``, ``nav_msgs/Odometry``, ``geometry_msgs/TwistStamped``, ``std_msgs/Float64``) in CDR,
by Python's ``mcap-ros2-support``. Then::

    port-est filter -m model.toml -i run.mcap -o est.mcap -e czf-nl --copy-topics

(the model file's ``[log]`` table, ``LOG`` below, maps the topics) writes the certified estimates on ``/estimate``
beside the copied sensor topics; the script checks that they hold exactly the numbers of the same run on
``examples/multi-rate/data.csv``, and draws the estimate from ``est.mcap`` alone (the track with the GNSS fixes it
holds, and the guaranteed interval of the position through the dropout) into ``estimate.svg`` beside this script.

    python examples/ros2-bag/ros2_bag_example.py [--out DIR] [--port-est PATH]

Needs ``mcap``, ``mcap-ros2-support``, ``numpy``, ``matplotlib`` (the Python test requirements) and ``port-est``
(``--port-est``, ``$PORT_EST``, ``target/release/port-est``, or ``cargo run --release -p port-est``).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DATA = HERE.parent / "multi-rate" / "data.csv"
MODEL = HERE.parent / "multi-rate" / "model.toml"
T0 = 1_700_000_000_000_000_000  # ns: the first message
TS = 10_000_000  # ns: the model's step, 0.01 s
LATENCY = 1_000_000  # ns: each sensor message is stamped 1 ms before its step ends

# The mapping: each input and output of the model from a topic's field (`port-est inspect run.mcap` lists them).
LOG = """
[log]
ts = 0.01                 # one step every 10 ms from the first message

[log.fields]
a = { topic = "/imu", field = "linear_acceleration.x" }
delta = { topic = "/steering", field = "data" }
gnss_x = { topic = "/gnss/odom", field = "pose.pose.position.x" }
gnss_y = { topic = "/gnss/odom", field = "pose.pose.position.y" }
gyro = { topic = "/imu", field = "angular_velocity.z" }
wheel_speed = { topic = "/wheel/twist", field = "twist.linear.x" }
compass = { topic = "/compass", field = "data" }
"""

# Standard definitions (comments left out; the constants a type declares are not needed to decode it).
DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "std_msgs/Float64": "float64 data\n",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/PoseWithCovariance": "Pose pose\nfloat64[36] covariance\n",
    "geometry_msgs/Twist": "Vector3 linear\nVector3 angular\n",
    "geometry_msgs/TwistWithCovariance": "Twist twist\nfloat64[36] covariance\n",
    "geometry_msgs/TwistStamped": "std_msgs/Header header\nTwist twist\n",
    "nav_msgs/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
        "geometry_msgs/TwistWithCovariance twist\n"
    ),
    "sensor_msgs/Imu": (
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
        "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
        "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n"
    ),
}
USES = {
    "std_msgs/Float64": [],
    "geometry_msgs/TwistStamped": ["std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Twist",
                                   "geometry_msgs/Vector3"],
    "nav_msgs/Odometry": ["std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/PoseWithCovariance",
                          "geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion",
                          "geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist", "geometry_msgs/Vector3"],
    "sensor_msgs/Imu": ["std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Quaternion",
                        "geometry_msgs/Vector3"],
}


def schema_text(name: str) -> str:
    parts = [DEFS[name]] + ["=" * 80 + f"\nMSG: {d}\n" + DEFS[d] for d in USES[name]]
    return "\n".join(parts)


def write_bag(bag: str | os.PathLike, model: str | os.PathLike | None = None) -> int:
    """Writes the multi-rate log as a ROS 2 bag at ``bag`` (and the model file with its ``[log]`` table at
    ``model``); returns the number of messages.

    Row ``k`` of the CSV holds the input ``u_k`` and the measurements ``y_{k+1}`` taken after it. Sensor message
    ``j`` is stamped ``s_j = T0 + j·ts − 1 ms`` (``s_0 = T0``: it fixes the step grid) and carries what was
    measured at ``t_j``: the inputs of row ``j`` and the outputs of row ``j − 1``. So row ``k``'s inputs are the
    latest at or before ``t_k`` and its outputs the messages in ``(t_k, t_k + ts]``: the bag's rows are the CSV's.
    """
    from mcap_ros2.writer import Writer

    with open(DATA, newline="") as f:
        rows = list(csv.DictReader(f))
    if model is not None:
        Path(model).write_text(MODEL.read_text() + LOG)
    schemas = {}
    count = 0
    with open(bag, "wb") as f:
        w = Writer(f)

        def put(topic: str, type_name: str, t: int, msg: dict) -> None:
            nonlocal count
            if type_name not in schemas:
                schemas[type_name] = w.register_msgdef(type_name, schema_text(type_name))
            w.write_message(topic, schemas[type_name], msg, log_time=t, publish_time=t)
            count += 1

        def header(t: int, frame: str) -> dict:
            return {"stamp": {"sec": t // 1_000_000_000, "nanosec": t % 1_000_000_000}, "frame_id": frame}

        zero9 = [0.0] * 9
        for j in range(len(rows) + 1):
            t = T0 if j == 0 else T0 + j * TS - LATENCY
            now = rows[min(j, len(rows) - 1)]  # inputs u_j (the last row's held once more)
            before = rows[j - 1] if j > 0 else None  # outputs y_j
            gyro = float(before["gyro"]) if before else 0.0
            imu = {
                "header": header(t, "imu_link"),
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                "orientation_covariance": [-1.0] + zero9[1:],
                "angular_velocity": {"x": 0.0, "y": 0.0, "z": gyro},
                "angular_velocity_covariance": zero9,
                "linear_acceleration": {"x": float(now["a"]), "y": 0.0, "z": 9.80665},
                "linear_acceleration_covariance": zero9,
            }
            put("/imu", "sensor_msgs/Imu", t, imu)
            put("/steering", "std_msgs/Float64", t, {"data": float(now["delta"])})
            if before is None:
                continue
            if before["wheel_speed"]:
                twist = {"linear": {"x": float(before["wheel_speed"]), "y": 0.0, "z": 0.0},
                         "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
                put("/wheel/twist", "geometry_msgs/TwistStamped", t, {"header": header(t, "base_link"), "twist": twist})
            if before["gnss_x"]:
                pose = {"position": {"x": float(before["gnss_x"]), "y": float(before["gnss_y"]), "z": 0.0},
                        "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}
                zero = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
                odom = {"header": header(t, "map"), "child_frame_id": "gnss",
                        "pose": {"pose": pose, "covariance": [0.0] * 36},
                        "twist": {"twist": zero, "covariance": [0.0] * 36}}
                put("/gnss/odom", "nav_msgs/Odometry", t, odom)
            if before["compass"]:
                put("/compass", "std_msgs/Float64", t, {"data": float(before["compass"])})
        w.finish()
    return count


def port_est_command(given: str | None) -> list[str]:
    if given or os.environ.get("PORT_EST"):
        return [given or os.environ["PORT_EST"]]
    built = ROOT / "target" / "release" / "port-est"
    if built.is_file():
        return [str(built)]
    return ["cargo", "run", "--quiet", "--release", "-p", "port-est", "--"]


def read_estimates(path: Path) -> tuple[list[dict], list[tuple[int, float, float]]]:
    """The ``/estimate`` messages and the GNSS fixes ``(log time, x, y)`` of a bag, by Python's ``mcap``."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        estimates = [json.loads(m.data) for _, _, m in reader.iter_messages(topics=["/estimate"])]
        fixes = [
            (m.log_time, odom.pose.pose.position.x, odom.pose.pose.position.y)
            for _, _, m, odom in reader.iter_decoded_messages(topics=["/gnss/odom"])
        ]
    return estimates, fixes


def check_against_csv(estimates: list[dict], csv_path: Path, states: list[str]) -> None:
    """The bag's estimates hold the CSV output's numbers, bit for bit."""
    with open(csv_path, newline="") as f:
        rows = list(csv.reader(f))[1:]
    assert len(rows) == len(estimates), (len(rows), len(estimates))
    n = len(states)
    for e, row in zip(estimates, rows):
        assert [e["x"][s] for s in states] == [float(c) for c in row[1 : 1 + n]], row[0]
        assert [e["lower"][s] for s in states] == [float(c) for c in row[1 + n : 1 + 2 * n]], row[0]
        assert [e["upper"][s] for s in states] == [float(c) for c in row[1 + 2 * n : 1 + 3 * n]], row[0]
        assert e["status"] == row[-1], row[0]


def draw(estimates: list[dict], fixes: list[tuple[int, float, float]], svg: Path) -> None:
    import matplotlib

    matplotlib.use("svg")
    import matplotlib.pyplot as plt

    plt.rcParams["svg.fonttype"] = "none"  # text as text: a small file
    plt.rcParams["svg.hashsalt"] = "ros2-bag"  # the same file from the same bag
    t = [e["t"] - T0 / 1e9 for e in estimates]
    x = [e["x"]["x"] for e in estimates]
    y = [e["x"]["y"] for e in estimates]
    fig, (track, width) = plt.subplots(1, 2, figsize=(10, 4))
    track.plot(x, y, color="C0", lw=1.2, label="estimate (centre)")
    track.plot([f[1] for f in fixes], [f[2] for f in fixes], ".", ms=3, color="C1", label="GNSS fixes (/gnss/odom)")
    track.set(xlabel="x [m]", ylabel="y [m]", title="Track, from est.mcap", aspect="equal")
    track.legend(loc="best", fontsize=8)
    step = max(1, len(t) // 400)  # a point every 50 ms is plenty for the figure
    for state, color in (("x", "C0"), ("y", "C2")):
        w = [e["upper"][state] - e["lower"][state] for e in estimates]
        width.plot(t[::step], w[::step], color=color, lw=1.2, label=f"upper − lower of {state}")
    gap = [f[0] for f in fixes]
    gaps = [(a, b) for a, b in zip(gap, gap[1:]) if b - a > 1_000_000_000]
    for a, b in gaps:
        width.axvspan((a - T0) / 1e9, (b - T0) / 1e9, color="0.9", label="no GNSS")
    width.set(xlabel="t [s]", ylabel="width of the guaranteed interval [m]",
              title="czf-nl: the certified interval through the dropout")
    width.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(svg, metadata={"Date": None})
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "target" / "ros2-bag-example"), help="where the bags go")
    ap.add_argument("--port-est", default=None, help="the port-est binary")
    ap.add_argument("--svg", default=str(HERE / "estimate.svg"), help="the figure")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    bag, model = out / "run.mcap", out / "model.toml"
    print(f"{bag}: {write_bag(bag, model)} messages; {model}: the multi-rate model with its [log] table")
    cmd = port_est_command(args.port_est)
    common = ["-m", str(model), "-e", "czf-nl"]
    subprocess.run(cmd + ["filter", *common, "-i", str(bag), "-o", str(out / "est.mcap"), "--copy-topics"], check=True)
    subprocess.run(cmd + ["filter", *common, "-i", str(DATA), "-o", str(out / "out.csv")], check=True)
    estimates, fixes = read_estimates(out / "est.mcap")
    check_against_csv(estimates, out / "out.csv", ["x", "y", "psi", "v"])
    print(f"{out / 'est.mcap'}: {len(estimates)} estimates, the CSV run's numbers bit for bit; {len(fixes)} GNSS fixes")
    draw(estimates, fixes, Path(args.svg))
    print(f"{args.svg}: drawn from {out / 'est.mcap'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
