"""The payload (issue 30, part 8): `adm.identify_payload` on top of an identification, in
MuJoCo with a payload the identification never saw (`python -m admittance.mujoco.payload`
shortened), and the identification carrying it saved into a file every consumer loads."""

import importlib.metadata
import json

import numpy as np
import pytest

import admittance as adm

pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco)")
try:
    importlib.metadata.distribution("example-robot-data")
except importlib.metadata.PackageNotFoundError:
    pytest.skip("example-robot-data is not installed (pip install example-robot-data==6.0.0)", allow_module_level=True)

from admittance.mujoco.payload import PayloadConfig, run_payload  # noqa: E402


@pytest.mark.parametrize("recording_pd", ["unloaded", "loaded"])
def test_a_payload_the_identification_never_saw_in_mujoco(recording_pd):
    # 2.5 kg, its centre of mass 9.9 cm from the flange (the bars: 0.5 to 3 kg, up to 10 cm).
    payload = {"mass": 2.5, "com": [-0.03, 0.04, 0.085], "principal_inertia": [0.006, 0.005, 0.003], "rpy": [0.4, 0.1, -0.3]}
    cfg = PayloadConfig(
        training_duration=30.0, validation_duration=10.0, evaluation_duration=10.0, payload=payload, recording_pd=recording_pd
    )
    r = run_payload(cfg, log=lambda s: None)
    # The PD told of the load tracks the wrist about as well as without payload; untold, the
    # load drags it more than twice as far.
    tracking = r["tracking_rms_rad"]
    wrist_with, wrist_without = (np.asarray(tracking[k])[4:6] for k in ("evaluation_with_payload", "evaluation_without_payload"))
    if recording_pd == "loaded":
        assert np.all(wrist_with < 1.5 * wrist_without), tracking
    else:
        assert np.all(wrist_with > 2.0 * wrist_without), tracking
    assert r["mass_error_relative"] <= 0.05, r
    assert r["com_error_m"] <= 0.01, r
    # The identification alone reads the payload as a large false torque; carrying the fitted
    # payload brings it near the floor without payload.
    assert r["false_torque_without_payload_model"] > 5.0 * r["false_torque_with_payload_model"], r
    assert r["ratio_to_floor"] <= 1.5, r
    # The same for the default estimator (the momentum observer on the identification).
    e = r["estimate_false_torque"]
    assert e["without_payload_model"] > 5.0 * e["with_payload_model"], e
    assert e["ratio_to_floor"] <= 1.5, e


def test_an_unknown_recording_pd_is_refused():
    with pytest.raises(ValueError, match="recording_pd 'told'"):
        run_payload(PayloadConfig(recording_pd="told"), log=lambda s: None)


def test_with_payload_saves_a_file_every_consumer_loads(tmp_path, baxter):
    m = baxter
    e = adm.excitation(m, 20.0, seed=2)
    truth = adm.Payload(1.2, [0.01, 0.02, 0.06], np.diag([0.003, 0.002, 0.002]))
    # The identification of the arm without the payload, and torques of the arm carrying it.
    q, v, a = e["q"], e["qdot"], e["qddot"]
    tau_plain = np.array([adm.rnea(m, q[k], v[k], a[k]) for k in range(len(q))])
    data_plain = {**e, "tau": tau_plain}
    other = adm.excitation(m, 10.0, seed=5)
    tau_other = np.array([adm.rnea(m, *row) for row in zip(other["q"], other["qdot"], other["qddot"])])
    # Exact accelerations: fitted as they are (the default low-pass would bend them slightly).
    base = adm.identify(
        data_plain, m, friction=False, validation={**other, "tau": tau_other}, fit_acceleration_hz=None
    )
    assert "fit_acceleration_hz" not in base.summary
    smoothed = adm.identify(data_plain, m, friction=False, validation={**other, "tau": tau_other})
    assert smoothed.summary["fit_acceleration_hz"] == adm.FIT_ACCELERATION_HZ
    # What the low-pass costs on exact data: a small fraction of a millinewton metre.
    assert max(smoothed.summary["expected_false_torque_rms"]) < 1e-4
    carrying = base.with_payload(truth)
    tau_tool = np.asarray(carrying.predict(q, v, a)) - np.asarray(base.predict(q, v, a)) + tau_plain
    p = adm.identify_payload({**e, "tau": tau_tool}, base)
    assert abs(p.mass - 1.2) < 1e-6 and np.allclose(p.com, [0.01, 0.02, 0.06], atol=1e-6)
    assert np.allclose(p.inertia, np.diag([0.003, 0.002, 0.002]), atol=1e-6)
    path = tmp_path / "with_tool.ident.json"
    base.with_payload(p).save(str(path))
    loaded = adm.load_identification(str(path), m)
    assert np.allclose(loaded.predict(q[:50], v[:50], a[:50]), carrying.predict(q[:50], v[:50], a[:50]), atol=1e-6)
    record = json.loads(path.read_text())["payload"]["data"]["payload"]
    assert abs(record["mass_kg"] - 1.2) < 1e-6 and record["frame"] == "left_hand"
    adm.MomentumObserver(loaded, gain=50.0)  # a consumer takes it
    with pytest.raises(ValueError, match="from_s"):
        adm.identify_payload({**e, "tau": tau_tool}, base, from_s=100.0)
