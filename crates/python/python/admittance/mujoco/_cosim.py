"""The co-simulation: free-motion data, training, the admittance experiment, metrics, and
the run folder."""

from __future__ import annotations

import json
import math
import os
import pathlib
import shutil
import tempfile
import time
from dataclasses import asdict, dataclass, field

import numpy as np

import admittance as adm

from ._plant import Encoder, MujocoArm

VARIANTS = ["learned", "learned_friction", "momentum", "hybrid", "oracle"]


@dataclass
class CosimConfig:
    """Every setting of a co-simulation (``python -m admittance.mujoco --help``)."""

    urdf: str
    base: str | None = None
    tip: str | None = None
    out: str = "runs/mujoco"
    contact: str = "push"  # or "wall"
    duration: float = 30.0
    training_duration: float = 450.0
    validation_duration: float = 90.0
    # The free-motion recordings' desired motion: "excitation" (adm.excitation, the optimised
    # motion of `admittance excite`, a seed drawn from each recording's generator) or
    # "multisine" (the hand-made multi-sine about the pose, before issue 22).
    training_motion: str = "excitation"
    # The hybrid observer's model: "identified" (adm.identify on the training recording,
    # settings chosen on the validation recording; the residual network learns what the
    # identification leaves: the recipe of docs/experiments.md) or "nominal" (the URDF with
    # nominal_inertia_scale, as before issue 22). The momentum variant stays on the nominal
    # model: the baseline that knows no friction.
    hybrid_nominal: str = "identified"
    nodes: int = 1000
    friction_scale: float = 1.0
    seed: int = 1
    dt: float = 1e-3
    sensor_cutoff_hz: float = 40.0
    input_filter_hz: float = 10.0
    estimate_cutoff_hz: float = 5.0
    warmup: float = 0.5
    nominal_inertia_scale: float = 0.8
    momentum_gain: float = 50.0
    admittance_damping: float = 10.0
    admittance_stiffness: float = 5.0
    saturation_half_range: float = 1.1
    push_force: float = 10.0
    width_scale: float = 2.0
    force: bool = False
    variants: list = field(default_factory=lambda: list(VARIANTS))


class Sensors:
    """What the robot's driver gives: quantised, noisy angles, and the torque commanded, both
    through the same low-pass (so that their delays match) with the angle differentiated
    twice, as the Rust sensors do (``sensor_cutoff_hz``)."""

    def __init__(self, n, cfg, rng):
        self.encoder = Encoder()
        self.filter = adm.InputConditioner(n, cfg.sensor_cutoff_hz, 1.0 / cfg.dt)
        self.rng = rng
        self.q_meas = np.zeros(n)

    def sample(self, q_true, tau_cmd):
        self.q_meas = self.encoder.read(q_true, self.rng)
        return self.filter.update(self.q_meas, tau_cmd)


def pd_gains(m, q0):
    """PD gains from the arm's own inertia at the pose (the armature is unknown to it):
    Kd = 20 I (a 20 rad/s velocity loop), Kp = 10 Kd, with nominal gravity compensation."""
    inertia = np.diag(adm.crba(m, q0))
    kd = np.maximum(20.0 * inertia, 0.05)
    kp = 10.0 * kd
    return {"kp": kp.tolist(), "kd": kd.tolist(), "gravity_compensation": True}


def _multisine(m, q0, rng, duration, dt, spread=0.6):
    """A multi-sine per joint inside the joint limits (and under 60 % of the velocity
    limits) around ``q0``: two incommensurate sines each."""
    n = m.n
    lo, hi = np.array(m.lower), np.array(m.upper)
    vmax = np.array(m.velocity_limit)
    amps, periods, phases = [], [], []
    for j in range(n):
        room = min(q0[j] - lo[j], hi[j] - q0[j]) if np.isfinite(lo[j]) and np.isfinite(hi[j]) else 1.5
        a_total = max(0.05, min(spread * room, 1.5))
        ps = rng.uniform(4.0, 16.0, 2)
        a = np.array([0.65, 0.35]) * a_total
        v_peak = float(np.sum(a * 2 * math.pi / ps))
        limit = 0.6 * (vmax[j] if np.isfinite(vmax[j]) and vmax[j] > 0 else 2.0)
        if v_peak > limit:
            a *= limit / v_peak
        amps.append(a)
        periods.append(ps)
        phases.append(rng.uniform(0, 2 * math.pi, 2))
    amps, periods, phases = map(np.array, (amps, periods, phases))

    def at(t):
        w = 2 * math.pi / periods
        s = q0 + np.sum(amps * np.sin(w * t + phases), axis=1)
        v = np.sum(amps * w * np.cos(w * t + phases), axis=1)
        a = -np.sum(amps * w * w * np.sin(w * t + phases), axis=1)
        return s, v, a

    return at


def _excitation(m, rng, duration, dt):
    """``adm.excitation`` (the optimised motion of ``admittance excite``) sampled at the
    control rate, with a seed drawn from ``rng``; ``at(t)`` as ``_multisine``'s."""
    seed = int(rng.integers(1, 2**31 - 1))
    # The excitation repeats equal periods of at most 10 s (adm.excitation's rule): one
    # period is optimised and sampled, then repeated (equal to the whole to 1e-14; a long
    # recording does not wait minutes for 1 kHz samples, nor Ctrl-C with it).
    period = duration / max(math.ceil(duration / 10.0), 1)
    steps = period / dt
    if abs(steps - round(steps)) > 1e-6:
        period = duration  # periods of a fractional number of steps: all of it
    e = adm.excitation(m, period, seed=seed, period=period, rate_hz=1.0 / dt)
    q, v, a = (np.asarray(e[k]) for k in ("q", "qdot", "qddot"))
    per = len(q) - 1

    def at(t):
        k = int(round(t / dt))
        k = k % per if period < duration else min(k, per)
        return q[k], v[k], a[k]

    return at


def record_free_motion(arm, m, q0, pd_config, cfg, rng, duration):
    """Free motion under PD + nominal gravity on the excitation (``cfg.training_motion``:
    ``"excitation"``, the default, or ``"multisine"``): the sensor signals, as a dict for
    ``adm.train``."""
    n = m.n
    steps = int(round(duration / cfg.dt))
    motion = getattr(cfg, "training_motion", "excitation")
    if motion == "excitation":
        desired = _excitation(m, rng, duration, cfg.dt)
    elif motion == "multisine":
        desired = _multisine(m, q0, rng, duration, cfg.dt)
    else:
        raise ValueError(f"training_motion {motion!r}: choose \"excitation\" or \"multisine\"")
    arm.set_q(desired(0.0)[0])
    ctl = adm.PdController(m, pd_config)
    sensors = Sensors(n, cfg, rng)
    tau = np.zeros(n)
    rows = {k: np.zeros((steps, n)) for k in ("q", "qdot", "qddot", "tau")}
    t_col = np.arange(steps) * cfg.dt
    zeros = np.zeros(n)
    for k in range(steps):
        t = k * cfg.dt
        q, qdot, qddot, tau_f = sensors.sample(arm.q(), tau)
        rows["q"][k], rows["qdot"][k], rows["qddot"][k], rows["tau"][k] = q, qdot, qddot, tau_f
        qd, vd, ad = desired(t)
        tau = np.array(ctl.step(t, sensors.q_meas, qdot, qd, vd, ad, zeros, cfg.dt))
        arm.step(tau)
        if not np.all(np.isfinite(arm.q())):
            raise RuntimeError(f"the free-motion recording diverged at t = {t:.3f} s")
    data = {"t": t_col, **rows}
    return data


def home_pose(m):
    """The middle of each joint's range (0 without limits)."""
    lo, hi = np.array(m.lower), np.array(m.upper)
    return np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), 0.0)


class Networks(dict):
    """The networks by variant name; ``identification``: the identified arm the hybrid's
    residual was trained on (``None``: the nominal model)."""

    identification = None


def train_networks(m, m_nominal, data, validation, cfg):
    """The three networks of experiment B: the paper's (no friction inputs), with
    friction-shaped inputs, and the hybrid's residual on the identification (or on the
    nominal model, ``cfg.hybrid_nominal``)."""
    hybrid_nominal = getattr(cfg, "hybrid_nominal", "identified")
    if hybrid_nominal not in ("identified", "nominal"):
        raise ValueError(f"hybrid_nominal {hybrid_nominal!r}: choose \"identified\" or \"nominal\"")
    identification = None
    if hybrid_nominal == "identified":
        identification = adm.identify(data, m, validation=validation, input_filter_hz=cfg.input_filter_hz)
    common = dict(
        input_filter_hz=cfg.input_filter_hz,
        validation=validation,
        seed=cfg.seed,
        width_scale=cfg.width_scale,
    )
    nets = Networks(
        learned=adm.train(data, m, cfg.nodes, **common),
        learned_friction=adm.train(data, m, cfg.nodes, friction_features=True, **common),
        hybrid=adm.train(
            data, m, cfg.nodes, friction_features=True, nominal=m_nominal if identification is None else identification, **common
        ),
    )
    nets.identification = identification
    return nets


def make_observer(variant, m_nominal, nets, cfg):
    if variant in ("learned", "learned_friction"):
        return adm.LearnedObserver(nets[variant])
    if variant == "momentum":
        return adm.MomentumObserver(m_nominal, gain=cfg.momentum_gain)
    if variant == "hybrid":
        # On the model its residual network was trained on.
        identification = getattr(nets, "identification", None)
        nominal = m_nominal if identification is None else identification
        return adm.HybridObserver(nominal, nets["hybrid"], gain=cfg.momentum_gain)
    return None  # oracle


def experiment_motion(q0):
    """The desired motion of the experiment: joint 1 = 0.5 sin(2 pi t / 12) about the pose
    (the joint with the admittance, as s0 in experiment B) and every other joint on a slow
    0.1 rad sine (periods 9-15 s), so that no joint rests in static friction, which no
    observer can tell from a contact (the plant's joint friction is unknown to them)."""
    n = len(q0)
    amps = np.array([0.5] + [0.1] * (n - 1))
    periods = np.array([12.0] + [9.0 + 6.0 * j / max(n - 2, 1) for j in range(n - 1)])
    w = 2 * math.pi / periods

    def at(t):
        return q0 + amps * np.sin(w * t), amps * w * np.cos(w * t), -amps * w * w * np.sin(w * t)

    return at


def push_profile(cfg, direction, magnitude):
    """The scripted push at the hand: from 8 s to 22 s a force along ``direction`` that
    swells and reverses (``magnitude sin(2 pi (t - 8) / 7)``, smooth at both ends)."""
    t0, t1 = 8.0, 22.0

    def at(t):
        if t < t0 or t > t1:
            return None
        return magnitude * math.sin(2 * math.pi * (t - t0) / 7.0) * direction

    return at, (t0, t1)


def run_variant(variant, arm, m, m_nominal, nets, q0, pd, cfg, rng, contact):
    """One variant of the admittance experiment; returns its series and status."""
    n = m.n
    dt = cfg.dt
    steps = int(round(cfg.duration / dt))
    big = [1e4] * n
    damping = [cfg.admittance_damping] + big[1:]
    stiffness = [cfg.admittance_stiffness] + big[1:]
    half = [cfg.saturation_half_range] + [math.inf] * (n - 1)
    adm_config = {
        "damping": damping,
        "stiffness": stiffness,
        "saturation": {"rho": 0.95, "centre": q0.tolist(), "half_range": half},
    }
    admittance = adm.Admittance.from_config(m, adm_config)
    reference = adm.Admittance.from_config(m, adm_config)  # driven by the true torque
    ctl = adm.PdController(m, pd)
    observer = make_observer(variant, m_nominal, nets, cfg)
    conditioner = adm.InputConditioner(n, cfg.input_filter_hz, 1.0 / dt)
    sensors = Sensors(n, cfg, rng)
    alpha = dt / (dt + 1.0 / (2 * math.pi * cfg.estimate_cutoff_hz))
    desired = experiment_motion(q0)
    arm.set_q(q0)
    tau = np.zeros(n)
    estimate = np.zeros(n)
    tau_ext = np.zeros(n)
    efforts = np.array(m.effort_limit)
    decimation = 10
    rows = []
    series = {k: [] for k in ("q_d", "q_r", "q", "qdot", "q_meas", "tau_cmd", "tau_ext", "tau_ext_hat", "q_r_ref")}
    diverged_at = None
    reason = None
    torque_violations = 0
    observer_faults = 0
    started = time.perf_counter()
    for k in range(steps):
        t = k * dt
        q_f, qdot_f, qddot_f, tau_f = sensors.sample(arm.q(), tau)
        # The estimate: the observer on the conditioned signals, low-passed, zero in warm-up.
        if observer is None:
            raw = tau_ext
        else:
            q_c, qdot_c, qddot_c, tau_c = conditioner.update(q_f, tau_f)
            raw = np.array(observer.update(t, q_c, qdot_c, qddot_c, tau_c, dt))
            if observer.fault is not None:
                observer_faults += 1
        if t < cfg.warmup and observer is not None:
            raw = np.zeros(n)
        estimate += alpha * (raw - estimate)
        q_d, v_d, a_d = desired(t)
        q_r, qdot_r, qddot_r = admittance.step(q_d, v_d, a_d, estimate, dt)
        q_r_ref = reference.step(q_d, v_d, a_d, tau_ext, dt)[0]
        tau = np.array(ctl.step(t, sensors.q_meas, qdot_f, q_r, qdot_r, qddot_r, np.zeros(n), dt))
        torque_violations += int(np.sum(np.abs(tau) > efforts * (1 + 1e-9)))
        force = contact.push(t) if contact.push is not None else None
        tau_ext = arm.step(tau, force)
        q_true = arm.q()
        if k % decimation == 0:
            for key, value in (
                ("q_d", q_d), ("q_r", np.array(q_r)), ("q", q_true), ("qdot", arm.qdot()),
                ("q_meas", sensors.q_meas), ("tau_cmd", tau), ("tau_ext", tau_ext),
                ("tau_ext_hat", estimate.copy()), ("q_r_ref", np.array(q_r_ref)),
            ):
                series[key].append(np.array(value, dtype=float))
            rows.append(t)
        if not np.all(np.isfinite(q_true)) or np.any(np.abs(q_true) > 1e3):
            diverged_at, reason = t, "the MuJoCo plant's angles left physical bounds"
        elif not np.all(np.isfinite(estimate)) or np.any(np.abs(estimate) > 10 * efforts):
            diverged_at, reason = t, "the external-torque estimate exceeded 10 x the effort limit"
        if diverged_at is not None:
            break
    seconds = time.perf_counter() - started
    out = {k: np.array(v) for k, v in series.items()}
    out["t"] = np.array(rows)
    return out, {
        "diverged_at": diverged_at,
        "reason": reason,
        "torque_limit_violations": torque_violations,
        "faults": int(ctl.fault_count),
        "observer_faults": observer_faults,
        "steps": k + 1,
        "seconds": seconds,
    }


def variant_metrics(series, status, cfg, validation_nrmse=None, m=None):
    """The metrics of experiment B under the same names and definitions (docs/outputs.md)."""
    t = series["t"]
    window = t >= 2.0
    true, hat = series["tau_ext"][window], series["tau_ext_hat"][window]
    touching = np.abs(true) > 1e-9
    in_contact = touching.any(axis=1)
    joints = touching.any(axis=0)
    err = (hat - true)[np.ix_(in_contact, joints)]
    denominator = float(np.sum(true[np.ix_(in_contact, joints)] ** 2))
    nrmse = math.sqrt(float(np.sum(err ** 2)) / denominator) if denominator > 0 else None
    false_rms = [
        float(np.sqrt(np.mean(hat[~touching[:, j], j] ** 2))) if np.any(~touching[:, j]) else 0.0
        for j in range(hat.shape[1])
    ]
    half = cfg.saturation_half_range
    centre = series["q_d"][0, 0] if len(series["q_d"]) else 0.0
    q_r = series["q_r"]
    violations = int(np.sum(np.abs(q_r[:, 0] - centre) >= half))
    metrics = {
        "diverged": status["diverged_at"] is not None,
        "diverged_at": status["diverged_at"],
        "external_torque_nrmse": nrmse,
        "external_torque_rmse": np.sqrt(np.mean((hat - true) ** 2, axis=0)).tolist(),
        "false_torque_rms": false_rms,
        "reference_bound_violations": violations,
        "admittance_error_rms": np.sqrt(np.mean((series["q_r"][window] - series["q_r_ref"][window]) ** 2, axis=0)).tolist(),
        "tracking_rmse": np.sqrt(np.mean((series["q_r"][window] - series["q"][window]) ** 2, axis=0)).tolist(),
        "torque_limit_violations": status["torque_limit_violations"],
        "faults": status["faults"],
        "observer_faults": status["observer_faults"],
        "steps": status["steps"],
        "cosim_seconds": status["seconds"],
        "cosim_steps_per_second": status["steps"] / max(status["seconds"], 1e-9),
    }
    if m is not None:
        lo, hi, effort = np.array(m.lower), np.array(m.upper), np.array(m.effort_limit)
        q = series["q"]
        metrics["q_limit_violation_fraction"] = np.mean((q < lo) | (q > hi), axis=0).tolist()
        metrics["torque_saturation_fraction"] = np.mean(
            np.abs(series["tau_cmd"]) >= effort * (1 - 1e-9), axis=0
        ).tolist()
    if validation_nrmse is not None:
        metrics["validation_nrmse"] = list(validation_nrmse)
    return metrics


@dataclass
class Contact:
    """How the world touches the hand: a scripted push (``push(t)`` -> force or None) or a
    wall (a MuJoCo box: ``wall = (centre, half_sizes, normal)``)."""

    kind: str
    push: object = None
    wall: tuple | None = None
    window: tuple = (0.0, 0.0)


def plan_contact(cfg, m, q0, probe):
    """The push or the wall for this arm, from its hand's position at the pose (``probe``:
    a MuJoCo arm without the wall)."""
    probe.set_q(q0)
    p0 = probe.tip_position()
    lever = np.array([p0[0], p0[1], 0.0])
    if np.linalg.norm(lever) < 0.05:
        lever = np.array([1.0, 0.0, 0.0])
    tangent = np.cross([0.0, 0.0, 1.0], lever)
    tangent /= np.linalg.norm(tangent)
    if cfg.contact == "push":
        push, window = push_profile(cfg, tangent, cfg.push_force)
        return Contact("push", push=push, window=window)
    # The wall: where joint 1 at +0.3 rad from the pose puts the hand, facing it.
    q = q0.copy()
    q[0] += 0.3
    probe.set_q(q)
    p = probe.tip_position()
    lever = np.array([p[0], p[1], 0.0])
    tangent = np.cross([0.0, 0.0, 1.0], lever)
    tangent /= np.linalg.norm(tangent)
    thickness = 0.02
    centre = p + tangent * (0.02 + thickness)  # the tip sphere (2 cm) touches the face
    return Contact("wall", wall=(centre.tolist(), [0.3, 0.3, thickness], (-tangent).tolist()), window=(0.0, cfg.duration))


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return "inf" if v == math.inf else ("-inf" if v == -math.inf else repr(float(v)) if isinstance(v, float) else str(v))
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return json.dumps(str(v))


def _check_out(out: pathlib.Path, force: bool):
    """The CLI's rule: ``out`` may be new, empty, or a run folder this tool wrote."""
    if not out.exists():
        return
    if not out.is_dir():
        raise SystemExit(f"admittance.mujoco: --out {out}: is not a folder; choose another path (nothing was written)")
    if not any(out.iterdir()):
        return
    try:
        marker = json.loads((out / "summary.json").read_text()).get("format")
    except (OSError, ValueError):
        marker = None
    if marker != "admittance-run" and not force:
        raise SystemExit(
            f"admittance.mujoco: --out {out}: is a folder this tool did not write (no summary.json "
            "with \"format\": \"admittance-run\"); choose another folder, or pass --force to replace it"
        )


def write_run_folder(out, cfg, m, results, summary):
    """Writes the run folder atomically: a hidden sibling, renamed into place at the end."""
    out = pathlib.Path(out)
    parent = out.parent
    parent.mkdir(parents=True, exist_ok=True)
    partial = pathlib.Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-{os.getpid()}-", dir=parent))
    partial.chmod(0o777 & ~_umask())  # mkdtemp makes it 0700; a run folder is an ordinary one
    (partial / ".admittance-partial").write_text("")
    joints = m.joint_names
    for variant, (series, _) in results.items():
        cols = ["t"]
        blocks = [series["t"][:, None]]
        for prefix in ("q_d", "q_r", "q", "qdot", "q_meas", "tau_cmd", "tau_ext", "tau_ext_hat"):
            cols += [f"{prefix}.{j}" for j in joints]
            blocks.append(series[prefix])
        cols += [f"tau_applied.{j}" for j in joints]
        blocks.append(series["tau_cmd"])
        table = np.hstack(blocks)
        with open(partial / f"{variant}.csv", "w") as f:
            f.write(",".join(cols) + "\n")
            np.savetxt(f, table, delimiter=",", fmt="%.17g")
    (partial / "summary.json").write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    lines = [
        f"# The MuJoCo co-simulation as run (python -m admittance.mujoco); plant: mujoco",
        f"name = {_toml_value(summary['scenario'])}",
        f"duration = {_toml_value(cfg.duration)}",
        "evaluation_start = 2.0",
        "",
        "[arm]",
        f"urdf = {_toml_value(str(pathlib.Path(cfg.urdf).resolve()))}",
    ]
    if cfg.base:
        lines.append(f"base = {_toml_value(cfg.base)}")
    if cfg.tip:
        lines.append(f"tip = {_toml_value(cfg.tip)}")
    n = m.n
    lines += [
        "",
        "[admittance]",
        f"damping = {_toml_value([cfg.admittance_damping] + [1e4] * (n - 1))}",
        f"stiffness = {_toml_value([cfg.admittance_stiffness] + [1e4] * (n - 1))}",
        "",
        "[admittance.saturation]",
        "rho = 0.95",
        f"centre = {_toml_value(summary['pose'])}",
        f"half_range = {_toml_value([cfg.saturation_half_range] + [math.inf] * (n - 1))}",
        "",
        "[cosim]",
    ]
    for k, v in asdict(cfg).items():
        if v is not None and k not in ("urdf", "base", "tip"):
            lines.append(f"{k} = {_toml_value(v)}")
    (partial / "scenario.toml").write_text("\n".join(lines) + "\n")
    (partial / ".admittance-partial").unlink()
    if out.exists():
        old = parent / f".{out.name}.old-{os.getpid()}"
        out.rename(old)
        partial.rename(out)
        shutil.rmtree(old)
    else:
        partial.rename(out)


def _umask():
    """The process's umask (read by setting it, then restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def run_cosimulation(cfg: CosimConfig, log=print):
    """The whole co-simulation; returns the summary dict (also in ``cfg.out``)."""
    out = pathlib.Path(cfg.out)
    _check_out(out, cfg.force)
    urdf_text = pathlib.Path(cfg.urdf).read_text()
    m = adm.Model.from_urdf(cfg.urdf, base=cfg.base, tip=cfg.tip)
    n = m.n
    tip = cfg.tip or m.tip_link  # without --tip, the CLI's rule (Model.from_urdf above)
    rng = np.random.default_rng(cfg.seed)
    q0 = home_pose(m)
    pd = pd_gains(m, q0)
    m_nominal = m.with_scaled_inertias(cfg.nominal_inertia_scale)
    probe = MujocoArm(urdf_text, m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale)
    contact = plan_contact(cfg, m, q0, probe)
    needs_training = any(v in ("learned", "learned_friction", "hybrid") for v in cfg.variants)
    nets = {}
    train_seconds = 0.0
    if needs_training:
        started = time.perf_counter()
        data = record_free_motion(probe, m, q0, pd, cfg, rng, cfg.training_duration)
        validation = record_free_motion(probe, m, q0, pd, cfg, np.random.default_rng(cfg.seed + 1000), cfg.validation_duration)
        log(f"free-motion data: {cfg.training_duration:.0f} s + {cfg.validation_duration:.0f} s of validation in {time.perf_counter() - started:.1f} s")
        started = time.perf_counter()
        nets = train_networks(m, m_nominal, data, validation, cfg)
        train_seconds = time.perf_counter() - started
        for name, net in nets.items():
            log(f"{name}: validation NRMSE {np.round(net.validation_nrmse, 3).tolist()}")
    results = {}
    variants = {}
    failures = []
    for variant in cfg.variants:
        arm = MujocoArm(urdf_text, m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale, contact.wall)
        series, status = run_variant(variant, arm, m, m_nominal, nets, q0, pd, cfg, np.random.default_rng(cfg.seed + 7), contact)
        metrics = variant_metrics(
            series, status, cfg, nets[variant].validation_nrmse if variant in nets else None, m
        )
        if variant in nets:
            metrics["train_seconds"] = train_seconds / len(nets)
        results[variant] = (series, status)
        variants[variant] = metrics
        log(
            f"{variant}: external-torque NRMSE {metrics['external_torque_nrmse']}, bound violations "
            f"{metrics['reference_bound_violations']}, {status['steps']} steps in {status['seconds']:.1f} s "
            f"({metrics['cosim_steps_per_second']:.0f} steps/s)"
        )
        if status["diverged_at"] is not None:
            failures.append(f"variant `{variant}` diverged at t = {status['diverged_at']:.3f} s: {status['reason']}")
    summary = {
        "format": "admittance-run",
        "format_version": 1,
        "scenario": f"mujoco_{pathlib.Path(cfg.urdf).stem}",
        "plant": "mujoco",
        "joints": m.joint_names,
        "variants": dict(sorted(variants.items())),
        "variant_order": list(cfg.variants),
        "pose": q0.tolist(),
        "contact": contact.kind,
        "unknown_joint_terms": probe.terms,
    }
    _check_finite(summary, failures)
    write_run_folder(out, cfg, m, results, summary)
    summary["failures"] = failures
    return summary


def _check_finite(summary, failures):
    for name, metrics in summary["variants"].items():
        for key, value in metrics.items():
            values = value if isinstance(value, list) else [value]
            for v in values:
                if isinstance(v, float) and not math.isfinite(v):
                    failures.append(f"variant `{name}`: {key} is not finite")
                    metrics[key] = None
                    break
