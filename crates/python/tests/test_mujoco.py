"""The MuJoCo co-simulation (`python -m admittance.mujoco`), shortened: the run folder it
writes, the oracle's estimate against MuJoCo's own external torque, the admittance yielding
to the push, and the refusal of a folder the tool did not write. The bars are measured on
the full run (docs/python.md)."""

import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT

mujoco = pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco)")

from admittance.mujoco import CosimConfig, run_cosimulation  # noqa: E402

PANDA = ROOT / "models" / "franka_panda.urdf"


def short(out, **kw):
    return CosimConfig(
        urdf=str(PANDA), tip="panda_hand_tcp", out=str(out), duration=14.0,
        training_duration=20.0, validation_duration=6.0, nodes=80, **kw,
    )


def read_csv(path):
    with open(path) as f:
        cols = f.readline().strip().split(",")
    return cols, np.loadtxt(path, delimiter=",", skiprows=1)


def test_push_run_folder_metrics_and_the_oracle(tmp_path):
    out = tmp_path / "run"
    summary = run_cosimulation(short(out, variants=["momentum", "oracle"]), log=lambda s: None)
    assert summary["failures"] == []
    written = json.loads((out / "summary.json").read_text())
    assert written["format"] == "admittance-run" and written["plant"] == "mujoco"
    assert written["variant_order"] == ["momentum", "oracle"]
    for name, m in written["variants"].items():
        assert m["diverged"] is False
        assert m["reference_bound_violations"] == 0
        assert m["torque_limit_violations"] == 0
        assert np.isfinite(m["external_torque_nrmse"])
    # The oracle is driven by MuJoCo's own J^T f: its estimate is the truth, low-passed.
    assert written["variants"]["oracle"]["external_torque_nrmse"] < 0.1
    # The unknown friction: the momentum observer reads it as torque.
    assert written["variants"]["momentum"]["external_torque_nrmse"] > 0.3
    cols, data = read_csv(out / "oracle.csv")
    t = data[:, cols.index("t")]
    tau = data[:, cols.index("tau_ext.panda_joint1")]
    # The push acts from 8 s on and reaches every joint it can turn.
    assert np.all(np.abs(tau[t < 7.9]) < 1e-9)
    assert np.max(np.abs(tau[t > 8.5])) > 1.0
    # Joint 1's admittance yields: q_r leaves q_d during the push.
    dev = data[:, cols.index("q_r.panda_joint1")] - data[:, cols.index("q_d.panda_joint1")]
    assert np.max(np.abs(dev[t > 9])) > 0.05
    assert (out / "scenario.toml").is_file()


def test_a_folder_of_the_users_is_refused(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    cmd = [
        sys.executable, "-m", "admittance.mujoco", "--urdf", str(PANDA), "--tip", "panda_hand_tcp",
        "--out", str(mine), "--duration", "1", "--variants", "oracle",
    ]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert p.returncode != 0
    assert "did not write" in p.stderr
    assert (mine / "notes.txt").read_text() == "keep"


def test_a_wall_is_real_contact(tmp_path):
    out = tmp_path / "wall"
    summary = run_cosimulation(short(out, contact="wall", variants=["oracle"]), log=lambda s: None)
    assert summary["failures"] == []
    cols, data = read_csv(out / "oracle.csv")
    tau = data[:, cols.index("tau_ext.panda_joint1")]
    # Joint 1 swings the hand into the box: contact torque on joint 1, resisting the motion.
    assert np.max(np.abs(tau)) > 0.5


def test_free_motion_is_recorded_on_the_excitation():
    """The training recording tracks `adm.excitation` (issue 22), with a seed drawn from the
    recording's generator; `training_motion="multisine"` keeps the hand-made multi-sine."""
    import admittance as adm
    from admittance.mujoco._cosim import home_pose, pd_gains, record_free_motion
    from admittance.mujoco._plant import MujocoArm

    m = adm.Model.from_urdf(PANDA, tip="panda_hand_tcp")
    cfg = short("unused")
    arm = MujocoArm(PANDA.read_text(), m.joint_names, "panda_hand_tcp", m.effort_limit, cfg.dt, 1.0)
    q0 = home_pose(m)
    pd = pd_gains(m, q0)
    data = record_free_motion(arm, m, q0, pd, cfg, np.random.default_rng(5), 3.0)
    seed = int(np.random.default_rng(5).integers(1, 2**31 - 1))
    e = adm.excitation(m, 3.0, seed=seed, rate_hz=1000.0, range=float("inf"), velocity_fraction=1.0, acceleration_fraction=1.0)
    assert data["q"].shape == (3000, m.n) and np.all(np.isfinite(data["tau"]))
    late = slice(1000, 3000)
    # The stiff joints follow it closely (the wrist's PD is soft: pd_gains ignores armature).
    assert np.max(np.abs(data["q"][late, :4] - e["q"][late, :4])) < 0.1
    assert np.ptp(e["q"][:, :4], axis=0).min() > 0.2  # and it does move
    cfg.training_motion = "multisine"
    other = record_free_motion(arm, m, q0, pd, cfg, np.random.default_rng(5), 1.0)
    assert np.max(np.abs(other["q"][500:] - e["q"][500:1000])) > 0.05
    cfg.training_motion = "sines"
    with pytest.raises(ValueError, match="training_motion"):
        record_free_motion(arm, m, q0, pd, cfg, np.random.default_rng(5), 1.0)
