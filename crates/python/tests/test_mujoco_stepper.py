"""The co-simulation's control steps in Rust (``adm.CosimStepper``, ``adm.FreeMotionStepper``,
issue 33 part 3) against its Python loops (``run_variant_stepwise``, ``_record_stepwise``):
the same MuJoCo arm, loop and push (or wall) stepped both ways give the same state, metrics
and every step's row of the time series, and the same free-motion recording, bit for bit."""

import numpy as np
import pytest

import admittance as adm
from conftest import ROOT

pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco)")

from admittance.mujoco import _cosim  # noqa: E402
from admittance.mujoco._plant import MujocoArm  # noqa: E402

PANDA = ROOT / "models" / "franka_panda.urdf"
#: Timings, not results: they differ from one run to the next.
TIMINGS = {"controller_step_median_us"}


def run_both_ways(tmp_path, variants, duration, contact="push"):
    cfg = _cosim.CosimConfig(urdf=str(PANDA), tip="panda_hand_tcp", duration=duration, contact=contact)
    m = adm.Model.from_urdf(cfg.urdf, tip=cfg.tip)
    q0 = _cosim.home_pose(m)
    pd = _cosim.pd_gains(m, q0)
    text = PANDA.read_text()
    probe = MujocoArm(text, m.joint_names, cfg.tip, m.effort_limit, cfg.dt, cfg.friction_scale)
    contact = _cosim.plan_contact(cfg, m, q0, probe)
    folders, states = {}, {}
    for stepwise in (True, False):
        recorders, state = [], []
        for variant in variants:
            arm = MujocoArm(text, m.joint_names, cfg.tip, m.effort_limit, cfg.dt, cfg.friction_scale, contact.wall)
            rec, *_ = _cosim.run_variant(variant, arm, m, {}, q0, pd, cfg, np.random.default_rng(cfg.seed + 7),
                                        contact, stepwise=stepwise)
            recorders.append(rec)
            state.append((arm.data.qpos.copy(), arm.data.qvel.copy(), arm.data.qacc.copy()))
        out = tmp_path / ("stepwise" if stepwise else "rust")
        summary, failures = _cosim.write_run_folder(out, cfg, m, cfg.tip, q0, pd, recorders, {})
        assert failures == []
        folders[stepwise], states[stepwise] = (out, summary), state
    return folders, states


def assert_same(folders, states, variants, steps):
    for (qa, va, aa), (qb, vb, ab) in zip(states[True], states[False]):
        assert np.array_equal(qa, qb) and np.array_equal(va, vb) and np.array_equal(aa, ab)
    (ref, ref_summary), (fast, fast_summary) = folders[True], folders[False]
    for variant in variants:
        a, b = ref_summary["variants"][variant], fast_summary["variants"][variant]
        assert a["steps"] == steps
        assert {k: v for k, v in a.items() if k not in TIMINGS} == {k: v for k, v in b.items() if k not in TIMINGS}
        rows = (ref / f"{variant}.csv").read_bytes()
        assert rows.count(b"\n") == steps + 1
        assert rows == (fast / f"{variant}.csv").read_bytes()
    cols = (ref / "oracle.csv").read_text().splitlines()[0].split(",")
    return np.loadtxt(ref / "oracle.csv", delimiter=",", skiprows=1)[:, cols.index("tau_ext.panda_joint1")]


def test_the_rust_steps_equal_the_python_loop(tmp_path, monkeypatch):
    # Every step in the series (not one in ten), through the push (8 s on).
    monkeypatch.setattr(_cosim, "DECIMATION", 1)
    variants = ["momentum", "oracle"]
    folders, states = run_both_ways(tmp_path, variants, duration=9.5)
    tau = assert_same(folders, states, variants, 9500)
    # The push reached the oracle's series: the comparison covers J^T f, not zeros only.
    assert np.max(np.abs(tau)) > 0.5


def test_the_rust_steps_equal_the_python_loop_against_a_wall(tmp_path, monkeypatch):
    # Joint 1 reaches the wall (0.3 rad from the pose) after about 1.2 s.
    monkeypatch.setattr(_cosim, "DECIMATION", 1)
    variants = ["oracle"]
    folders, states = run_both_ways(tmp_path, variants, duration=3.0, contact="wall")
    tau = assert_same(folders, states, variants, 3000)
    assert np.max(np.abs(tau)) > 0.5 and np.count_nonzero(tau) < len(tau)


def test_a_divergence_stops_both_loops_at_the_same_step():
    # A push of 1e6 N drives the oracle's estimate past 10 x an effort limit just after 8 s.
    cfg = _cosim.CosimConfig(urdf=str(PANDA), tip="panda_hand_tcp", duration=10.0, push_force=1e6)
    m = adm.Model.from_urdf(cfg.urdf, tip=cfg.tip)
    q0 = _cosim.home_pose(m)
    pd = _cosim.pd_gains(m, q0)
    text = PANDA.read_text()
    contact = _cosim.plan_contact(cfg, m, q0, MujocoArm(text, m.joint_names, cfg.tip, m.effort_limit, cfg.dt, 1.0))
    ends = []
    for stepwise in (True, False):
        arm = MujocoArm(text, m.joint_names, cfg.tip, m.effort_limit, cfg.dt, 1.0)
        rec, *_ = _cosim.run_variant("oracle", arm, m, {}, q0, pd, cfg, np.random.default_rng(8), contact,
                                    stepwise=stepwise)
        metrics = {k: v for k, v in rec.metrics.items() if k not in TIMINGS}
        ends.append((rec.steps, rec.divergence, metrics, arm.data.qpos.tobytes(), arm.data.qvel.tobytes()))
    assert ends[0][1] is not None and 8000 < ends[0][0] < 10000
    assert ends[0] == ends[1]


@pytest.mark.parametrize("motion, seconds", [("excitation", 3.0), ("multisine", 4.5)])
def test_the_free_motion_recording_in_rust_equals_the_python_loop(motion, seconds):
    cfg = _cosim.CosimConfig(urdf=str(PANDA), tip="panda_hand_tcp", training_motion=motion)
    m = adm.Model.from_urdf(cfg.urdf, tip=cfg.tip)
    q0 = _cosim.home_pose(m)
    pd = _cosim.pd_gains(m, q0)
    runs = []
    for stepwise in (True, False):
        arm = MujocoArm(PANDA.read_text(), m.joint_names, cfg.tip, m.effort_limit, cfg.dt, 1.0)
        data = _cosim.record_free_motion(arm, m, q0, pd, cfg, np.random.default_rng(3), seconds, stepwise=stepwise)
        runs.append((data, arm.data.qpos.tobytes(), arm.data.qvel.tobytes()))
    (a, *state_a), (b, *state_b) = runs
    steps = int(round(seconds * 1000))
    assert a["q"].shape == (steps, m.n) and np.ptp(a["q"][:, 0]) > 0.01
    assert sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in a)
    assert state_a == state_b


def test_the_stepper_refuses_a_bad_plan(tmp_path):
    cfg = _cosim.CosimConfig(urdf=str(PANDA), tip="panda_hand_tcp", duration=1.0)
    m = adm.Model.from_urdf(cfg.urdf, tip=cfg.tip)
    q0 = _cosim.home_pose(m)
    config = _cosim.loop_config("momentum", cfg, m, q0, _cosim.pd_gains(m, q0))
    loop = adm.ClosedLoop(m, config)
    rec = adm.VariantRecorder("momentum", m, config, 1.0, 0.5)
    arm = MujocoArm(PANDA.read_text(), m.joint_names, cfg.tip, m.effort_limit, cfg.dt, 1.0)
    rows = np.zeros((10, m.n))
    plan = dict(dt=1e-3, q_d=rows, qdot_d=rows, qddot_d=rows, noise=rows, resolution=1e-4,
                push=np.zeros((10, 3)), push_on=[False] * 10)
    with pytest.raises(ValueError, match="noise"):
        adm.CosimStepper(loop, rec, arm.stepper_plant(), **{**plan, "noise": np.zeros((9, m.n))})
    plant = arm.stepper_plant()
    plant["dof_index"] = [0] * (m.n - 1)
    with pytest.raises(ValueError, match="dof_index"):
        adm.CosimStepper(loop, rec, plant, **plan)
    stepper = adm.CosimStepper(loop, rec, arm.stepper_plant(), **plan)
    with pytest.raises(ValueError, match="not within"):
        stepper.run(5, 11)
    assert stepper.run(0, 10) is None and rec.steps == 10
