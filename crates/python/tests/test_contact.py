"""Contact detection from Python (issue 31's contract): calibrate_contact on free motion the
identification did not fit, the floor's file, ContactDetector (estimate, flags, link) and the
admittance's deadband."""

import numpy as np
import pytest

import admittance as adm

from conftest import free_motion


def noisy(data, seed, sd=0.2):
    """The recording with white noise on the torque (what the identification cannot fit)."""
    rng = np.random.default_rng(seed)
    return {**data, "tau": data["tau"] + sd * rng.standard_normal(data["tau"].shape)}


@pytest.fixture(scope="module")
def ident_and_floor(baxter, motion):
    ident = adm.identify(motion, baxter)
    calibration = noisy(free_motion(baxter, 120.0, rate=200.0, seed=1, friction=0.3), 1)
    return ident, adm.calibrate_contact(calibration, ident, false_alarms_per_hour=1.0)


def test_the_floor_has_a_level_per_joint_and_round_trips(baxter, ident_and_floor, tmp_path):
    _, floor = ident_and_floor
    c, k = floor.contact_thresholds, floor.collision_thresholds
    assert c.shape == (baxter.n,) and k.shape == (baxter.n,)
    assert np.all(c > 0) and np.all(k >= c)
    assert floor.false_alarms_per_hour == 1.0
    assert "guarantee" in floor.describe()
    path = tmp_path / "floor.json"
    floor.save(path)
    back = adm.load_contact_floor(path)
    assert np.array_equal(back.contact_thresholds, c)
    mine = tmp_path / "mine.json"
    mine.write_text("{}")
    with pytest.raises(ValueError, match="not overwritten"):
        floor.save(mine)


def test_the_detector_is_quiet_in_free_motion_and_names_a_pushed_joint(baxter, ident_and_floor):
    ident, floor = ident_and_floor
    data = noisy(free_motion(baxter, 60.0, rate=200.0, seed=2, friction=0.3), 2)
    # A 15 N m push on joint 3 (applied to the arm) from 40 s to 42 s: the torque the
    # controller commands is that much less than the motion needs.
    push = np.zeros_like(data["tau"])
    pushed = (data["t"] >= 40.0) & (data["t"] < 42.0)
    push[pushed, 3] = 15.0
    tau = data["tau"] - push
    det = adm.ContactDetector(ident, floor)
    contact, link, events = [], [], 0
    for k in range(len(data["t"])):
        est = det.update(data["t"][k], data["q"][k], data["qdot"][k], data["qddot"][k], tau[k], 0.005)
        assert est.shape == (baxter.n,)
        events += int(det.contact and not (contact and contact[-1]))
        contact.append(det.contact)
        link.append(det.link)
    contact, link = np.array(contact), np.array(link)
    quiet = data["t"] >= 1.0
    assert not contact[quiet & (data["t"] < 40.0)].any(), "a false alarm in 39 s of free motion"
    during = (data["t"] >= 40.2) & (data["t"] < 42.0)
    assert contact[during].all()
    assert np.all(link[during] == 3)
    assert not contact[data["t"] >= 43.0].any()
    assert det.detect(np.zeros(baxter.n), np.zeros(baxter.n), np.zeros(baxter.n)) == (False, False, -1)


def test_an_admittance_with_the_floor_as_deadband_stays_put(baxter, ident_and_floor):
    _, floor = ident_and_floor
    d = floor.contact_thresholds
    adm_plain = adm.Admittance(baxter, 3.0, 5.0, rho=None)
    adm_band = adm.Admittance(baxter, 3.0, 5.0, rho=None, deadband=d)
    z = np.zeros(baxter.n)
    for _ in range(1000):
        q_plain = adm_plain.step(z, z, z, 0.9 * d, 1e-3)[0]
        q_band = adm_band.step(z, z, z, 0.9 * d, 1e-3)[0]
    assert np.all(q_band == 0.0) and np.all(np.abs(q_plain) > 0)
    with pytest.raises(ValueError, match="deadband"):
        adm.Admittance(baxter, 3.0, 5.0, deadband=-1.0)


def test_several_recordings_pool_into_one_floor_and_levels_follow_the_motion(baxter, ident_and_floor):
    ident, one = ident_and_floor
    first = noisy(free_motion(baxter, 60.0, rate=200.0, seed=3, friction=0.3), 3)
    second = noisy(free_motion(baxter, 60.0, rate=200.0, seed=4, friction=0.3), 4)
    floor = adm.calibrate_contact([first, second], ident)
    payload = __import__("json").loads(floor.to_json())
    assert payload["source"]["recordings"] == 2
    # Two recordings of 60 s, each less its first second.
    assert abs(payload["calibration"]["duration_s"] - 118.0) < 0.1
    # The detector's own levels: the standstill level at rest, one row per sample.
    n = baxter.n
    zero = np.zeros(n)
    assert np.allclose(floor.contact_levels(zero, zero), floor.contact_thresholds)
    qdot = np.tile(np.linspace(-1.0, 1.0, 5)[:, None], (1, n))
    levels = floor.contact_levels(qdot, np.zeros_like(qdot))
    assert levels.shape == (5, n) and np.all(levels > 0)
    low = floor.contact_thresholds * (1.0 - floor.moving_drop)
    assert np.all(levels >= low * (1 - 1e-12))
    with pytest.raises(ValueError, match="rows"):
        floor.contact_levels(qdot, np.zeros((4, n)))
    with pytest.raises(ValueError, match=r"data\[1\]"):
        adm.calibrate_contact([first, {"t": first["t"]}], ident)


def test_an_external_plant_gathers_contact_like_a_scenario(baxter, ident_and_floor):
    """`VariantRecorder(..., contact_floor=floor)`: the scenario runner's contact detection
    and scoring for a plant outside Rust (one gathering path for both)."""
    from test_closed_loop import DT, pd_config
    from conftest import Q0

    _, floor = ident_and_floor
    n = baxter.n
    kd = np.maximum(20.0 * np.diag(adm.crba(baxter, Q0)), 0.05)
    config = pd_config(n, {"kind": "oracle", "cutoff_hz": 20.0, "warmup": 0.1}, kd=kd)
    loop = adm.ClosedLoop(baxter, config, sensor_cutoff_hz=40.0)
    seconds = 1.5
    rec = adm.VariantRecorder("pushed", baxter, config, seconds, 0.2, decimation=5, contact_floor=floor)
    zeros = np.zeros(n)
    q, qdot, tau_ext = Q0.copy(), zeros.copy(), zeros.copy()
    for k in range(int(round(seconds / DT))):
        t = k * DT
        tau, _ = loop.step(t, q, None, Q0, zeros, zeros, tau_ext)
        # A half-sine of 15 N m peak on joint 3 from 0.8 s to 1.2 s: far above its level.
        size = 15.0 * np.sin(np.pi * (t - 0.8) / 0.4) if 0.8 <= t < 1.2 else 0.0
        tau_ext = np.where(np.arange(n) == 3, size, 0.0)
        qdot = qdot + DT * adm.aba(baxter, q, qdot, tau + tau_ext)
        q = q + DT * qdot
        assert rec.add(loop, q, qdot, tau_ext) is None
    rec.finish(loop)
    m = rec.metrics
    assert m["contact_pushes"] == 1 and m["contact_pushes_detected"] == 1
    assert m["contact_false_events"] == 0
    assert m["contact_isolation"] == 1.0
    with pytest.raises(ValueError, match="contact_floor"):
        small = adm.Model.from_urdf(str(__import__("conftest").BAXTER), base="base", tip="left_lower_elbow")
        adm.VariantRecorder("x", small, pd_config(small.n), 1.0, 0.5, contact_floor=floor)
