"""The co-simulation: free-motion data, training, the admittance experiment, metrics, and
the run folder.

What is Python here is the MuJoCo plant, the contact, the truth and the orchestration: each
variant steps the Rust loop (``adm.ClosedLoop``: sensor filter, observer stage with its
input filter, low-pass and warm-up, admittance model, PD), its metrics and health checks
(divergence) are the scenario runner's (``adm.VariantRecorder``), and its run folder is
written by the same Rust code as ``admittance run``'s (``adm.write_run_folder``). A
variant's control steps run in Rust (``adm.CosimStepper``, which calls MuJoCo's
``mj_step`` through its Python bindings), the same values as the Python loop
``run_variant_stepwise`` (issue 33, part 3)."""

from __future__ import annotations

import math
import pathlib
import tempfile
import time
from dataclasses import asdict, dataclass, field

import numpy as np

import admittance as adm
from admittance import _progress

from ._plant import Encoder, MujocoArm

VARIANTS = ["learned", "learned_friction", "momentum", "momentum_identified", "hybrid", "oracle"]


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
    # model: the baseline that knows no friction; momentum_identified runs on the
    # identification.
    hybrid_nominal: str = "identified"
    nodes: int = adm.DEFAULT_NODES
    friction_scale: float = 1.0
    seed: int = 1
    dt: float = 1e-3
    sensor_cutoff_hz: float = 40.0
    input_filter_hz: float = 10.0
    estimate_cutoff_hz: float = 5.0
    warmup: float | None = None  # s; None: the loop's own default (observer.warmup)
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
        # t: a time, or a vector of times (then one row per time).
        t = np.asarray(t, dtype=float)[..., None, None]
        w = 2 * math.pi / periods
        s = q0 + np.sum(amps * np.sin(w * t + phases), axis=-1)
        v = np.sum(amps * w * np.cos(w * t + phases), axis=-1)
        a = -np.sum(amps * w * w * np.sin(w * t + phases), axis=-1)
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
    # A simulation: the URDF's whole limits, not the conservative envelope for a real arm.
    e = adm.excitation(m, period, seed=seed, period=period, rate_hz=1.0 / dt,
                       range=float("inf"), velocity_fraction=1.0, acceleration_fraction=1.0)
    q, v, a = (np.asarray(e[k]) for k in ("q", "qdot", "qddot"))
    per = len(q) - 1

    def at(t):
        # t: a time, or a vector of times (then one row per time); rint: round()'s ties.
        k = np.rint(np.asarray(t, dtype=float) / dt).astype(np.int64)
        k = k % per if period < duration else np.minimum(k, per)
        return q[k], v[k], a[k]

    return at


def record_free_motion(arm, m, q0, pd_config, cfg, rng, duration, stepwise=False):
    """Free motion under PD + nominal gravity on the excitation (``cfg.training_motion``:
    ``"excitation"``, the default, or ``"multisine"``): the sensor signals, as a dict for
    ``adm.train``. The steps run in Rust (``adm.FreeMotionStepper``, a simulated second per
    call), or with ``stepwise`` as a Python loop (``_record_stepwise``, the same values)."""
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
    rows = {k: np.zeros((steps, n)) for k in ("q", "qdot", "qddot", "tau")}
    t_col = np.arange(steps) * cfg.dt
    label = f"free motion: {duration:.0f} s in MuJoCo"
    if stepwise:
        _record_stepwise(arm, m, pd_config, cfg, rng, desired, rows, steps, label)
    else:
        encoder = Encoder()
        stepper = adm.FreeMotionStepper(
            m, pd_config, arm.stepper_plant(), dt=cfg.dt, sensor_cutoff_hz=cfg.sensor_cutoff_hz,
            rate_hz=1.0 / cfg.dt, resolution=encoder.resolution, out=rows,
        )
        for start in _progress.steps(range(0, steps, STEPPER_CHUNK), label):
            end = min(start + STEPPER_CHUNK, steps)
            # The plan of this stretch, as the Python loop computes it step by step.
            q_d, qdot_d, qddot_d = (np.ascontiguousarray(x) for x in desired(t_col[start:end]))
            stepper.run(start, q_d, qdot_d, qddot_d, encoder.noise(rng, end - start, n))
    data = {"t": t_col, **rows}
    return data


def _record_stepwise(arm, m, pd_config, cfg, rng, desired, rows, steps, label):
    """``record_free_motion``'s steps as a Python loop, into ``rows``."""
    n = m.n
    ctl = adm.PdController(m, pd_config)
    sensors = Sensors(n, cfg, rng)
    tau = np.zeros(n)
    zeros = np.zeros(n)
    for k in _progress.steps(range(steps), label):
        t = k * cfg.dt
        q, qdot, qddot, tau_f = sensors.sample(arm.q(), tau)
        rows["q"][k], rows["qdot"][k], rows["qddot"][k], rows["tau"][k] = q, qdot, qddot, tau_f
        qd, vd, ad = desired(t)
        tau = np.array(ctl.step(t, sensors.q_meas, qdot, qd, vd, ad, zeros, cfg.dt))
        arm.step(tau)
        if not np.all(np.isfinite(arm.q())):
            raise RuntimeError(f"the free-motion recording diverged at t = {t:.3f} s")


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


#: The co-simulation's bound on the hand's distance from its reference (m; health rule
#: ``hand_error``, see ``scenario_as_run``).
HAND_ERROR_BOUND = 0.1
#: Metrics are taken from here to the end (s), as a scenario's ``evaluation_start``.
EVALUATION_START = 2.0
#: One row of ``VARIANT.csv`` every this many control steps (a scenario's ``output.decimation``).
DECIMATION = 10
#: The loop's observer kind of each variant.
OBSERVER_KIND = {
    "learned": "learned",
    "learned_friction": "learned",
    "momentum": "momentum",
    "momentum_identified": "momentum",
    "hybrid": "hybrid",
    "oracle": "oracle",
}


def loop_config(variant, cfg, m, q0, pd, identification_file=None):
    """The loop of a variant as a scenario's tables (``[controller]``, ``[admittance]``,
    ``[observer]``): PD on the compliant reference, the admittance model of experiment B on
    joint 1 (the others stiff), and the variant's observer; ``identification_file``: the
    identified arm that ``momentum_identified`` and the identified hybrid run on."""
    n = m.n
    identified = identification_file is not None and variant in ("momentum_identified", "hybrid")
    stiff = [1e4] * (n - 1)
    return {
        "control_rate_hz": 1.0 / cfg.dt,
        "controller": {"kind": "pd", "pd": pd, "subtract_estimate": False},
        "admittance": {
            "damping": [cfg.admittance_damping] + stiff,
            "stiffness": [cfg.admittance_stiffness] + stiff,
            "saturation": {
                "rho": 0.95,
                "centre": [float(x) for x in q0],
                "half_range": [cfg.saturation_half_range] + [math.inf] * (n - 1),
            },
        },
        "observer": {
            "kind": OBSERVER_KIND[variant],
            "nominal_inertia_scale": 1.0 if identified else cfg.nominal_inertia_scale,
            **({"identification": str(identification_file)} if identified else {}),
            "cutoff_hz": cfg.estimate_cutoff_hz,
            "input_filter_hz": cfg.input_filter_hz,
            **({"warmup": cfg.warmup} if cfg.warmup is not None else {}),
            "momentum": {"gain": cfg.momentum_gain},
        },
    }


#: Control steps per call into ``adm.CosimStepper`` (one simulated second at 1 kHz): the
#: progress bar and Ctrl-C get a turn between calls.
STEPPER_CHUNK = 1000


def run_variant(variant, arm, m, nets, q0, pd, cfg, rng, contact, identification_file=None, stepwise=False):
    """One variant of the admittance experiment: the Rust loop against the MuJoCo arm, every
    step gathered by a ``VariantRecorder``; returns the finished recorder and the wall and
    this thread's CPU time (s) of the stepping. The steps run in Rust (``adm.CosimStepper``: the same values as
    the Python loop, one call per second simulated), or with ``stepwise`` one Python
    iteration per step (``run_variant_stepwise``, the reference the tests compare with)."""
    n = m.n
    dt = cfg.dt
    steps = int(round(cfg.duration / dt))
    if variant == "momentum_identified" and identification_file is None:
        raise ValueError("momentum_identified needs the identification (hybrid_nominal = \"identified\")")
    config = loop_config(variant, cfg, m, q0, pd, identification_file)
    net = nets.get(variant)
    closed_loop = adm.ClosedLoop(m, config, net, sensor_cutoff_hz=cfg.sensor_cutoff_hz)
    recorder = adm.VariantRecorder(variant, m, config, cfg.duration, EVALUATION_START, DECIMATION)
    desired = experiment_motion(q0)
    arm.set_q(q0)
    label = f"{variant}: {cfg.duration:.0f} s with the admittance loop"
    started, cpu_started = time.perf_counter(), time.thread_time()
    if stepwise:
        run_variant_stepwise(closed_loop, recorder, arm, desired, contact, rng, steps, dt, label)
    else:
        _run_in_rust(closed_loop, recorder, arm, desired, contact, rng, steps, dt, n, label)
    seconds, cpu_seconds = time.perf_counter() - started, time.thread_time() - cpu_started
    recorder.finish(closed_loop, net)
    return recorder, seconds, cpu_seconds


def run_variant_stepwise(closed_loop, recorder, arm, desired, contact, rng, steps, dt, label):
    """The variant's control steps as a Python loop: read the encoder, step the loop, apply
    the command and the push, step MuJoCo, gather (what ``adm.CosimStepper`` does in
    Rust)."""
    encoder = Encoder()
    tau_ext = np.zeros(closed_loop.n)  # MuJoCo's external torque of the last step (the oracle's input)
    out = (np.zeros(closed_loop.n), np.zeros(closed_loop.n))
    for k in _progress.steps(range(steps), label):
        t = k * dt
        q_d, qdot_d, qddot_d = desired(t)
        # The command held over the period that just ended is the loop's own (tau=None).
        tau, _ = closed_loop.step(t, encoder.read(arm.q(), rng), None, q_d, qdot_d, qddot_d,
                                  tau_ext, out=out)
        force = contact.push(t) if contact.push is not None else None
        tau_ext = arm.step(tau, force)
        if recorder.add(closed_loop, arm.q(), arm.qdot(), tau_ext) is not None:
            break  # diverged: the scenario runner's health rules


def _run_in_rust(closed_loop, recorder, arm, desired, contact, rng, steps, dt, n, label):
    """The control steps through ``adm.CosimStepper``: the desired motion, the encoder's
    noise and the push planned for every step with the stepwise loop's own expressions
    (``desired`` on a column of times, the noise drawn in one go, ``contact.push(t)``), then
    the steps in Rust a second at a time."""
    encoder = Encoder()
    times = np.arange(steps) * dt
    q_d, qdot_d, qddot_d = (np.ascontiguousarray(np.broadcast_to(a, (steps, n))) for a in desired(times[:, None]))
    push = np.zeros((steps, 3))
    push_on = [False] * steps
    if contact.push is not None:
        for k in range(steps):
            f = contact.push(k * dt)
            if f is not None:
                push[k], push_on[k] = f, True
    stepper = adm.CosimStepper(
        closed_loop, recorder, arm.stepper_plant(), dt=dt, q_d=q_d, qdot_d=qdot_d, qddot_d=qddot_d,
        noise=encoder.noise(rng, steps, n), resolution=encoder.resolution, push=push, push_on=push_on,
    )
    for start in _progress.steps(range(0, steps, STEPPER_CHUNK), label):
        if stepper.run(start, min(start + STEPPER_CHUNK, steps)) is not None:
            break  # diverged: the scenario runner's health rules


def variant_metrics(recorder, seconds, cpu_seconds):
    """The variant's metrics (the scenario runner's, computed in Rust) and the speed of its
    co-simulation: by the wall clock, and by the stepping thread's CPU time (``cosim_cpu_*``;
    on a shared machine the wall clock counts other processes' turns too)."""
    metrics = dict(recorder.metrics)
    metrics["cosim_seconds"] = seconds
    metrics["cosim_steps_per_second"] = recorder.steps / max(seconds, 1e-9)
    metrics["cosim_cpu_seconds"] = cpu_seconds
    metrics["cosim_cpu_steps_per_second"] = recorder.steps / max(cpu_seconds, 1e-9)
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


def _delayed_torque(data):
    """Free-motion data as the Rust recorder pairs it (docs/outputs.md): the filtered command
    one sample late, matching ``qddot``'s delay; the loop feeds its learned observers so."""
    tau = data["tau"]
    data["tau"] = np.vstack([np.zeros((1, tau.shape[1])), tau[:-1]])
    return data


def scenario_as_run(cfg, m, tip, q0, pd):
    """The co-simulation as a scenario file's keys (``scenario.toml`` of the run folder: it
    loads as a scenario); what a scenario cannot say of MuJoCo is in ``summary.json``'s
    ``cosim``."""
    config = loop_config("momentum", cfg, m, q0, pd)
    observer = dict(config.pop("observer"))
    observer.pop("kind")
    config.pop("control_rate_hz")  # plant.control_rate_hz in a scenario file
    encoder = Encoder()
    variants = {}
    identified = getattr(cfg, "hybrid_nominal", "identified") == "identified"
    for variant in cfg.variants:
        spec = {"kind": OBSERVER_KIND[variant]}
        if variant in ("learned", "learned_friction", "hybrid", "momentum_identified"):
            spec["training"] = {
                "data": "free_motion.csv",
                "validation": "free_motion_validation.csv",
                "nodes": cfg.nodes,
                "friction_features": variant != "learned",
                "seed": cfg.seed,
                "width_scale": cfg.width_scale,
                "cache": False,
            }
        if variant == "momentum_identified" or (variant == "hybrid" and identified):
            spec["nominal_inertia_scale"] = 1.0
            spec["training"]["identify"] = True
        variants[variant] = {"observer": spec}
    return {
        "name": f"mujoco_{pathlib.Path(cfg.urdf).stem}",
        "description": "Experiment B on the MuJoCo plant (python -m admittance.mujoco); plant, contact and truth are MuJoCo's",
        "duration": cfg.duration,
        "evaluation_start": EVALUATION_START,
        "seed": cfg.seed,
        "arm": {"urdf": str(pathlib.Path(cfg.urdf).resolve()), "base": cfg.base, "tip": tip},
        "plant": {
            "control_rate_hz": 1.0 / cfg.dt,
            "sensors": {
                "counts_per_rev": encoder.counts,
                "noise_std": encoder.noise_std,
                "seed": cfg.seed + 7,
                "filter_cutoff_hz": cfg.sensor_cutoff_hz,
            },
        },
        "output": {"decimation": DECIMATION},
        # The tracking PD is soft by design (Kd = 20 I): under a 10 N push the hand leaves its
        # compliant reference by about 6.5 cm even with the true torque (the oracle), so the
        # scenarios' 4 cm bound would fail every variant; 10 cm still catches an arm that
        # does not track.
        "health": {"max_hand_error": HAND_ERROR_BOUND},
        **config,
        "observer": observer,
        "variants": variants,
    }


def write_run_folder(out, cfg, m, tip, q0, pd, recorders, extra):
    """Writes the run folder with the Rust writer of ``admittance run`` (atomic; the same
    files, metrics and ``scenario.toml``); returns ``(summary, failures)``."""
    return adm.write_run_folder(
        str(out), scenario_as_run(cfg, m, tip, q0, pd), recorders, extra, force=cfg.force,
        protect=str(pathlib.Path(cfg.urdf).resolve()),
        header="The MuJoCo co-simulation as run (python -m admittance.mujoco); plant: mujoco",
    )


def run_cosimulation(cfg: CosimConfig, log=print):
    """The whole co-simulation; returns the summary dict (also in ``cfg.out``) with the
    ``failures`` (a divergence, a metric not finite)."""
    out = pathlib.Path(cfg.out)
    adm.check_out_dir(str(out), force=cfg.force, protect=str(pathlib.Path(cfg.urdf).resolve()))
    urdf_text = pathlib.Path(cfg.urdf).read_text()
    m = adm.Model.from_urdf(cfg.urdf, base=cfg.base, tip=cfg.tip)
    tip = cfg.tip or m.tip_link  # without --tip, the CLI's rule (Model.from_urdf above)
    rng = np.random.default_rng(cfg.seed)
    q0 = home_pose(m)
    pd = pd_gains(m, q0)
    m_nominal = m.with_scaled_inertias(cfg.nominal_inertia_scale)
    probe = MujocoArm(urdf_text, m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale)
    contact = plan_contact(cfg, m, q0, probe)
    needs_training = any(
        v in ("learned", "learned_friction", "hybrid", "momentum_identified") for v in cfg.variants
    )
    nets = {}
    if needs_training:
        started = time.perf_counter()
        data = record_free_motion(probe, m, q0, pd, cfg, rng, cfg.training_duration)
        validation = record_free_motion(probe, m, q0, pd, cfg, np.random.default_rng(cfg.seed + 1000), cfg.validation_duration)
        data, validation = _delayed_torque(data), _delayed_torque(validation)
        log(f"free-motion data: {cfg.training_duration:.0f} s + {cfg.validation_duration:.0f} s of validation in {time.perf_counter() - started:.1f} s")
        with _progress.spinner(f"training the networks ({cfg.nodes} nodes each) and the identification"):
            nets = train_networks(m, m_nominal, data, validation, cfg)
        for name, net in nets.items():
            log(f"{name}: validation NRMSE {np.round(net.validation_nrmse, 3).tolist()}")
    recorders = []
    speed = {}
    # The loop reads an identification from its file (as a robot program does).
    scratch = tempfile.TemporaryDirectory(prefix="admittance-cosim-")
    identification_file = None
    if getattr(nets, "identification", None) is not None:
        identification_file = pathlib.Path(scratch.name) / "identification.json"
        nets.identification.save(str(identification_file))
    for variant in cfg.variants:
        arm = MujocoArm(urdf_text, m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale, contact.wall)
        recorder, seconds, cpu_seconds = run_variant(
            variant, arm, m, nets, q0, pd, cfg, np.random.default_rng(cfg.seed + 7), contact, identification_file
        )
        metrics = variant_metrics(recorder, seconds, cpu_seconds)
        recorders.append(recorder)
        speed[variant] = {k: v for k, v in metrics.items() if k.startswith("cosim_")}
        log(
            f"{variant}: external-torque NRMSE {metrics['external_torque_nrmse']}, bound violations "
            f"{metrics['reference_bound_violations']}, {recorder.steps} steps in {seconds:.1f} s "
            f"({metrics['cosim_steps_per_second']:.0f} steps/s; {metrics['cosim_cpu_steps_per_second']:.0f} per CPU second)"
        )
    settings = {k: v for k, v in asdict(cfg).items() if v is not None and k not in ("force",)}
    extra = {
        "plant": "mujoco",
        "pose": q0.tolist(),
        "contact": contact.kind,
        "unknown_joint_terms": probe.terms,
        "cosim": {"settings": settings, "speed": speed},
    }
    summary, failures = write_run_folder(out, cfg, m, tip, q0, pd, recorders, extra)
    summary["failures"] = failures
    return summary
