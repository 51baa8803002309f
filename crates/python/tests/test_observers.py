"""Observers on data whose external torque is known: tau = RNEA(q, qdot, qddot) - tau_ext along
a smooth excitation (the arm's own dynamics, docs/method.md's sign: tau_ext acts on the robot)."""

import numpy as np
import pytest

import admittance as adm
from conftest import Q0, free_motion, multisine

DT = 1e-3
EXT = np.array([2.0, -1.0, 0.5, 1.0, 0.2, -0.3, 0.1])


def contact_data(m, seconds=1.0, seed=1, friction=0.0):
    t = np.arange(0.0, seconds, DT)
    q, qd, qdd = multisine(t, m.n, seed)
    tau = np.array([adm.rnea(m, q[k], qd[k], qdd[k]) for k in range(len(t))]) + friction * qd - EXT
    return t, q, qd, qdd, tau


def run(obs, data):
    t, q, qd, qdd, tau = data
    return np.array([obs.update(t[k], q[k], qd[k], qdd[k], tau[k], DT) for k in range(len(t))])


def test_momentum_observer_converges_to_the_external_torque(baxter):
    data = contact_data(baxter)
    obs = adm.MomentumObserver(baxter, gain=50.0)
    assert obs.name == "momentum" and obs.n == 7 and isinstance(obs, adm.Observer)
    est = run(obs, data)
    np.testing.assert_array_equal(est[0], np.zeros(7))  # the first sample sets p0
    # A first-order lag of 1/50 s: after 0.1 s within 1 %; the 1 kHz discretisation
    # leaves about 0.2 % at the end.
    assert np.max(np.abs(est[-1] - EXT)) < 0.01 * np.max(np.abs(EXT))
    lag = np.abs(est[20] - EXT) / np.abs(EXT)  # after 20 ms = one time constant: ~exp(-1)
    assert np.all(lag > 0.25) and np.all(lag < 0.5)
    # Per-joint gains and the [observer.momentum] table give the same observer.
    a = adm.MomentumObserver(baxter, gain=[50.0] * 7)
    b = adm.MomentumObserver(baxter, config={"gain": 50.0})
    np.testing.assert_array_equal(run(a, data)[-1], est[-1])
    np.testing.assert_array_equal(run(b, data)[-1], est[-1])
    obs.reset()
    np.testing.assert_array_equal(run(obs, data)[-1], est[-1])


def test_momentum_observer_faults_and_errors(baxter):
    obs = adm.MomentumObserver(baxter)
    zeros = np.zeros(7)
    tau = adm.gravity(baxter, Q0)
    obs.update(0.0, Q0, zeros, zeros, tau, DT)
    bad = tau.copy()
    bad[1] = np.nan
    est = obs.update(DT, Q0, zeros, zeros, bad, DT)
    np.testing.assert_array_equal(est, zeros)
    assert obs.fault == "measured `tau_commanded` is not finite at joint 1" and obs.fault_count == 1
    out = np.full(7, np.nan)
    assert obs.update(2 * DT, Q0, zeros, zeros, tau, DT, out=out) is out
    assert obs.fault is None and np.all(np.isfinite(out))
    with pytest.raises(ValueError, match=r"`qddot` must have shape \(7,\)"):
        obs.update(0.0, Q0, zeros, np.zeros(3), tau, DT)
    with pytest.raises(ValueError, match="`gain` or `config`, not both"):
        adm.MomentumObserver(baxter, gain=10.0, config={"gain": 10.0})
    with pytest.raises(ValueError, match=r"unknown field `gian`"):
        adm.MomentumObserver(baxter, config={"gian": 10.0})
    with pytest.raises(ValueError, match=r"`gain`: is -1"):
        adm.MomentumObserver(baxter, gain=-1.0)
    with pytest.raises(ValueError, match=r"`gain` must have shape \(7,\) \(one value per joint, or a single number\)"):
        adm.MomentumObserver(baxter, gain=[1.0, 2.0])


def test_an_absurd_finite_torque_is_a_fault_and_is_not_integrated(baxter):
    # Issue 34: one torque of 1e300 used to leave the momentum observer's estimate near
    # 1e274 N m a second later; beyond +-1e12 a value now takes the path of a NaN.
    data = contact_data(baxter, seconds=2.0)
    clean = run(adm.MomentumObserver(baxter, gain=50.0), data)
    t, q, qd, qdd, tau = data
    hit = tau.copy()
    hit[500, 2] = 1e300
    obs = adm.MomentumObserver(baxter, gain=50.0)
    est = run(obs, (t, q, qd, qdd, hit))
    np.testing.assert_array_equal(est[500], np.zeros(7))
    assert obs.fault_count == 1
    assert np.max(np.abs(est[1500:] - clean[1500:])) < 1e-3


def test_learned_observer_is_the_network_minus_the_torque(baxter, network):
    t, q, qd, qdd, tau = contact_data(baxter, seconds=0.2)
    raw = network.predict(q, qd, qdd) - tau
    obs = adm.LearnedObserver(network)
    assert obs.name == "learned"
    np.testing.assert_allclose(run(obs, (t, q, qd, qdd, tau)), raw, rtol=0, atol=1e-9)
    # With a 5 Hz low-pass: a first-order filter started at the first raw value.
    filtered = adm.LearnedObserver(network, cutoff_hz=5.0)
    alpha = DT / (DT + 1.0 / (2 * np.pi * 5.0))
    expected = [raw[0]]
    for r in raw[1:]:
        expected.append(expected[-1] + alpha * (r - expected[-1]))
    np.testing.assert_allclose(run(filtered, (t, q, qd, qdd, tau)), expected, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="cutoff_hz"):
        adm.LearnedObserver(network, cutoff_hz=-1.0)


def test_hybrid_observer_beats_the_momentum_observer_with_a_model_error(baxter, motion):
    nominal = baxter.with_scaled_inertias(0.8)
    # Another recording of other motion shows which outputs pay (without one, all are zero).
    other = free_motion(baxter, 20.0, rate=200.0, seed=1, friction=0.3)
    residual = adm.train(motion, baxter, 80, nominal=nominal, friction_features=True, validation=other)
    # It learned tau - RNEA_nominal = 0.2 RNEA + 0.3 qdot.
    assert np.all(residual.validation_nrmse < 0.5)
    data = contact_data(baxter, friction=0.3)
    momentum = run(adm.MomentumObserver(nominal, gain=50.0), data)[-300:]
    hybrid_obs = adm.HybridObserver(nominal, residual, gain=50.0)
    assert hybrid_obs.name == "hybrid"
    hybrid = run(hybrid_obs, data)[-300:]
    err = lambda est: np.sqrt(np.mean((est - EXT) ** 2))
    assert err(hybrid) < 0.5 * err(momentum), (err(hybrid), err(momentum))
    with pytest.raises(ValueError, match="HybridObserver"):
        adm.HybridObserver(adm.Model.from_urdf_string(_two_joint_urdf()), residual)


def test_oracle_returns_the_true_value():
    obs = adm.OracleObserver(3)
    assert obs.name == "oracle" and obs.n == 3
    obs.set_true_value([1.0, 2.0, 3.0])
    zeros = np.zeros(3)
    np.testing.assert_array_equal(obs.update(0.0, zeros, zeros, zeros, zeros, DT), [1.0, 2.0, 3.0])
    obs.set_true_value([np.nan, 0.0, 0.0])
    np.testing.assert_array_equal(obs.update(0.0, zeros, zeros, zeros, zeros, DT), zeros)
    assert "estimate" in obs.fault
    with pytest.raises(ValueError, match=r"`tau_ext` must have shape \(3,\)"):
        obs.set_true_value([1.0])
    with pytest.raises(ValueError):
        adm.OracleObserver(0)


def test_input_conditioner_is_the_training_conditioning(baxter, motion):
    """Feeding the data through InputConditioner and training on the result equals training
    with input_filter_hz on the raw data: one conditioning, at run time and in training."""
    c = adm.InputConditioner(7, 10.0, 200.0)
    assert c.n == 7
    rows = [c.update(motion["q"][k], motion["tau"][k]) for k in range(len(motion["t"]))]
    conditioned = {"t": motion["t"]}
    for i, name in enumerate(("q", "qdot", "qddot", "tau")):
        conditioned[name] = np.array([r[i] for r in rows])
    a = adm.train(conditioned, baxter, 40)
    b = adm.train(motion, baxter, 40, input_filter_hz=10.0)
    x = (motion["q"][:50], motion["qdot"][:50], motion["qddot"][:50])
    np.testing.assert_array_equal(a.predict(*x), b.predict(*x))
    np.testing.assert_array_equal(a.validation_nrmse, b.validation_nrmse)
    with pytest.raises(ValueError, match="InputConditioner"):
        adm.InputConditioner(7, 150.0, 200.0)  # above Nyquist
    bad = np.zeros(7)
    bad[0] = np.nan
    with pytest.raises(ValueError, match=r"`q\[0\]` is NaN"):
        c.update(bad, np.zeros(7))


def _two_joint_urdf():
    link = ('<link name="{0}"><inertial><mass value="1"/><origin xyz="0 0 0.1"/>'
            '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>')
    joint = ('<joint name="{0}" type="revolute"><parent link="{1}"/><child link="{2}"/>'
             '<origin xyz="0 0 0.2"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="2"/></joint>')
    return ('<robot name="two">' + '<link name="base"/>' + link.format("l1") + link.format("l2")
            + joint.format("j1", "base", "l1") + joint.format("j2", "l1", "l2") + "</robot>")
