"""``python -m admittance.mujoco.payload``: a payload the identification never saw, identified
from 20 s of motion with it attached, on an example-robot-data arm in MuJoCo (issue 30, part 8;
docs/experiments.md, "Payload").

1. The arm without payload tracks 60 s of ``adm.excitation`` (seed 1) and 20 s of another
   (seed 3, the validation recording) under PD in MuJoCo, with the plant, sensors and input
   conditioning of ``python -m admittance.mujoco.arms`` (joint friction, damping and armature
   unknown to every model, a 16-bit noisy encoder, 40 Hz sensor filter, 10 Hz conditioning);
   ``adm.identify`` fits the arm on them.
2. A rigid payload (mass, centre of mass off the flange, a rotated inertia) is fixed to the
   tip link in the URDF MuJoCo loads; the arm tracks 20 s of a third excitation (seed 4) with
   it, and ``adm.identify_payload`` fits it on top of the identification (its first second,
   the PD settling under the new load, left out). The PD recording with the payload keeps, by
   default (``recording_pd="unloaded"``), the gains and gravity of the arm without it; with
   ``"loaded"`` it is the robot's controller told of its load, as after libfranka's
   ``setLoad`` or UR's ``set_payload``: its gains tuned by the same rule on the arm carrying
   it, and the payload's gravity compensated.
3. Judged on a fourth excitation (seed 5), recorded with and without the payload, against
   the floor (the identification's own false torque on the recording without it), in two
   ways:
   - the estimate's false torque (the bar): the default estimator, the momentum observer on
     ``ident.with_payload(p)`` (``K_O`` and warm-up of the arms table) through the loop's
     estimate low-pass (``estimate_cutoff_hz``), rms over joints in free motion, as
     ``python -m admittance.mujoco.arms`` scores it;
   - the inverse-dynamics residual: the conditioned torque minus ``predict`` from the
     conditioned motion, its measured acceleration included.

Bars (issue 30): mass within 5 %, centre of mass within 1 cm, the estimate's false torque
with the payload model within 10 % of the floor.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, field

import numpy as np

import admittance as adm

#: The payload of the default run: 1.5 kg, its centre of mass 8.8 cm from the flange, an
#: inertia about it with principal moments (kg m^2) turned by ``rpy`` from the tip axes.
DEFAULT_PAYLOAD = {
    "mass": 1.5,
    "com": [0.02, -0.03, 0.08],
    "principal_inertia": [0.004, 0.003, 0.002],
    "rpy": [0.2, -0.1, 0.3],
}


@dataclass
class PayloadConfig:
    """Every setting of the payload run (``python -m admittance.mujoco.payload --help``)."""

    arm: str = "panda"
    training_duration: float = 60.0
    validation_duration: float = 20.0
    payload_duration: float = 20.0
    evaluation_duration: float = 20.0
    payload: dict = field(default_factory=lambda: dict(DEFAULT_PAYLOAD))
    seed: int = 1  # sensor noise
    dt: float = 1e-3
    sensor_cutoff_hz: float = 40.0
    input_filter_hz: float = 10.0
    friction_scale: float = 1.0
    estimate_cutoff_hz: float = 10.0  # the estimate's low-pass (the arms table's choice on the Panda)
    momentum_gain: float = 50.0  # K_O of the momentum observer (the arms table's)
    warmup: float = 1.0  # s left out of every false torque (the filters settle)
    recording_pd: str = "unloaded"  # the PD with the payload: "unloaded" (as without it) or "loaded" (told of it)


def rpy_matrix(roll, pitch, yaw):
    """The URDF's ``rpy`` rotation (fixed axes x, y, z)."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def true_payload(payload):
    """The payload as ``identify_payload`` reports it: mass, centre of mass (tip frame) and the
    inertia about it in tip axes."""
    r = rpy_matrix(*payload["rpy"])
    inertia = r @ np.diag(payload["principal_inertia"]) @ r.T
    return float(payload["mass"]), np.array(payload["com"], float), inertia


def urdf_with_payload(text, tip_link, payload):
    """The URDF with a link ``payload`` fixed to ``tip_link`` at its origin: the payload's mass,
    centre of mass and principal inertia turned by ``rpy`` (its ``<inertial>``)."""
    root = ET.fromstring(text)
    link = ET.SubElement(root, "link", {"name": "payload"})
    inertial = ET.SubElement(link, "inertial")
    com = " ".join(repr(float(v)) for v in payload["com"])
    rpy = " ".join(repr(float(v)) for v in payload["rpy"])
    ET.SubElement(inertial, "origin", {"xyz": com, "rpy": rpy})
    ET.SubElement(inertial, "mass", {"value": repr(float(payload["mass"]))})
    ixx, iyy, izz = (repr(float(v)) for v in payload["principal_inertia"])
    ET.SubElement(inertial, "inertia", {"ixx": ixx, "iyy": iyy, "izz": izz, "ixy": "0", "ixz": "0", "iyz": "0"})
    joint = ET.SubElement(root, "joint", {"name": "payload_fixed", "type": "fixed"})
    ET.SubElement(joint, "parent", {"link": tip_link})
    ET.SubElement(joint, "child", {"link": "payload"})
    ET.SubElement(joint, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})
    return ET.tostring(root, encoding="unicode")


def false_torque(ident, cond, cfg):
    """Rms over joints and samples (after the warm-up) of the conditioned torque minus what
    ``ident`` predicts from the conditioned motion (N m), each joint's torque paired with the
    motion as the identification was fitted (its ``delay_s``: the torque that much later)."""
    start = int(round(cfg.warmup / cfg.dt))
    tau = np.asarray(cond["tau"], dtype=float)
    k = np.arange(len(tau), dtype=float)
    for i, d in enumerate(ident.summary.get("delay_s") or []):
        if d:
            tau[:, i] = np.interp(np.clip(k + d / cfg.dt, 0, len(tau) - 1), k, tau[:, i])
    predicted = np.asarray(ident.predict(cond["q"][start:], cond["qdot"][start:], cond["qddot"][start:]))
    return float(np.sqrt(np.mean((tau[start:] - predicted) ** 2)))


def estimate_after_warmup(ident, cond, cfg):
    """The default estimator's output in free motion after the warm-up (samples x joints,
    N m): the momentum observer on ``ident`` (``momentum_gain``), on the conditioned signals,
    through the loop's estimate low-pass, as the arms table runs it."""
    from ._arms import ArmsConfig, lowpass, raw_estimate

    arms_cfg = ArmsConfig(dt=cfg.dt, estimate_cutoff_hz=cfg.estimate_cutoff_hz, warmup=cfg.warmup, momentum_gain=cfg.momentum_gain)
    hat = lowpass(raw_estimate(adm.MomentumObserver(ident, gain=cfg.momentum_gain), cond, arms_cfg), arms_cfg)
    return hat[int(round(cfg.warmup / cfg.dt)) :]


def estimate_false_torque(ident, cond, cfg):
    """Rms over joints of :func:`estimate_after_warmup` (N m)."""
    return float(np.sqrt(np.mean(estimate_after_warmup(ident, cond, cfg) ** 2)))


#: Below this speed (rad/s, the conditioned velocity) a joint is reversing or held by its dry
#: friction, whose torque there is anything up to its Coulomb level: no curve of the velocity
#: gives it.
SLOW_RAD_S = 0.01


def estimate_by_speed(ident, cond, cfg):
    """Where the estimate's false torque is, per joint: the share of samples after the
    warm-up with ``|q'| < SLOW_RAD_S`` and the rms there and elsewhere (N m)."""
    hat = estimate_after_warmup(ident, cond, cfg)
    slow = np.abs(np.asarray(cond["qdot"], dtype=float)[int(round(cfg.warmup / cfg.dt)) :]) < SLOW_RAD_S

    def rms(x):
        return float(np.sqrt(np.mean(x**2))) if x.size else 0.0

    return {
        "slow_share": slow.mean(axis=0).tolist(),
        "slow_rms": [rms(hat[slow[:, j], j]) for j in range(hat.shape[1])],
        "elsewhere_rms": [rms(hat[~slow[:, j], j]) for j in range(hat.shape[1])],
    }


def run_payload(cfg: PayloadConfig, robots=None, log=print):
    """The run of the module doc: the numbers as a dict."""
    from ._arms import ARMS, conditioned, excitation_motion, record, recording_gains, robots_dir
    from ._plant import MujocoArm

    if cfg.recording_pd not in ("loaded", "unloaded"):
        raise ValueError(f"recording_pd {cfg.recording_pd!r}: must be 'unloaded' or 'loaded'")
    robots = robots or robots_dir()
    rel, base, tip = ARMS[cfg.arm]
    path = robots / rel
    m = adm.Model.from_urdf(str(path), base=base, tip=tip)
    tip = tip or m.tip_link
    text = path.read_text()
    plain = MujocoArm(text, m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale)
    loaded = MujocoArm(urdf_with_payload(text, tip, cfg.payload), m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale)
    motions = {
        name: excitation_motion(m, duration, seed, cfg.dt)[0]
        for name, duration, seed in (
            ("training", cfg.training_duration, 1),
            ("validation", cfg.validation_duration, 3),
            ("payload", cfg.payload_duration, 4),
            ("evaluation", cfg.evaluation_duration, 5),
        )
    }
    mean_pose = motions["training"]["q"].mean(axis=0)
    gains = recording_gains(m, mean_pose, plain.terms)
    # The controller recording with the payload: told of it (the same tuning rule on the arm
    # carrying it, and its gravity), or left as it was without it.
    pd_model, pd_gains = m, gains
    if cfg.recording_pd == "loaded":
        pd_model = adm.Model.from_urdf_string(urdf_with_payload(text, tip, cfg.payload), base=base, tip=tip)
        pd_gains = recording_gains(pd_model, mean_pose, loaded.terms)
    rng = np.random.default_rng(cfg.seed)
    log(f"{cfg.arm}: recording in MuJoCo")
    train = record(plain, m, motions["training"], gains, cfg, rng)[0]
    valid = record(plain, m, motions["validation"], gains, cfg, rng)[0]
    with_tool, _, tracking_payload = record(loaded, pd_model, motions["payload"], pd_gains, cfg, rng)
    eval_plain, _, tracking_plain = record(plain, m, motions["evaluation"], gains, cfg, rng)
    eval_tool, _, tracking_tool = record(loaded, pd_model, motions["evaluation"], pd_gains, cfg, rng)
    ident = adm.identify(train, m, validation=valid, input_filter_hz=cfg.input_filter_hz)
    # The first second is the arm settling under the new load, which no model here describes
    # (the filters' lag on a jerk); the fit takes the rest.
    p = adm.identify_payload(with_tool, ident, from_s=cfg.warmup)
    carried = ident.with_payload(p)
    mass, com, inertia = true_payload(cfg.payload)
    cond_plain, cond_tool = conditioned(eval_plain, cfg), conditioned(eval_tool, cfg)
    floor = false_torque(ident, cond_plain, cfg)
    with_model = false_torque(carried, cond_tool, cfg)
    without_model = false_torque(ident, cond_tool, cfg)
    truth = ident.with_payload(adm.Payload(mass, com, inertia))
    true_model = false_torque(truth, cond_tool, cfg)
    estimate = {
        "floor": estimate_false_torque(ident, cond_plain, cfg),
        "with_payload_model": estimate_false_torque(carried, cond_tool, cfg),
        "without_payload_model": estimate_false_torque(ident, cond_tool, cfg),
        "with_true_payload": estimate_false_torque(truth, cond_tool, cfg),
    }
    estimate["ratio_to_floor"] = estimate["with_payload_model"] / estimate["floor"]
    estimate["by_speed"] = {
        "slow_rad_s": SLOW_RAD_S,
        "floor": estimate_by_speed(ident, cond_plain, cfg),
        "with_payload_model": estimate_by_speed(carried, cond_tool, cfg),
    }
    out = {
        "arm": cfg.arm,
        "tip": tip,
        "config": asdict(cfg),
        "true": {"mass": mass, "com": com.tolist(), "inertia": inertia.tolist()},
        "identified": {"mass": p.mass, "com": np.asarray(p.com).tolist(), "inertia": np.asarray(p.inertia).tolist()},
        "mass_error_relative": abs(p.mass - mass) / mass,
        "com_error_m": float(np.linalg.norm(np.asarray(p.com) - com)),
        "inertia_error_kg_m2": float(np.linalg.norm(np.asarray(p.inertia) - inertia)),
        "estimate_false_torque": estimate,
        "false_torque_floor": floor,
        "false_torque_with_payload_model": with_model,
        "false_torque_without_payload_model": without_model,
        "false_torque_with_true_payload": true_model,
        "ratio_to_floor": with_model / floor,
        "identification_input_filter_hz": ident.summary.get("input_filter_hz"),
        # rms of the true angle's distance from the planned one, per joint (rad)
        "tracking_rms_rad": {
            "evaluation_without_payload": tracking_plain.tolist(),
            "evaluation_with_payload": tracking_tool.tolist(),
            "payload_recording": tracking_payload.tolist(),
        },
    }
    out["bars"] = {
        "mass within 5 %": out["mass_error_relative"] <= 0.05,
        "com within 1 cm": out["com_error_m"] <= 0.01,
        "the estimate's false torque within 10 % of the floor": estimate["ratio_to_floor"] <= 1.10,
    }
    return out


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m admittance.mujoco.payload",
        description="A payload the identification never saw, identified from 20 s with it attached, on an "
        "example-robot-data arm in MuJoCo; prints the errors and the false torque against the floor.",
    )
    p.add_argument("--arm", default="panda", help="an arm of `python -m admittance.mujoco.arms --list` (panda)")
    p.add_argument("--mass", type=float, default=DEFAULT_PAYLOAD["mass"], help="payload mass, kg (1.5)")
    p.add_argument("--com", default=",".join(map(str, DEFAULT_PAYLOAD["com"])), help="centre of mass in the tip frame, m (0.02,-0.03,0.08)")
    p.add_argument("--training-duration", type=float, default=60.0)
    p.add_argument("--payload-duration", type=float, default=20.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--input-filter-hz", type=float, default=10.0, help="the input conditioning's cut-off, Hz (10, as the arms table; 0: raw signals)")
    p.add_argument(
        "--recording-pd",
        choices=("unloaded", "loaded"),
        default="unloaded",
        help="the PD recording with the payload: as without it (the default) or told of it (gains tuned on "
        "the arm carrying it, its gravity compensated, as after setLoad)",
    )
    p.add_argument("--out", help="write the numbers to this JSON file")
    a = p.parse_args(argv)
    try:
        import mujoco  # noqa: F401
    except ImportError:
        print("admittance.mujoco.payload: needs MuJoCo: pip install './crates/python[mujoco]'", file=sys.stderr)
        return 2
    payload = dict(DEFAULT_PAYLOAD, mass=a.mass, com=[float(v) for v in a.com.split(",")])
    if len(payload["com"]) != 3 or not a.mass > 0:
        p.error("--com needs three numbers and --mass a positive number")
    if not (math.isfinite(a.input_filter_hz) and a.input_filter_hz >= 0):
        p.error("--input-filter-hz needs a cut-off >= 0 Hz (0: raw signals)")
    cfg = PayloadConfig(
        arm=a.arm,
        training_duration=a.training_duration,
        payload_duration=a.payload_duration,
        payload=payload,
        seed=a.seed,
        input_filter_hz=a.input_filter_hz,
        recording_pd=a.recording_pd,
    )
    r = run_payload(cfg, log=lambda s: print(s, file=sys.stderr))
    print(f"{r['arm']} (tip {r['tip']}): payload {r['true']['mass']:.3f} kg identified as {r['identified']['mass']:.4f} kg "
          f"({100 * r['mass_error_relative']:.2f} %), centre of mass off by {100 * r['com_error_m']:.2f} cm")
    e = r["estimate_false_torque"]
    print(f"the estimate's false torque on other motion (momentum observer, rms, N m): floor without payload {e['floor']:.3f}; "
          f"with the payload: payload model {e['with_payload_model']:.3f} (ratio {e['ratio_to_floor']:.3f}), "
          f"identification alone {e['without_payload_model']:.3f}, the true payload {e['with_true_payload']:.3f}")
    slow = e["by_speed"]
    loaded, floor = slow["with_payload_model"], slow["floor"]
    grown = [loaded["slow_share"][j] * loaded["slow_rms"][j] ** 2 + (1 - loaded["slow_share"][j]) * loaded["elsewhere_rms"][j] ** 2
             - floor["slow_share"][j] * floor["slow_rms"][j] ** 2 - (1 - floor["slow_share"][j]) * floor["elsewhere_rms"][j] ** 2
             for j in range(len(floor["slow_rms"]))]
    j = int(np.argmax(grown))
    print(f"  joint {j + 1}, whose estimate grows most: |q'| < {slow['slow_rad_s']} rad/s on {100 * loaded['slow_share'][j]:.1f} % of the samples, "
          f"{loaded['slow_rms'][j]:.3f} N m there and {loaded['elsewhere_rms'][j]:.3f} elsewhere with the payload model "
          f"(floor: {100 * floor['slow_share'][j]:.1f} %, {floor['slow_rms'][j]:.3f} and {floor['elsewhere_rms'][j]:.3f})")
    print(f"inverse-dynamics residual on other motion (rms, N m): floor without payload {r['false_torque_floor']:.3f}; with the payload: "
          f"payload model {r['false_torque_with_payload_model']:.3f} (ratio {r['ratio_to_floor']:.3f}), "
          f"identification alone {r['false_torque_without_payload_model']:.3f}, the true payload {r['false_torque_with_true_payload']:.3f}")
    for bar, ok in r["bars"].items():
        print(f"  {'pass' if ok else 'FAIL'}  {bar}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump(r, f, indent=2)
    return 0 if all(r["bars"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())
