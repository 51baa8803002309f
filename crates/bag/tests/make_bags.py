"""Writes the small rosbag2 test bags of crates/bag/tests/data with `rosbags` (pure Python,
no ROS): a known analytic trajectory on each profile's real topic names, so that the Rust
tests compare the imported columns with the truth.

    python3 -m venv .venv-bag && .venv-bag/bin/pip install rosbags mcap  # 0.11.9, 1.6.0
    .venv-bag/bin/python crates/bag/tests/make_bags.py crates/bag/tests/data

The truth (the same formulas are in crates/bag/tests/common/mod.rs), joint i = 0..n-1,
s = stamp - T0 in seconds:

    q_i(s)     = A_i sin(W_i s + P_i) + C_i,   A_i = 0.3 + 0.05 i, W_i = 2 pi (0.5 + 0.1 i),
                                               P_i = 0.2 i,        C_i = 0.1 i
    qdot_i, qddot_i: its exact derivatives
    tau_i(s)   = 5 sin(q_i) + 0.5 qdot_i + 0.1 (i + 1) qddot_i
    label_i(s) = 0.2 (i + 1) sin(2 pi s)               (external joint torque)
    wrench(s)  = [1, 2, 3, 0.1, 0.2, 0.3] * cos(2 pi s)

Each message's header stamp is T0 + k / rate exactly; its log (receive) time is the stamp
plus a deterministic latency of 0.1 to 0.5 ms, so that a reader using the receive time
instead of the stamp is caught.
"""

import math
import shutil
import sys
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

T0_NS = 1_700_000_000 * 10**9
FRANKA = [f"fr3_joint{i}" for i in range(1, 8)]
UR = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
      "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
# joint_state_broadcaster need not publish in chain order: the UR bag uses this order.
UR_PUBLISHED = sorted(UR)
UR_TORQUE_CONSTANT = [10.0, 10.0, 10.0, 5.0, 5.0, 5.0]  # test values, not UR's
LBR = [f"lbr_A{i}" for i in range(1, 8)]

# lbr_fri_idl/msg/LBRState as the lbr_fri_ros2_stack defines it (field order and types;
# the comments are ours).
LBR_STATE = """
float64 sample_time
int8 session_state
int8 connection_quality
int8 safety_state
int8 operation_mode
int8 drive_state
int8 client_command_mode
int8 overlay_type
int8 control_mode
uint32 time_stamp_sec
uint32 time_stamp_nano_sec
float64[7] measured_joint_position
float64[7] commanded_joint_position
float64[7] measured_torque
float64[7] commanded_torque
float64[7] external_torque
float64[7] ipo_joint_position
float64 tracking_performance
"""


def truth(i, s):
    a, w, p, c = 0.3 + 0.05 * i, 2 * math.pi * (0.5 + 0.1 * i), 0.2 * i, 0.1 * i
    q = a * math.sin(w * s + p) + c
    qd = a * w * math.cos(w * s + p)
    qdd = -a * w * w * math.sin(w * s + p)
    tau = 5 * math.sin(q) + 0.5 * qd + 0.1 * (i + 1) * qdd
    return q, qd, qdd, tau


def label(i, s):
    return 0.2 * (i + 1) * math.sin(2 * math.pi * s)


def wrench(s):
    c = math.cos(2 * math.pi * s)
    return [1 * c, 2 * c, 3 * c, 0.1 * c, 0.2 * c, 0.3 * c]


def latency_ns(k):
    return 100_000 + (k * 7919) % 400_001


def stamps(rate, seconds, offset_ns=0):
    period = round(1e9 / rate)
    n = int(round(seconds * rate))
    return [T0_NS + offset_ns + k * period for k in range(n)]


class Bag:
    """A rosbags Writer (a rosbag2 folder), or with `mcap_compression` a single MCAP file
    written with the `mcap` package (which stores chunk CRCs and can write lz4)."""

    def __init__(self, path, storage=StoragePlugin.MCAP, zstd=False, mcap_compression=None):
        self.ts = get_typestore(Stores.ROS2_HUMBLE)
        self.ts.register(get_types_from_msg(LBR_STATE, "lbr_fri_idl/msg/LBRState"))
        self.path = path
        self.mcap_compression = mcap_compression
        self.w = None
        if mcap_compression is None:
            self.w = Writer(path, version=9, storage_plugin=storage)
            if zstd:
                self.w.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
            self.w.open()
        self.conns = {}
        self.pending = []

    def add(self, topic, msgtype, t_ns, msg, k):
        if topic not in self.conns:
            self.conns[topic] = (
                self.w.add_connection(topic, msgtype, typestore=self.ts) if self.w else msgtype
            )
        data = self.ts.serialize_cdr(msg, msgtype)
        self.pending.append((t_ns + latency_ns(k), topic, data))

    def close(self):
        # A recorder writes in receive order.
        pending = sorted(self.pending, key=lambda x: x[0])
        if self.w is None:
            return self.close_mcap(pending)
        for log, topic, data in pending:
            self.w.write(self.conns[topic], log, data)
        self.w.close()

    def close_mcap(self, pending):
        from mcap.writer import Writer as McapWriter

        with open(self.path, "wb") as f:
            w = McapWriter(f, compression=self.mcap_compression, enable_crcs=True)
            w.start(profile="ros2", library="make_bags.py")
            channels = {}
            for topic, msgtype in self.conns.items():
                msgdef = self.ts.generate_msgdef(msgtype)[0]
                schema = w.register_schema(name=msgtype, encoding="ros2msg", data=msgdef.encode())
                channels[topic] = w.register_channel(topic=topic, message_encoding="cdr",
                                                     schema_id=schema)
            for seq, (log, topic, data) in enumerate(pending):
                w.add_message(channel_id=channels[topic], log_time=log, publish_time=log,
                              data=data, sequence=seq)
            w.finish()

    def header(self, t_ns):
        T = self.ts.types
        stamp = T["builtin_interfaces/msg/Time"](sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id="base")

    def joint_state(self, topic, t_ns, k, names, pos, vel, eff):
        T = self.ts.types
        msg = T["sensor_msgs/msg/JointState"](
            header=self.header(t_ns), name=list(names),
            position=np.array(pos, dtype=np.float64), velocity=np.array(vel, dtype=np.float64),
            effort=np.array(eff, dtype=np.float64))
        self.add(topic, "sensor_msgs/msg/JointState", t_ns, msg, k)

    def wrench(self, topic, t_ns, k, w):
        T = self.ts.types
        v3 = T["geometry_msgs/msg/Vector3"]
        msg = T["geometry_msgs/msg/WrenchStamped"](
            header=self.header(t_ns),
            wrench=T["geometry_msgs/msg/Wrench"](force=v3(x=w[0], y=w[1], z=w[2]),
                                                 torque=v3(x=w[3], y=w[4], z=w[5])))
        self.add(topic, "geometry_msgs/msg/WrenchStamped", t_ns, msg, k)


def franka(path, seconds, zstd, storage=StoragePlugin.MCAP, mcap_compression=None):
    bag = Bag(path, storage, zstd, mcap_compression)
    base = "/franka_robot_state_broadcaster/"
    for k, t in enumerate(stamps(1000, seconds)):
        s = (t - T0_NS) / 1e9
        rows = [truth(i, s) for i in range(7)]
        bag.joint_state(base + "measured_joint_states", t, k, FRANKA,
                        [r[0] for r in rows], [r[1] for r in rows], [r[3] for r in rows])
    # The estimates at 250 Hz, 0.5 ms after the joint states: the import interpolates.
    for k, t in enumerate(stamps(250, seconds, 500_000)):
        s = (t - T0_NS) / 1e9
        bag.joint_state(base + "external_joint_torques", t, k, FRANKA, [], [],
                        [label(i, s) for i in range(7)])
        bag.wrench(base + "external_wrench_in_base_frame", t, k, wrench(s))
    bag.close()


def ur(path, seconds):
    bag = Bag(path)
    for k, t in enumerate(stamps(500, seconds)):
        s = (t - T0_NS) / 1e9
        rows = {UR[i]: truth(i, s) for i in range(6)}
        kt = dict(zip(UR, UR_TORQUE_CONSTANT))
        bag.joint_state("/joint_states", t, k, UR_PUBLISHED,
                        [rows[j][0] for j in UR_PUBLISHED], [rows[j][1] for j in UR_PUBLISHED],
                        [rows[j][3] / kt[j] for j in UR_PUBLISHED])
        bag.wrench("/force_torque_sensor_broadcaster/wrench", t, k, wrench(s))
    bag.close()


def lbr(path, seconds):
    bag = Bag(path, zstd=True)
    state = bag.ts.types["lbr_fri_idl/msg/LBRState"]
    for k, t in enumerate(stamps(1000, seconds)):
        s = (t - T0_NS) / 1e9
        rows = [truth(i, s) for i in range(7)]
        q = np.array([r[0] for r in rows])
        tau = np.array([r[3] for r in rows])
        msg = state(sample_time=0.001, session_state=4, connection_quality=3, safety_state=0,
                    operation_mode=2, drive_state=1, client_command_mode=3, overlay_type=1,
                    control_mode=3, time_stamp_sec=t // 10**9, time_stamp_nano_sec=t % 10**9,
                    measured_joint_position=q, commanded_joint_position=q + 1e-4,
                    measured_torque=tau, commanded_torque=tau - 0.5,
                    external_torque=np.array([label(i, s) for i in range(7)]),
                    ipo_joint_position=q, tracking_performance=1.0)
        bag.add("/lbr/state", "lbr_fri_idl/msg/LBRState", t, msg, k)
    bag.close()


def single_file(folder, target):
    """Moves the folder bag's one .mcap file to `target` and removes the folder."""
    (mcap,) = Path(folder).glob("*.mcap")
    shutil.move(str(mcap), target)
    shutil.rmtree(folder)


def main(out):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    names = ["franka_zstd", "franka_plain.mcap", "ur_plain", "lbr_zstd", "franka_sqlite",
             "franka_crc_zstd.mcap", "franka_lz4.mcap"]
    for name in names:
        p = out / name
        if p.is_dir():
            shutil.rmtree(p)
        elif p.exists():
            p.unlink()
    franka(out / "franka_zstd", 1.0, zstd=True)
    franka(out / "tmp_plain", 0.1, zstd=False)
    single_file(out / "tmp_plain", out / "franka_plain.mcap")
    ur(out / "ur_plain", 0.2)
    lbr(out / "lbr_zstd", 0.5)
    franka(out / "franka_sqlite", 0.01, zstd=False, storage=StoragePlugin.SQLITE3)
    from mcap.writer import CompressionType

    franka(out / "franka_crc_zstd.mcap", 0.1, zstd=False, mcap_compression=CompressionType.ZSTD)
    franka(out / "franka_lz4.mcap", 0.02, zstd=False, mcap_compression=CompressionType.LZ4)
    total = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    print(f"wrote {out}: {total} bytes")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent / "data")
