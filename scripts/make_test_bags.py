#!/usr/bin/env python3
"""Writes the ROS 2 bag fixtures under fixtures/bags/ (MCAP files of
sensor_msgs/msg/JointState, written by the `mcap` and `mcap-ros2-support`
packages, the writers ROS 2 tools build on) and the CSV logs they must read as.

Run in a throwaway environment:

    python3 -m venv /tmp/venv-bags
    /tmp/venv-bags/bin/pip install mcap mcap-ros2-support
    /tmp/venv-bags/bin/python scripts/make_test_bags.py [--sim SIM.csv]

`--sim` converts a simulated log (`aras simulate --out SIM.csv`, columns
t,theta1,theta2,tau1,tau2 or with logged derivatives) into `sim.mcap`, the
bag the command-line tests identify. The committed bags are small (tens of
kB), so the Rust tests need no Python.

Bags:
* clean.mcap: /joint_states at 100 Hz, joints motor_left, motor_right with
  position, velocity and effort, header stamps 1.5 ms before the bag's log
  time (jittered), plus a /chatter topic of std_msgs/msg/String; clean.csv
  holds the same values (t from the first header stamp, dtheta from velocity).
* two_topics.mcap: /joint_states (as clean) and /arm/joint_states (three
  joints, fewer messages).
* dropped.mcap: clean with messages 60-62 and 150 dropped.
* reordered.mcap: clean, but odd messages list the joints in reverse order
  and every third message carries an extra `gripper` joint; reads as clean.csv.
* no_effort.mcap: clean without effort.
* no_stamps.mcap: clean with every header stamp left at zero (a driver that
  does not fill it); only the log time orders it.
"""

import argparse
import math
import os

from mcap.writer import CompressionType
from mcap_ros2.writer import Writer

JOINT_STATE = """std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""

STRING = "string data\n"

# ROS time of the first sample: 2024-01-01T00:00:00Z.
T0_NS = 1_704_067_200 * 1_000_000_000
STEP_NS = 10_000_000  # 100 Hz
N = 240
NAMES = ["motor_left", "motor_right"]
OUT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures", "bags"))


def sample(i):
    """θ, θ̇, τ of sample i: two sines in rad, rad/s and N·m."""
    t = i * STEP_NS / 1e9
    w1, w2 = 2 * math.pi * 0.7, 2 * math.pi * 1.3
    # Within the ARAS-Diamond's workspace (θ1 ≈ 2.5, θ2 ≈ 1.0 rad), so that
    # every command can run the robot's model on these angles.
    th = [2.5 + 0.3 * math.sin(w1 * t), 1.0 - 0.2 * math.cos(w2 * t)]
    dth = [0.3 * w1 * math.cos(w1 * t), 0.2 * w2 * math.sin(w2 * t)]
    tau = [0.8 * math.sin(w1 * t + 0.3) + 0.05, 0.5 * math.cos(w2 * t - 0.2)]
    return th, dth, tau


def joint_state(stamp_ns, names, pos, vel, eff):
    return {
        "header": {
            "stamp": {"sec": stamp_ns // 1_000_000_000, "nanosec": stamp_ns % 1_000_000_000},
            "frame_id": "",
        },
        "name": names,
        "position": pos,
        "velocity": vel,
        "effort": eff,
    }


def log_time(i, stamp_ns):
    """The recorder's receive time: 1.5 ms after the stamp, ±0.4 ms jitter."""
    return stamp_ns + 1_500_000 + ((i * 7919) % 9 - 4) * 100_000


def clean_messages(drop=(), reorder=False, effort=True, stamps=True):
    for i in range(N):
        if i in drop:
            continue
        th, dth, tau = sample(i)
        stamp = T0_NS + i * STEP_NS
        names, pos, vel, eff = list(NAMES), th, dth, tau
        if reorder and i % 2 == 1:
            names, pos, vel, eff = names[::-1], pos[::-1], vel[::-1], eff[::-1]
        if reorder and i % 3 == 0:
            names, pos, vel, eff = names + ["gripper"], pos + [0.01], vel + [0.0], eff + [0.2]
        yield i, joint_state(stamp if stamps else 0, names, pos, vel, eff if effort else []), log_time(
            i, stamp
        )


def write_bag(name, topics):
    """topics: list of (topic, schema name, definition, messages) with messages
    (index, message, log_time)."""
    path = os.path.join(OUT, name)
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD)
        events = []
        for topic, datatype, definition, messages in topics:
            schema = w.register_msgdef(datatype, definition)
            for i, msg, lt in messages:
                events.append((lt, topic, schema, msg, i))
        events.sort(key=lambda e: e[0])
        for lt, topic, schema, msg, i in events:
            w.write_message(topic, schema, msg, log_time=lt, publish_time=lt, sequence=i)
        w.finish()
    print(f"{path}: {os.path.getsize(path)} bytes")


def write_clean_csv():
    path = os.path.join(OUT, "clean.csv")
    with open(path, "w") as f:
        f.write("t,theta1,theta2,tau1,tau2,dtheta1,dtheta2\n")
        for i in range(N):
            th, dth, tau = sample(i)
            t = (i * STEP_NS) / 1e9
            f.write(",".join(repr(x) for x in [t, *th, *tau, *dth]) + "\n")


def chatter():
    for i in range(0, N, 20):
        stamp = T0_NS + i * STEP_NS
        yield i, {"data": f"status {i}"}, stamp + 3


def arm_messages():
    for i in range(0, N, 2):
        th, dth, tau = sample(i)
        stamp = T0_NS + i * STEP_NS
        msg = joint_state(stamp, ["a1", "a2", "a3"], th + [0.0], dth + [0.0], tau + [0.0])
        yield i, msg, log_time(i, stamp) + 1


def sim_bag(csv_path):
    """The simulated log as a bag: joints joint_a, joint_b, stamps from t."""
    with open(csv_path) as f:
        rows = [line.strip() for line in f if line.strip() and not line.startswith("#")]
    header = rows[0].split(",")
    col = {n: k for k, n in enumerate(header)}
    msgs = []
    for i, line in enumerate(rows[1:]):
        v = [float(x) for x in line.split(",")]
        stamp = T0_NS + round(v[col["t"]] * 1e9)
        pos = [v[col["theta1"]], v[col["theta2"]]]
        eff = [v[col["tau1"]], v[col["tau2"]]]
        msgs.append((i, joint_state(stamp, ["joint_a", "joint_b"], pos, [], eff), stamp + 200_000))
    write_bag("sim.mcap", [("/joint_states", "sensor_msgs/msg/JointState", JOINT_STATE, msgs)])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", help="a simulated log (aras simulate) to convert into sim.mcap")
    args = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    js = ("sensor_msgs/msg/JointState", JOINT_STATE)
    write_clean_csv()
    write_bag(
        "clean.mcap",
        [("/joint_states", *js, clean_messages()), ("/chatter", "std_msgs/msg/String", STRING, chatter())],
    )
    write_bag(
        "two_topics.mcap",
        [("/joint_states", *js, clean_messages()), ("/arm/joint_states", *js, arm_messages())],
    )
    write_bag("dropped.mcap", [("/joint_states", *js, clean_messages(drop={60, 61, 62, 150}))])
    write_bag("reordered.mcap", [("/joint_states", *js, clean_messages(reorder=True))])
    write_bag("no_effort.mcap", [("/joint_states", *js, clean_messages(effort=False))])
    write_bag("no_stamps.mcap", [("/joint_states", *js, clean_messages(stamps=False))])
    if args.sim:
        sim_bag(args.sim)


if __name__ == "__main__":
    main()
