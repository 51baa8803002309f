"""`ClosedLoop` (the Rust loop of one control period), its configuration dict (deserialised
straight from the Python objects, errors at the dotted key), and `VariantRecorder` with
`write_run_folder`: the scenario runner's metrics and run folder for a plant outside Rust,
here a rigid arm integrated in Python with `aba`."""

import json
import subprocess

import numpy as np
import pytest

import admittance as adm
from conftest import Q0

DT = 1e-3


def pd_config(n, observer=None, admittance=None, subtract=False, kd=None):
    kd = [20.0] * n if kd is None else list(kd)
    config = {
        "control_rate_hz": 1.0 / DT,
        "controller": {
            "kind": "pd",
            "pd": {"kp": [10.0 * g for g in kd], "kd": kd, "gravity_compensation": True},
            "subtract_estimate": subtract,
        },
    }
    if observer is not None:
        config["observer"] = observer
    if admittance is not None:
        config["admittance"] = admittance
    return config


def test_the_loop_is_the_controller_on_the_differentiated_angles(baxter):
    """Without a sensor filter, admittance model or observer, the loop's command is the PD
    controller's on the backward difference of the angles, bit for bit."""
    n = baxter.n
    config = pd_config(n)
    loop = adm.ClosedLoop(baxter, config, sensor_cutoff_hz=0.0)
    ctl = adm.PdController(baxter, config["controller"]["pd"])
    zeros = np.zeros(n)
    q_prev = None
    for k in range(50):
        t = k * DT
        q = Q0 + 0.01 * np.sin(3.0 * t + np.arange(n))
        q_d = Q0 + 0.02
        tau, estimate = loop.step(t, q, None, q_d, zeros, zeros)
        qdot = zeros if q_prev is None else (q - q_prev) / DT
        expected = ctl.step(t, q, qdot, q_d, zeros, zeros, zeros, DT)
        assert np.array_equal(tau, expected), k
        assert np.array_equal(estimate, zeros)
        q_prev = q
    assert np.array_equal(loop.torque, tau) and np.array_equal(loop.q_r, q_d)
    assert loop.fault is None and loop.fault_count == 0 and loop.dt == DT


def test_oracle_momentum_and_warmup(baxter):
    n = baxter.n
    zeros = np.zeros(n)
    truth = np.linspace(-1.0, 1.0, n)
    oracle = adm.ClosedLoop(baxter, pd_config(n, {"kind": "oracle"}))
    _, estimate = oracle.step(0.0, Q0, None, Q0, zeros, zeros, truth)
    assert np.array_equal(estimate, truth)  # the oracle is the truth, unfiltered
    observer = {"kind": "momentum", "cutoff_hz": 5.0, "warmup": 0.05, "momentum": {"gain": 50.0}}
    loop = adm.ClosedLoop(baxter, pd_config(n, observer), sensor_cutoff_hz=40.0)
    out = (np.zeros(n), np.zeros(n))
    seen = []
    for k in range(100):
        tau, estimate = loop.step(k * DT, Q0, np.zeros(n) + 3.0, Q0, zeros, zeros, out=out)
        assert tau is out[0] and estimate is out[1]
        seen.append(np.abs(estimate).max())
    # Held at zero during the warm-up, then the observer reads the unexplained command.
    assert max(seen[:50]) == 0.0 and seen[-1] > 0.0
    assert loop.measurement["q_filtered"].shape == (n,)


def test_config_errors_name_the_dotted_key(baxter):
    n = baxter.n
    bad = pd_config(n)
    bad["controller"]["pd"]["kk"] = 1.0
    with pytest.raises(ValueError, match=r"key `controller\.pd\.kk`: unknown field `kk`"):
        adm.ClosedLoop(baxter, bad)
    with pytest.raises(ValueError, match=r"key `observer\.cutoff_hz`"):
        adm.ClosedLoop(baxter, pd_config(n, {"kind": "momentum", "cutoff_hz": -1.0}))
    # The text a scenario file or a robot's loop.toml gives for the same key (issue 32).
    with pytest.raises(ValueError, match=r"key `observer\.cutof_hz`: unknown field `cutof_hz`, .*; "
                       r"hint: remove the key or fix its spelling; the expected keys are listed$"):
        adm.ClosedLoop(baxter, pd_config(n, {"kind": "momentum", "cutof_hz": 1.0}))
    with pytest.raises(ValueError, match=r"key `observer\.kind`: unknown variant `psychic`"):
        adm.ClosedLoop(baxter, pd_config(n, {"kind": "psychic"}))
    with pytest.raises(ValueError, match=r"key `observer\.warmup`: invalid type: string"):
        adm.ClosedLoop(baxter, pd_config(n, {"kind": "momentum", "warmup": "long"}))
    with pytest.raises(ValueError, match=r"key `observer\.kind`.*trained network"):
        adm.ClosedLoop(baxter, pd_config(n, {"kind": "learned"}))
    with pytest.raises(TypeError, match=r"key `controller\.pd\.kd`: a `object` is not"):
        c = pd_config(n)
        c["controller"]["pd"]["kd"] = object()
        adm.ClosedLoop(baxter, c)
    # numpy values are numbers, None a default.
    c = pd_config(n, {"kind": "momentum", "warmup": None, "cutoff_hz": np.float32(2.0)})
    c["controller"]["pd"]["kp"] = np.full(n, 100, dtype=np.int64)
    adm.ClosedLoop(baxter, c)


def run_rigid_arm(m, variant, config, seconds, push):
    """The loop against the arm `m` itself (semi-implicit Euler on `aba`), pushed by
    `push(t)` (joint torque); returns the finished recorder."""
    n = m.n
    zeros = np.zeros(n)
    loop = adm.ClosedLoop(m, config, sensor_cutoff_hz=40.0)
    rec = adm.VariantRecorder(variant, m, config, seconds, 0.5, decimation=5)
    q, qdot, tau_ext = Q0.copy(), zeros.copy(), zeros.copy()
    for k in range(int(round(seconds / DT))):
        t = k * DT
        tau, _ = loop.step(t, q, None, Q0, zeros, zeros, tau_ext)
        tau_ext = push(t)
        qdot = qdot + DT * adm.aba(m, q, qdot, tau + tau_ext)
        q = q + DT * qdot
        if rec.add(loop, q, qdot, tau_ext) is not None:
            break
    rec.finish(loop)
    return rec


def scenario(m, variants, config):
    base = {k: v for k, v in config.items() if k not in ("observer", "control_rate_hz")}
    return {
        "name": "python_plant",
        "description": "a rigid arm integrated in Python",
        "duration": 1.0,
        "evaluation_start": 0.5,
        "arm": {"urdf": str(m_path()), "base": "base", "tip": "left_hand"},
        **base,
        "plant": {"control_rate_hz": config["control_rate_hz"]},
        "observer": {"cutoff_hz": 5.0, "warmup": 0.1},
        "variants": {v: {"observer": {"kind": v}} for v in variants},
    }


def m_path():
    from conftest import BAXTER

    return BAXTER


def test_recorder_and_run_folder(baxter, tmp_path, admittance_bin):
    n = baxter.n
    admittance = {
        "damping": [10.0] + [1e4] * (n - 1),
        "stiffness": [5.0] + [1e4] * (n - 1),
        "saturation": {"rho": 0.95, "centre": Q0.tolist(), "half_range": [1.1] + [np.inf] * (n - 1)},
    }
    push = lambda t: np.where(np.arange(n) == 0, 2.0 if t > 0.3 else 0.0, 0.0)  # noqa: E731
    recorders = []
    kd = np.maximum(20.0 * np.diag(adm.crba(baxter, Q0)), 0.05)  # a 20 rad/s velocity loop
    for variant in ("oracle", "momentum"):
        observer = {"kind": variant, "cutoff_hz": 5.0, "warmup": 0.1}
        config = pd_config(n, observer, admittance, kd=kd)
        recorders.append(run_rigid_arm(baxter, variant, config, 1.0, push))
    oracle, momentum = recorders
    metrics = oracle.metrics
    assert oracle.steps == 1000 and oracle.divergence is None
    assert metrics["diverged"] is False and metrics["steps"] == 1000
    # The oracle's estimate is the truth one step late: in contact, a small error.
    assert metrics["external_torque_nrmse"] < 0.05
    assert momentum.metrics["external_torque_nrmse"] > metrics["external_torque_nrmse"]
    assert metrics["reference_bound_violations"] == 0
    assert len(metrics["admittance_error_rms"]) == n
    fresh = adm.ClosedLoop(baxter, pd_config(n))
    with pytest.raises(ValueError, match="not stepped yet"):
        adm.VariantRecorder("x", baxter, pd_config(n), 1.0, 0.5).add(fresh, Q0, Q0, Q0)
    fresh.step(0.0, Q0, None, Q0, np.zeros(n), np.zeros(n))
    with pytest.raises(RuntimeError, match="already finished"):
        oracle.add(fresh, Q0, np.zeros(n), np.zeros(n))

    out = tmp_path / "run"
    config = pd_config(n, None, admittance, kd=kd)
    summary, failures = adm.write_run_folder(
        out, scenario(baxter, ["oracle", "momentum"], config), recorders,
        {"plant": "python"}, header="written by a test",
    )
    assert failures == []
    written = json.loads((out / "summary.json").read_text())
    assert written == summary
    assert written["format"] == "admittance-run" and written["plant"] == "python"
    assert written["variant_order"] == ["oracle", "momentum"]
    assert written["variants"]["oracle"]["external_torque_nrmse"] == metrics["external_torque_nrmse"]
    with open(out / "oracle.csv") as f:
        header = f.readline().strip().split(",")
    assert header[0] == "t" and f"tau_ext_hat.{baxter.joint_names[0]}" in header
    rows = np.loadtxt(out / "oracle.csv", delimiter=",", skiprows=1)
    assert rows.shape == (200, len(header))
    text = (out / "scenario.toml").read_text()
    assert text.startswith("# written by a test\n")
    # The scenario as run loads and runs as a scenario (Rust simulator, the momentum variant).
    rerun = adm.run(out / "scenario.toml", tmp_path / "rerun", variant="momentum",
                    overrides={"duration": 0.2, "evaluation_start": 0.1}, report=False)
    assert rerun["variants"]["momentum"]["steps"] == 200
    # `admittance report` draws the folder.
    p = subprocess.run([str(admittance_bin), "report", str(out)], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    assert (out / "report.md").is_file()
    # A folder the tool did not write is refused; a scenario without the variant too.
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep")
    with pytest.raises(FileExistsError, match="did not write"):
        adm.write_run_folder(mine, scenario(baxter, ["oracle", "momentum"], config), recorders)
    with pytest.raises(FileExistsError, match="did not write"):
        adm.check_out_dir(mine)
    adm.check_out_dir(out)
    with pytest.raises(ValueError, match=r"variants\.momentum"):
        adm.write_run_folder(tmp_path / "other", scenario(baxter, ["oracle"], config), recorders)
    assert (mine / "notes.txt").read_text() == "keep" and not (tmp_path / "other").exists()


def test_the_example_of_docs_python_md_runs(monkeypatch, capsys):
    """docs/python.md's example of `ClosedLoop` ("The whole loop") runs as printed."""
    import re

    from conftest import ROOT

    text = (ROOT / "docs" / "python.md").read_text()
    section = text[text.index("**The whole loop.**"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(ROOT)
    namespace = {}
    exec(compile(code, "docs/python.md", "exec"), namespace)
    loop, q = namespace["loop"], namespace["q"]
    assert np.abs(loop.q_r - q).max() < 1e-9 and loop.fault is None
    assert "None" in capsys.readouterr().out
