"""Controllers: each law against its formula, in a closed loop on the arm's own dynamics
(semi-implicit Euler on `aba`), the fault behaviour, and configuration errors."""

import numpy as np
import pytest

import admittance as adm
from conftest import Q0

DT = 1e-3
KP = np.array([100.0, 150.0, 50.0, 50.0, 10.0, 10.0, 2.0])  # scenarios/admittance.toml
KD = np.array([10.0, 15.0, 4.0, 4.0, 0.5, 0.5, 0.1])


def reference(t):
    """s0 follows a slow sine from the pose Q0, the others hold."""
    w = 2 * np.pi / 2.0
    q = Q0.copy()
    qd, qdd = np.zeros(7), np.zeros(7)
    q[0] += 0.2 * np.sin(w * t)
    qd[0] = 0.2 * w * np.cos(w * t)
    qdd[0] = -0.2 * w * w * np.sin(w * t)
    return q, qd, qdd


def hold(t):
    """The pose Q0, held."""
    return Q0, np.zeros(7), np.zeros(7)


def closed_loop(m, ctl, seconds, ref=reference, q0=Q0):
    """Runs `ctl` on the arm (no friction, no contact) from rest at `q0` and returns the
    tracking errors and torques per step."""
    q, qd = np.array(q0, dtype=float), np.zeros(7)
    zeros = np.zeros(7)
    errors, torques = [], []
    for k in range(int(seconds / DT)):
        t = k * DT
        q_r, qd_r, qdd_r = ref(t)
        tau = ctl.step(t, q, qd, q_r, qd_r, qdd_r, zeros, DT)
        assert ctl.fault is None, ctl.fault
        qd = qd + DT * adm.aba(m, q, qd, tau)
        q = q + DT * qd
        errors.append(q_r - q)
        torques.append(tau)
    return np.array(errors), np.array(torques)


def test_pd_gravity_law_and_loop(baxter):
    ctl = adm.PdController(baxter, {"kp": KP, "kd": KD.tolist(), "gravity_compensation": True})
    assert ctl.name == "pd_gravity" and ctl.n == 7 and isinstance(ctl, adm.Controller)
    rng = np.random.default_rng(2)
    q, qd = Q0 + rng.uniform(-0.1, 0.1, 7), rng.uniform(-0.5, 0.5, 7)
    q_r, qd_r = Q0, np.zeros(7)
    tau = ctl.step(0.0, q, qd, q_r, qd_r, np.zeros(7), np.zeros(7), DT)
    law = KP * (q_r - q) + KD * (qd_r - qd) + adm.gravity(baxter, q)
    limit = baxter.effort_limit
    np.testing.assert_allclose(tau, np.clip(law, -limit, limit), rtol=0, atol=1e-12)
    # From 0.05 rad off on every joint to the pose, held against gravity: the error decays
    # (e0, with the lowest gain for its inertia, last: 7.6e-3 rad after 1 s, 1.6e-4 after 3 s).
    errors, torques = closed_loop(baxter, ctl, 3.0, ref=hold, q0=Q0 + 0.05)
    assert np.all(np.abs(torques) <= limit)
    assert np.max(np.abs(errors[-1])) < 1e-3
    assert np.max(np.abs(errors[-1])) < 0.1 * np.max(np.abs(errors[1000]))


def test_pd_without_gravity_is_plain_pd(baxter):
    ctl = adm.PdController(baxter, {"kp": 10.0, "kd": 1.0})
    assert ctl.name == "pd"
    tau = ctl.step(0.0, Q0, np.zeros(7), Q0 + 0.01, np.zeros(7), np.zeros(7), np.zeros(7), DT)
    np.testing.assert_allclose(tau, np.full(7, 0.1), rtol=1e-12)


def test_computed_torque_law_and_loop(baxter):
    ctl = adm.ComputedTorqueController(baxter, {"kp": 400.0, "kd": 40.0})
    assert ctl.name == "computed_torque"
    q, qd, qdd = Q0 + 0.05, np.full(7, 0.1), np.linspace(-1, 1, 7)
    q_r, qd_r = Q0, np.zeros(7)
    tau = ctl.step(0.0, q, qd, q_r, qd_r, qdd, np.zeros(7), DT)
    acc = qdd + 40.0 * (qd_r - qd) + 400.0 * (q_r - q)
    limit = baxter.effort_limit
    np.testing.assert_allclose(tau, np.clip(adm.rnea(baxter, q, qd, acc), -limit, limit), rtol=0, atol=1e-12)
    ctl.reset()
    errors, _ = closed_loop(baxter, ctl, 1.0)
    assert np.max(np.abs(errors[200:])) < 2e-3


def test_neural_controller_loop_reset_and_determinism(baxter):
    ctl = adm.NeuralController(baxter)
    assert ctl.name == "nn"
    errors, torques = closed_loop(baxter, ctl, 0.5)
    assert np.all(np.isfinite(torques)) and np.all(np.abs(torques) <= baxter.effort_limit)
    # It adapts: the same input gives another torque after learning than at the start.
    args = (0.0, Q0 + 0.01, np.zeros(7), Q0, np.zeros(7), np.zeros(7), np.zeros(7), DT)
    fresh = adm.NeuralController(baxter)
    first = fresh.step(*args)
    assert not np.array_equal(ctl.step(*args), first)
    ctl.reset()
    np.testing.assert_array_equal(ctl.step(*args), first)
    # A configured controller: other gains, no deadzone network.
    cfg = {"k1": [12.0] * 7, "k2": 3.0, "deadzone_compensation": False,
           "f": {"form": "lumped", "network": {"placement": {"kind": "random", "count": 64, "seed": 3}}}}
    small = adm.NeuralController(baxter, cfg)
    tau = small.step(*args)
    assert np.all(np.isfinite(tau)) and small.fault is None


def test_out_is_written_and_returned(baxter):
    ctl = adm.PdController(baxter, {"kp": 10.0, "kd": 1.0, "gravity_compensation": True})
    out = np.full(7, np.nan)
    tau = ctl.step(0.0, Q0, np.zeros(7), Q0, np.zeros(7), np.zeros(7), np.zeros(7), DT, out=out)
    assert tau is out
    np.testing.assert_allclose(out, adm.gravity(baxter, Q0), atol=1e-12)
    with pytest.raises(ValueError, match="`out`"):
        ctl.step(0.0, Q0, np.zeros(7), Q0, np.zeros(7), np.zeros(7), np.zeros(7), DT, out=np.empty(3))


@pytest.mark.parametrize("make", [
    lambda m: adm.NeuralController(m),
    lambda m: adm.PdController(m, {"kp": 10.0, "kd": 1.0, "gravity_compensation": True}),
    lambda m: adm.ComputedTorqueController(m, {"kp": 10.0, "kd": 1.0}),
])
def test_faults_hold_safely(baxter, make):
    ctl = make(baxter)
    zeros = np.zeros(7)
    ctl.step(0.0, Q0, zeros, Q0, zeros, zeros, zeros, DT)
    assert ctl.fault is None and ctl.fault_count == 0
    bad = Q0.copy()
    bad[2] = np.nan
    qd = np.full(7, 0.2)
    tau = ctl.step(DT, bad, qd, Q0, zeros, zeros, zeros, DT)
    assert ctl.fault == "measured `q` is not finite at joint 2"
    assert ctl.fault_count == 1
    # The documented hold: nominal gravity at the last valid position minus 0.5 qdot.
    expected = np.clip(adm.gravity(baxter, Q0) - 0.5 * qd, -baxter.effort_limit, baxter.effort_limit)
    np.testing.assert_allclose(tau, expected, atol=1e-12)
    est = zeros.copy()
    est[6] = np.inf
    ctl.step(2 * DT, Q0, zeros, Q0, zeros, zeros, est, DT)
    assert "estimate" in ctl.fault and ctl.fault_count == 2
    ctl.step(3 * DT, Q0, zeros, Q0, zeros, zeros, zeros, 0.0)
    assert "time step" in ctl.fault and ctl.fault_count == 3
    ctl.step(4 * DT, Q0, zeros, Q0, zeros, zeros, zeros, DT)
    assert ctl.fault is None and ctl.fault_count == 3
    with pytest.raises(ValueError, match=r"`qddot_ref` must have shape \(7,\)"):
        ctl.step(0.0, Q0, zeros, Q0, zeros, np.zeros(8), zeros, DT)
    ctl.reset()
    assert ctl.fault_count == 0


def test_config_errors_name_the_key(baxter):
    with pytest.raises(ValueError, match=r"NeuralController config: key `kk`: unknown field `kk`"):
        adm.NeuralController(baxter, {"kk": 1.0})
    with pytest.raises(ValueError, match=r"unknown field `sgima`"):
        adm.NeuralController(baxter, {"f": {"form": "lumped", "network": {"sgima": 0.1}}})
    with pytest.raises(ValueError, match=r"`k1`: is -1, must be a finite number > 0"):
        adm.NeuralController(baxter, {"k1": -1})
    with pytest.raises(ValueError, match=r"`k2`: has 3 values but the arm has 7 joints"):
        adm.NeuralController(baxter, {"k2": [1.0, 2.0, 3.0]})
    with pytest.raises(ValueError, match=r"key `k1`"):
        adm.NeuralController(baxter, {"k1": "fast"})
    with pytest.raises(ValueError, match=r"missing field `kd`"):
        adm.PdController(baxter, {"kp": 1.0})
    with pytest.raises(ValueError, match=r"unknown field `gravity`"):
        adm.PdController(baxter, {"kp": 1.0, "kd": 1.0, "gravity": True})
    with pytest.raises(ValueError, match=r"key `safe_hold.dampin`: unknown field `dampin`"):
        adm.ComputedTorqueController(baxter, {"kp": 1.0, "kd": 1.0, "safe_hold": {"dampin": 1.0}})
    with pytest.raises(ValueError, match=r"key `variants`"):
        adm.NeuralController(baxter, {"variants": {}})
    with pytest.raises(TypeError, match="must be a dict"):
        adm.NeuralController(baxter, [("k1", 1.0)])
    with pytest.raises(TypeError, match="keys must be strings"):
        adm.NeuralController(baxter, {1: 1.0})
    with pytest.raises(TypeError, match=r"config: key `k1`: a `object` is not a configuration value"):
        adm.NeuralController(baxter, {"k1": object()})
    # None leaves a key at its default; the safe hold's keys validate too.
    adm.NeuralController(baxter, {"k1": None, "safe_hold": {"damping": 0.3, "effort_limits": 40.0}})
    with pytest.raises(ValueError, match=r"safe_hold.*damping"):
        adm.PdController(baxter, {"kp": 1.0, "kd": 1.0, "safe_hold": {"damping": -1.0}})
