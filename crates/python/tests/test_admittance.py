"""The admittance model: its exact first-order solution, the saturation, configuration and
faults."""

import math

import numpy as np
import pytest

import admittance as adm
from conftest import Q0

DT = 1e-3


def test_first_order_solution_is_exact(baxter):
    a = adm.Admittance(baxter, damping=3.0, stiffness=5.0, rho=None)
    tau = np.array([1.0, -2.0, 0.0, 0.5, 0.0, 0.0, 0.1])
    zeros = np.zeros(7)
    for k in range(1, 1001):
        q_r, qd_r, qdd_r = a.step(Q0, zeros, zeros, tau, DT)
    # x = (tau / G_d)(1 - exp(-G_d t / C_d)), x' = (tau - G_d x) / C_d, x'' = -(G_d / C_d) x'.
    x = tau / 5.0 * (1 - math.exp(-5.0 * 1.0 / 3.0))
    xd = (tau - 5.0 * x) / 3.0
    np.testing.assert_allclose(q_r, Q0 + x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(qd_r, xd, rtol=0, atol=1e-12)
    np.testing.assert_allclose(qdd_r, -(5.0 / 3.0) * xd, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.deviation, x, atol=1e-12)
    np.testing.assert_allclose(a.q_a, Q0 + x, atol=1e-12)
    a.reset()
    np.testing.assert_array_equal(a.deviation, zeros)


def test_per_joint_values_and_second_order(baxter):
    damping = np.linspace(1.0, 7.0, 7)
    a = adm.Admittance(baxter, damping, [5.0] * 7, mass=0.2, rho=None)
    tau = np.ones(7)
    zeros = np.zeros(7)
    for _ in range(20000):
        q_r, qd_r, _ = a.step(zeros, zeros, zeros, tau, DT)
    # Settles at tau / G_d whatever the damping and inertia.
    np.testing.assert_allclose(q_r, tau / 5.0, atol=1e-6)
    np.testing.assert_allclose(qd_r, 0.0, atol=1e-6)


def test_saturation_keeps_the_reference_inside_the_bound(baxter):
    zeros = np.zeros(7)
    paper = adm.Admittance(baxter, 3.0, 5.0, bound=1.1)
    limits = adm.Admittance(baxter, 3.0, 5.0)  # bound from the joint limits
    for _ in range(3000):
        q_r, _, _ = paper.step(zeros, zeros, zeros, np.full(7, 100.0), DT)
        q_l, _, _ = limits.step(Q0, zeros, zeros, np.full(7, -100.0), DT)
    assert np.all(paper.q_a > 10.0)  # the unsaturated state went far
    assert np.all(q_r < 1.1) and np.all(q_r > 0.95 * 1.1)
    assert np.all(q_l > baxter.lower) and np.all(q_l < Q0)
    assert np.all(limits.q_a < baxter.lower)
    with pytest.raises(ValueError, match="`bound` needs `rho`"):
        adm.Admittance(baxter, 3.0, 5.0, rho=None, bound=1.0)
    with pytest.raises(ValueError, match=r"`rho`: is 1.5"):
        adm.Admittance(baxter, 3.0, 5.0, rho=1.5)


def test_from_config_takes_the_scenario_keys(baxter):
    # scenarios/admittance.toml's [admittance] table.
    cfg = {"damping": [3.0] + [1e4] * 6, "stiffness": [5.0] + [1e4] * 6,
           "saturation": {"rho": 0.95, "centre": 0.0, "half_range": [1.1] + [float("inf")] * 6}}
    a = adm.Admittance.from_config(baxter, cfg)
    zeros = np.zeros(7)
    for _ in range(3000):
        q_r, _, _ = a.step(zeros, zeros, zeros, np.full(7, 100.0), DT)
    assert q_r[0] < 1.1 and q_r[0] > 1.0
    np.testing.assert_allclose(q_r[1:], a.q_a[1:])  # unsaturated joints
    with pytest.raises(ValueError, match=r"Admittance config: key `saturation.centr`: unknown field `centr`"):
        adm.Admittance.from_config(baxter, {"damping": 1.0, "stiffness": 1.0, "saturation": {"rho": 0.9, "half_range": 1.0, "centr": 0.0}})
    with pytest.raises(ValueError, match=r"`stiffness`: is 0, must be a finite number > 0"):
        adm.Admittance.from_config(baxter, {"damping": 1.0, "stiffness": 0.0})
    with pytest.raises(ValueError, match=r"missing field `stiffness`"):
        adm.Admittance.from_config(baxter, {"damping": 1.0})


def test_shapes_out_and_faults(baxter):
    with pytest.raises(ValueError, match=r"`damping` must have shape \(7,\)"):
        adm.Admittance(baxter, [1.0, 2.0], 5.0)
    with pytest.raises(ValueError, match=r"`stiffness`: is -5"):
        adm.Admittance(baxter, 1.0, -5.0)
    a = adm.Admittance(baxter, 3.0, 5.0, bound=1.1)
    zeros = np.zeros(7)
    outs = (np.empty(7), np.empty(7), np.empty(7))
    got = a.step(zeros, zeros, zeros, np.ones(7), DT, out=outs)
    assert all(g is o for g, o in zip(got, outs))
    last = outs[0].copy()
    bad = np.ones(7)
    bad[3] = np.nan
    q_r, qd_r, qdd_r = a.step(zeros, zeros, zeros, bad, DT)
    assert a.fault == "external torque estimate is not finite at joint 3" and a.fault_count == 1
    np.testing.assert_array_equal(q_r, last)  # the reference is held
    np.testing.assert_array_equal(qd_r, zeros)
    np.testing.assert_array_equal(qdd_r, zeros)
    a.step(zeros, zeros, zeros, np.ones(7), DT)
    assert a.fault is None and a.fault_count == 1
    with pytest.raises(ValueError, match=r"`tau_ext_hat` must have shape \(7,\)"):
        a.step(zeros, zeros, zeros, np.ones(6), DT)
    with pytest.raises(ValueError, match="tuple of three"):
        a.step(zeros, zeros, zeros, np.ones(7), DT, out=np.empty(7))
    assert a.n == 7
