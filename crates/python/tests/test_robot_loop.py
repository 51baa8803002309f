"""`RobotLoop` (issue 32): the robot's loop of a deployment folder (`admittance deploy`),
the loop the C ABI and the ROS 2 bridge wrap. No command before the first angles, the first
pose held, one absurd sample flagged and forgotten (issue 34), a missing file named."""

import subprocess

import numpy as np
import pytest

import admittance as adm
from conftest import ROOT

POSE = np.array([0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5])


@pytest.fixture(scope="module")
def deployed(admittance_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("deploy") / "baxter_momentum"
    subprocess.run(
        [str(admittance_bin), "deploy", str(ROOT / "scenarios/admittance.toml"),
         "--variant", "momentum", "--out", str(out)],
        check=True, capture_output=True, text=True,
    )
    return out


def motion(k):
    t = k * 1e-3
    w = 1.0 + 0.3 * np.arange(7)
    return POSE + 0.1 * np.sin(w * t), 0.5 * np.sin(3.0 * t) * np.ones(7)


def run(deployed, absurd, overrides=None):
    loop = adm.RobotLoop.load(str(deployed), overrides)
    estimates, statuses = [], []
    for k in range(3000):
        q, tau = motion(k)
        if absurd and k == 1000:
            tau[1] = 1e300
        if absurd and k == 1500:
            q[3] = 1e20
        torque, est = loop.step(k * 1e-3, q, tau)
        assert np.all(np.isfinite(torque))
        estimates.append(est.copy())
        statuses.append(loop.status)
    return loop, np.array(estimates), statuses


def test_an_absurd_sample_is_flagged_and_forgotten(deployed):
    _, clean, _ = run(deployed, False)
    loop, hit, statuses = run(deployed, True)
    assert statuses[1000]["implausible"] == (1, "torque")
    assert statuses[1500]["implausible"] == (3, "angle")
    assert loop.implausible_samples == 2
    assert np.max(np.abs(hit[2500:] - clean[2500:])) < 1e-3
    _, open_, _ = run(deployed, True, ["signals.gates.enabled = false"])
    assert not np.max(np.abs(open_[1000:] - clean[1000:])) < 1e3


def test_safe_by_default(deployed):
    loop = adm.RobotLoop.load(str(deployed))
    q = POSE.copy()
    q[2] = np.nan
    torque, _ = loop.step(0.0, q)
    assert loop.status["waiting_for_angles"] and not loop.status["ok"]
    assert np.all(torque == 0.0)
    for k in range(1, 300):
        loop.step(k * 1e-3, POSE)
    assert loop.status["holding_pose"]
    # An observer on the URDF has no training range: never outside it.
    assert loop.status["outside_training_range"] is False
    assert loop.status["faster_than_training"] is False
    np.testing.assert_allclose(loop.reference[0], POSE, atol=1e-9)


def test_a_missing_file_is_named(deployed, tmp_path):
    import shutil
    copy = tmp_path / "copy"
    shutil.copytree(deployed, copy)
    (copy / "arm.urdf").unlink()
    with pytest.raises(ValueError, match="arm.urdf"):
        adm.RobotLoop.load(str(copy))


def test_a_time_that_is_not_finite_is_refused_and_nothing_is_stepped(deployed):
    loop = adm.RobotLoop.load(str(deployed))
    loop.step(0.0, POSE)
    before = loop.status
    for t in (np.nan, np.inf, -np.inf):
        with pytest.raises(ValueError, match="`t` is .*must be finite"):
            loop.step(t, POSE)
    assert loop.status == before
