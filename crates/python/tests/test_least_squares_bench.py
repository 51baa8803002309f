"""The least-squares bench on a user's own recording (scripts/bench/identify_vs_least_squares.py
`--recording`): the free-motion CSV read by its column names, and every problem told before
a fit (the fits themselves need Pinocchio, which the bench's own environment installs)."""

import importlib.util

import numpy as np
import pytest

import admittance as adm
from conftest import BAXTER, ROOT


def bench():
    spec = importlib.util.spec_from_file_location("ls_bench", ROOT / "scripts" / "bench" / "identify_vs_least_squares.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write_recording(path, m, rows, columns=None):
    """A free-motion CSV of `rows` samples at 100 Hz, its columns shuffled (read by name)."""
    names = ["t"] + [f"{key}.{j}" for key in ("q", "qdot", "qddot", "tau") for j in m.joint_names]
    rng = np.random.default_rng(3)
    table = np.column_stack([np.arange(rows) * 0.01] + [rng.normal(size=rows) for _ in names[1:]])
    order = columns if columns is not None else list(rng.permutation(len(names)))
    with open(path, "w") as f:
        f.write(",".join(names[i] for i in order) + "\n")
        for row in table:
            f.write(",".join(repr(float(row[i])) for i in order) + "\n")
    return table


def test_a_recording_is_read_by_its_column_names(tmp_path):
    m = adm.Model.from_urdf(str(BAXTER))
    table = write_recording(tmp_path / "r.csv", m, 50)
    data = bench().load_recording(tmp_path / "r.csv", m)
    n = m.n
    assert np.array_equal(data["t"], table[:, 0])
    for k, key in enumerate(("q", "qdot", "qddot", "tau")):
        assert np.array_equal(data[key], table[:, 1 + k * n : 1 + (k + 1) * n]), key


def test_derivatives_left_out_are_taken_by_differences(tmp_path):
    # As the project's loader takes them (FreeMotionData): backward differences over the
    # time column, a row dropped per derivative taken in turn.
    m = adm.Model.from_urdf(str(BAXTER))
    n, names = m.n, 1 + 4 * m.n
    table = write_recording(tmp_path / "r.csv", m, 30, columns=[0] + list(range(1, 1 + n)) + list(range(1 + 3 * n, names)))
    data = bench().load_recording(tmp_path / "r.csv", m)
    t, q = table[:, 0], table[:, 1 : 1 + n]
    qdot = np.diff(q, axis=0) / np.diff(t)[:, None]
    qddot = np.diff(qdot, axis=0) / np.diff(t[1:])[:, None]
    assert np.array_equal(data["t"], t[2:])
    assert np.allclose(data["qdot"], qdot[1:], rtol=1e-12) and np.allclose(data["qddot"], qddot, rtol=1e-12)
    assert np.array_equal(data["tau"], table[2:, 1 + 3 * n :])


def test_a_missing_column_and_time_going_back_are_named(tmp_path):
    m = adm.Model.from_urdf(str(BAXTER))
    b = bench()
    names = 1 + 4 * m.n
    write_recording(tmp_path / "short.csv", m, 20, columns=[i for i in range(names) if i != names - 1])
    with pytest.raises(SystemExit, match=r"short\.csv: line 1: no column 'tau\.left_w2' \(1 missing\)"):
        b.load_recording(tmp_path / "short.csv", m)
    write_recording(tmp_path / "back.csv", m, 20, columns=list(range(names)))
    lines = (tmp_path / "back.csv").read_text().splitlines()
    lines[6] = "0" + lines[6][lines[6].index(",") :]  # the 6th sample at t = 0
    (tmp_path / "back.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(SystemExit, match=r"back\.csv: line 7: time 0 s does not come after 0\.04 s"):
        b.load_recording(tmp_path / "back.csv", m)
    with pytest.raises(SystemExit, match=r"nowhere\.csv: no such file"):
        b.load_recording(tmp_path / "nowhere.csv", m)


def test_the_scored_rows_are_never_the_fitted_ones(tmp_path):
    m = adm.Model.from_urdf(str(BAXTER))
    b = bench()
    write_recording(tmp_path / "r.csv", m, 1000)
    args = dict(log=lambda s: None, urdf=BAXTER, m=m, path=tmp_path / "r.csv")
    with pytest.raises(SystemExit, match="overlap"):
        b.recording_points(**args, train_s=(0.0, 6.0), score_s=(5.0, 10.0))
    # The same file given as the other recording is still the fitted one.
    with pytest.raises(SystemExit, match="overlap"):
        b.recording_points(**args, score_path=tmp_path / "r.csv")
    with pytest.raises(SystemExit, match=r"--score: 50 rows scored \(at least 100\)"):
        b.recording_points(**args, train_s=(0.0, 5.0), score_s=(5.0, 5.5))


def test_the_link_torque_sensor_reads_the_torque_past_the_joint_friction():
    # `--link-torque`: what a link-side joint torque sensor reads is the command less the
    # plant's damping, rotor inertia and dry friction (at most its frictionloss), not the command.
    pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco)")
    import importlib.metadata

    try:
        importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    from admittance.mujoco import _arms
    from admittance.mujoco._plant import MujocoArm

    cfg = _arms.ArmsConfig()
    path, base, tip = _arms.arm_source("so101", cfg)
    m = adm.Model.from_urdf(str(path), base=base, tip=tip)
    arm = MujocoArm(path.read_text(), m.joint_names, tip or m.tip_link, m.effort_limit, cfg.dt, cfg.friction_scale)
    motion, _ = _arms.excitation_motion(m, 1.0, 1, cfg.dt)
    gains = _arms.recording_gains(m, motion["q"].mean(axis=0), arm.terms)
    sensor = bench().LinkTorqueSensor(m, cfg.dt, 1)
    assert np.array_equal(sensor.offset, bench().LinkTorqueSensor(m, cfg.dt, 2).offset)  # one sensor's offset
    sensor.noise[:] = 0.0
    sensor.offset[:] = 0.0
    steps = []

    def reading(q, qdot, plant, tau):
        read = sensor(q, qdot, plant, tau)
        steps.append((read, tau.copy(), qdot.copy(), plant.qdot()))
        return read

    data = _arms.record(arm, m, motion, gains, cfg, np.random.default_rng(1), torque_sensor=reading)[0]
    armature = np.array([t["armature"] for t in arm.terms])
    damping = np.array([t["damping"] for t in arm.terms])
    friction = np.array([t["frictionloss"] for t in arm.terms])
    gap = []
    for read, tau, before, after in steps:
        # MuJoCo's implicit damping acts on the velocity after the step.
        rest = tau - read - armature * (after - before) / cfg.dt - damping * after
        gap.append(np.abs(rest) - friction)
    gap = np.array(gap)
    assert gap.max() < 1e-3 * friction.max(), gap.max()
    differs = np.abs(np.array([s[1] - s[0] for s in steps]))
    assert differs.max() > 0.5 * friction.max()  # not the command
    assert data["tau"].shape == data["q"].shape
