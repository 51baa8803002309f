"""`adm.identify` beside a plain least-squares fit on the same conditioned data (issue 30,
item 4: never worse than least squares).

Run through identify_vs_least_squares.sh (which makes the virtual environment and installs the
package). Per recording and input cut-off (raw signals, 4 Hz, 10 Hz):

1. The whole recording goes through the observers' input conditioning (`adm.InputConditioner`,
   as `adm.identify(data, m, input_filter_hz=f)` conditions its data); the training stretch is
   its first part, the scored stretch another part (or another recording) it never saw.
2. The project: `adm.identify(train, m, input_filter_hz=f)` (one recording, no validation
   recording: settings chosen as a user with one recording gets them), scored with
   `ident.predict` on the conditioned scored rows.
3. The baseline, plain least squares: Pinocchio's joint-torque regressor (10 inertial
   parameters per body) plus per joint a rotor inertia (q''), viscous friction (q'), two
   smooth Coulomb terms tanh(q'/w), tanh(q'/10w) (w = 0.01 rad/s, the project's default), an
   offset and q, sin q, cos q; every column scaled to unit rms, a fixed ridge of 1e-3 (relative
   to the rows) toward the URDF's inertial parameters and zero joint terms; one numpy solve.
   Nothing is bounded or tuned on the scored rows.
4. Printed per point: rms false torque (N m, all joints of the scored rows) of both, the ratio
   project / least squares (the bar: <= 1.0), and whether every fitted joint term of the
   project is physical (armature, viscous >= 0; a friction that opposes the velocity at every speed:
   coulomb[0] + coulomb[1] >= 0 and 10 coulomb[0] + coulomb[1] >= 0);
   then the geometric mean of the ratios (the bar: <= 0.9). With `--speed-flags`, also the share
   of scored rows where a joint moves faster than the identification's training speeds by more
   than `adm.TRAINING_SPEED_MARGIN` (what the run-time loop flags as faster_than_training) and
   both fits' rms on those joints' samples and on the rest. Where the identification's
   acceleration gain is below 1, also its rms predicting with that gain on every sample (the
   prediction raises it where the motion accelerates beyond the training's noise) and with
   the whole measured acceleration.

Recordings: the real Baxter recording (ADMITTANCE_DATA/baxter_rand/baxter_rand.csv: the first
120 s train, the last 30 s are scored) when it is found, and the example-robot-data arms of
`admittance.mujoco.arms` in MuJoCo (60 s of `adm.excitation(m, 60, seed=1)` train, 30 s of
other free motion, `seed=2`, are scored; the plant, sensors and PD of that table).
Your own arm's recording (`--recording CSV --urdf URDF [--base B --tip T]`: a free-motion CSV,
columns `t, q.J, qdot.J, qddot.J, tau.J` for the chain's joints, as `admittance import`
writes it; `qdot` and `qddot` may be left out, then taken by differences) instead: fitted
on `--train FROM,UNTIL` and scored on `--score FROM,UNTIL` (default: the last fifth scored,
the rest fitted), or scored on another recording of the arm
(`--score-recording CSV`); the stretches never overlap. Joints outside the chain are held at 0
in Pinocchio's model, whose regressor is checked against the project's RNEA first.
`--torque-scale F` multiplies every recorded torque by F, training and scored alike: a torque
signal of another size than the URDF's arm (a torque constant or gear ratio off).
`--drop-rows P` drops a random fraction P of the MuJoCo training recordings' rows (a logger
that lost samples; the time column keeps the true times of the rows left); the scored
recording stays whole, as a control loop's samples are.
`--link-torque` records, instead of the commanded torque, what a joint torque sensor on the
link side reads (`LinkTorqueSensor`: the rigid-body torque, a constant offset, white noise), as
torque-controlled arms log it.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import re
import sys
import time

import numpy as np

import admittance as adm

ROOT = pathlib.Path(__file__).resolve().parents[2]
CUTOFFS_HZ = (0.0, 4.0, 10.0)
#: --speed-flags: also split each point's scored samples at the identification's training speeds.
SPEED_FLAGS = False
COULOMB_WIDTH = 0.01  # rad/s, the plain fit's fixed width (identify chooses among COULOMB_WIDTH_CANDIDATES)
RIDGE_REL = 1e-3
JOINT_COLUMNS = 8  # q'', q', tanh(q'/w), tanh(q'/10w), 1, q, sin q, cos q


def pinocchio_chain(urdf, joint_names):
    """Pinocchio's model of the URDF reduced to the chain's joints (others locked at 0)."""
    import pinocchio as pin

    # Joints outside the chain become fixed (their bodies lumped at angle 0, as locking them
    # would; some URDFs name a frame twice, which buildReducedModel refuses).
    text = pathlib.Path(urdf).read_text()

    def fix(match):
        return match.group(0) if match.group(2) in joint_names else match.group(1) + "fixed" + match.group(3)

    text = re.sub(r'(<joint\b[^>]*?\bname="([^"]+)"[^>]*?\btype=")[^"]+(")', fix, text)
    text = re.sub(r'(<joint\b[^>]*?\btype=")[^"]+("[^>]*?\bname="([^"]+)")',
                  lambda m: m.group(0) if m.group(3) in joint_names else m.group(1) + "fixed" + m.group(2), text)
    model = pin.buildModelFromXML(text)
    kept = [model.names[i] for i in range(1, model.njoints)]
    if kept != list(joint_names) or model.nv != len(joint_names):
        raise SystemExit(f"{urdf}: Pinocchio's chain {kept} is not the project's {list(joint_names)}")
    return model


def pinocchio_q(pmodel, q):
    """Joint angles as Pinocchio's configuration: a continuous joint (2 coordinates) is
    ``(cos q, sin q)``."""
    parts = []
    for j in range(1, pmodel.njoints):
        a = q[:, j - 1 : j]
        parts.append(np.hstack([np.cos(a), np.sin(a)]) if pmodel.joints[j].nq == 2 else a)
    return np.hstack(parts)


def body_regressor(pmodel, q, qd, qdd):
    """Pinocchio's joint-torque regressor, rows stacked: ``(N n, 10 n)``."""
    import pinocchio as pin

    data = pmodel.createData()
    n = pmodel.nv
    qp = pinocchio_q(pmodel, np.asarray(q))
    out = np.empty((len(q) * n, 10 * n))
    for k in range(len(q)):
        out[k * n : (k + 1) * n] = pin.computeJointTorqueRegressor(pmodel, data, qp[k], qd[k], qdd[k])
    return out


def joint_regressor(q, qd, qdd):
    """The per-joint columns, rows stacked like ``body_regressor``: ``(N n, 8 n)``."""
    rows, n = q.shape
    out = np.zeros((rows, n, JOINT_COLUMNS * n))
    cols = np.stack(
        [
            qdd,
            qd,
            np.tanh(qd / COULOMB_WIDTH),
            np.tanh(qd / (10 * COULOMB_WIDTH)),
            np.ones_like(q),
            q,
            np.sin(q),
            np.cos(q),
        ],
        axis=2,
    )  # (N, n, 8)
    for j in range(n):
        out[:, j, JOINT_COLUMNS * j : JOINT_COLUMNS * (j + 1)] = cols[:, j, :]
    return out.reshape(rows * n, JOINT_COLUMNS * n)


class LeastSquares:
    """The plain baseline: one ridge-regularised linear solve toward the URDF."""

    def __init__(self, pmodel):
        self.pmodel = pmodel
        n = pmodel.nv
        urdf = np.concatenate([pmodel.inertias[j].toDynamicParameters() for j in range(1, n + 1)])
        self.prior = np.concatenate([urdf, np.zeros(JOINT_COLUMNS * n)])

    def regressor(self, q, qd, qdd):
        return np.hstack([body_regressor(self.pmodel, q, qd, qdd), joint_regressor(q, qd, qdd)])

    def fit(self, q, qd, qdd, tau):
        phi = self.regressor(q, qd, qdd)
        y = tau.reshape(-1)
        scale = np.sqrt(np.mean(phi**2, axis=0))
        scale[scale < 1e-9 * scale.max()] = 1.0  # a column that is zero: the ridge holds it
        a = phi / scale
        lam = RIDGE_REL * len(y)
        prior = self.prior * scale
        lhs = a.T @ a + lam * np.eye(a.shape[1])
        rhs = a.T @ y + lam * prior
        self.theta = np.linalg.solve(lhs, rhs) / scale
        return self

    def predict(self, q, qd, qdd):
        return (self.regressor(q, qd, qdd) @ self.theta).reshape(q.shape)

    def joint_terms(self):
        n = self.pmodel.nv
        c = self.theta[10 * n :].reshape(n, JOINT_COLUMNS)
        return [{"armature": r[0], "viscous": r[1], "coulomb": [r[2], r[3]]} for r in c]


def physical(terms):
    """Every joint's armature and viscous >= 0, coulomb[0] + coulomb[1] >= 0 and 10 coulomb[0] + coulomb[1] >= 0."""
    return all(
        t["armature"] >= 0 and t["viscous"] >= 0 and t["coulomb"][0] + t["coulomb"][1] >= -1e-9 and 10 * t["coulomb"][0] + t["coulomb"][1] >= -1e-9
        for t in terms
    )


def condition(data, hz):
    """The recording through ``adm.InputConditioner`` (``hz`` 0: the columns as recorded)."""
    if hz <= 0:
        return {k: np.asarray(data[k], dtype=float) for k in ("q", "qdot", "qddot", "tau")}
    n = data["q"].shape[1]
    t = np.asarray(data["t"])
    rate = (len(t) - 1) / (t[-1] - t[0])
    cond = adm.InputConditioner(n, hz, rate)
    out = {k: np.zeros_like(data["q"]) for k in ("q", "qdot", "qddot", "tau")}
    for k in range(len(t)):
        out["q"][k], out["qdot"][k], out["qddot"][k], out["tau"][k] = cond.update(data["q"][k], data["tau"][k])
    return out


def delay_torque(tau, delay_s, rate):
    """Each joint's torque ``delay_s[i]`` later (linear interpolation, held at the ends): the
    pairing an identification with those delays expects (``ConditionedSamples::delay_torque``)."""
    if not delay_s or all(d == 0 for d in delay_s):
        return tau
    k = np.arange(len(tau), dtype=float)
    return np.stack(
        [np.interp(np.clip(k + d * rate, 0, len(tau) - 1), k, tau[:, i]) for i, d in enumerate(delay_s)], axis=1
    )


def rows(data, mask):
    return {k: np.asarray(v)[mask] for k, v in data.items() if k in ("t", "q", "qdot", "qddot", "tau")}


def rms(x):
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


def compare(label, m, pmodel, train, scored, log):
    """Both fits at every cut-off: ``train`` and ``scored`` are raw recordings; ``scored``
    may carry ``score_mask`` (rows of it that are scored, after conditioning it whole)."""
    points = []
    for hz in CUTOFFS_HZ:
        t0 = time.perf_counter()
        ident = adm.identify(train, m, input_filter_hz=hz)
        seconds = time.perf_counter() - t0
        ct = condition(train, hz)
        cs = condition(scored["data"], hz)
        w = scored["mask"]
        q, qd, qdd, tau = (cs[k][w] for k in ("q", "qdot", "qddot", "tau"))
        # The identification is scored on the torque paired with the motion as it was fitted
        # (its delays, when it records any), as its consumers run it.
        t = np.asarray(scored["data"]["t"])
        delays = list(ident.summary.get("delay_s") or [])
        tau_id = delay_torque(cs["tau"], delays, (len(t) - 1) / (t[-1] - t[0]))[w]
        project = rms(tau_id - np.asarray(ident.predict(q, qd, qdd)))
        gain = ident.summary["acceleration_gain"]
        # The same identification predicting with the whole measured acceleration, and with
        # the gain chosen on the training motion everywhere (predict raises it where the
        # scored motion accelerates well beyond the training's noise).
        full = fixed = project
        if gain < 1.0:
            still, inertial = gain_variants(ident, q, qd, qdd)
            full, fixed = rms(tau_id - still - inertial), rms(tau_id - still - gain * inertial)
        ls = LeastSquares(pmodel).fit(ct["q"], ct["qdot"], ct["qddot"], ct["tau"])
        baseline = rms(tau - ls.predict(q, qd, qdd))
        summary = ident.summary
        faster = speed_flags(ident, qd, tau_id - np.asarray(ident.predict(q, qd, qdd)), tau - ls.predict(q, qd, qdd)) if SPEED_FLAGS else None
        point = {
            "recording": label,
            "input_filter_hz": hz,
            "project_rms": project,
            "least_squares_rms": baseline,
            "ratio": project / baseline,
            "project_physical": physical(ident.joint_terms),
            "least_squares_physical": physical(ls.joint_terms()),
            "identify_seconds": seconds,
            "chosen_input_filter_hz": summary.get("input_filter_hz"),
            "delay_s": summary.get("delay_s"),
            "prior_scale": summary.get("prior_scale"),
            "acceleration_gain": gain,
            "project_rms_whole_acceleration": full,
            "project_rms_fixed_gain": fixed,
        }
        if faster is not None:
            point["faster_than_training"] = faster
        log(
            f"{label:<28} {'raw' if hz == 0 else f'{hz:g} Hz':>6} {project:8.3f} {baseline:8.3f} {point['ratio']:7.3f}"
            f"  {'yes' if point['project_physical'] else 'NO':>8}  ({'yes' if point['least_squares_physical'] else 'no'})"
        )
        points.append(point)
        if gain < 1.0:
            log(f"    acceleration gain {gain:g}: with it everywhere {fixed:.3f} ({fixed / baseline:.3f} x least squares), "
                f"with the whole acceleration {full:.3f} ({full / baseline:.3f} x)")
        if faster is not None:
            log("    " + speed_flag_text(faster))
    return points


def gain_variants(ident, q, qd, qdd):
    """The identification's prediction without the acceleration and its whole inertial torque
    (``M q''`` and the rotor inertias): with a share ``g`` of ``q''`` it predicts
    ``still + g inertial``."""
    still = np.asarray(ident.predict(q, qd, np.zeros_like(qdd)))
    rotor = np.array([t["armature"] for t in ident.joint_terms])
    inertial = np.array([np.asarray(adm.crba(ident.model, a)) @ b for a, b in zip(q, qdd)])
    return still, inertial + rotor * qdd


def speed_flags(ident, qdot, error, baseline_error):
    """The scored samples (joint by joint) faster than the identification's training speeds
    by more than ``adm.TRAINING_SPEED_MARGIN`` (what the loop flags as faster_than_training)
    and the rest: their counts and summed squared errors of both fits, and the share of rows
    with a joint flagged."""
    top = np.asarray(ident.summary["training_speed"])
    faster = np.abs(qdot) > (1.0 + adm.TRAINING_SPEED_MARGIN) * top
    within = ~faster
    return {
        "rows": float(faster.any(axis=1).mean()),
        "samples": int(faster.sum()),
        "sq_identify": float((error[faster] ** 2).sum()),
        "sq_least_squares": float((baseline_error[faster] ** 2).sum()),
        "within_samples": int(within.sum()),
        "within_sq_identify": float((error[within] ** 2).sum()),
        "within_sq_least_squares": float((baseline_error[within] ** 2).sum()),
    }


def speed_flag_text(f):
    """One line: the share of rows flagged, and both fits' rms on the flagged and other samples."""
    r = lambda sq, k: f"{math.sqrt(sq / k):.3f}" if k else "-"
    return (f"faster than trained: {100 * f['rows']:.1f} % of the rows; rms identify / LS on those joints' samples "
            f"{r(f['sq_identify'], f['samples'])} / {r(f['sq_least_squares'], f['samples'])}, "
            f"on the rest {r(f['within_sq_identify'], f['within_samples'])} / {r(f['within_sq_least_squares'], f['within_samples'])}")


def scale_torque(data, factor):
    """``data`` with its torque column times ``factor``."""
    return {**data, "tau": np.asarray(data["tau"]) * factor} if factor != 1.0 else data


def load_recording(path, m):
    """A free-motion CSV (docs/outputs.md: columns ``t, q.J, qdot.J, qddot.J, tau.J`` for the
    chain's joints ``J``; ``admittance import`` writes it) as arrays; ``qdot`` or ``qddot``
    left out for every joint is taken by backward differences, the first rows dropped, as the
    project's loader does. A clear exit naming the file when it is not one."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise SystemExit(f"{path}: no such file")
    with path.open() as f:
        header = [name.strip() for name in f.readline().split(",")]
    col = {name: i for i, name in enumerate(header)}
    groups = {key: [f"{key}.{j}" for j in m.joint_names] for key in ("q", "qdot", "qddot", "tau")}
    derived = [key for key in ("qdot", "qddot") if not any(name in col for name in groups[key])]
    wanted = ["t"] + [name for key, names in groups.items() if key not in derived for name in names]
    missing = [name for name in wanted if name not in col]
    if missing:
        raise SystemExit(
            f"{path}: line 1: no column '{missing[0]}' ({len(missing)} missing); the columns are t, q.J, tau.J "
            f"and qdot.J, qddot.J (or neither, then taken by differences) for the chain's joints J: "
            f"{', '.join(m.joint_names)} (--base, --tip)"
        )
    try:
        table = np.loadtxt(path, delimiter=",", skiprows=1, usecols=[col[name] for name in wanted], ndmin=2)
    except ValueError as e:
        raise SystemExit(f"{path}: {e} (every row needs a number in each of the chain's columns)")
    t = table[:, 0]
    if len(t) < 3 or not np.all(np.isfinite(table)):
        raise SystemExit(f"{path}: {len(t)} rows{'' if len(t) < 3 else ', some not finite'}: needs a recording of finite numbers")
    backwards = np.flatnonzero(np.diff(t) <= 0)
    if backwards.size:
        raise SystemExit(f"{path}: line {backwards[0] + 3}: time {t[backwards[0] + 1]:g} s does not come after {t[backwards[0]]:g} s")
    n = m.n
    data, k = {"t": t}, 1
    for key in ("q", "qdot", "qddot", "tau"):
        if key in derived:
            source = data["q"] if key == "qdot" else data["qdot"]
            data[key] = np.vstack([np.full((1, n), np.nan), np.diff(source, axis=0) / np.diff(t)[:, None]])
        else:
            data[key], k = table[:, k : k + n], k + n
    dropped = len(derived)  # a row per derivative taken in turn
    if derived:
        print(f"{path}: no {' and '.join(derived)} columns: taken as backward differences, the first {dropped} rows dropped")
    return {key: value[dropped:] for key, value in data.items()}


def recording_points(log, urdf, m, path, train_s=None, score_s=None, score_path=None, torque_scale=1.0, label=None, data=None):
    """A real recording (a free-motion CSV of ``m``, the chain of ``urdf``; ``data``: its
    arrays when already read): fitted on ``train_s`` = [from, until) s (default: all but the
    last fifth, or the whole recording when another one is scored), scored on ``score_s`` of
    ``score_path`` (default: the same recording's last fifth, or the whole other recording);
    never on rows the fit saw."""
    data = scale_torque(load_recording(path, m) if data is None else data, torque_scale)
    t = data["t"]
    scored = data if score_path is None else scale_torque(load_recording(score_path, m), torque_scale)
    ts = scored["t"]
    if score_path is None and train_s is None and score_s is None:
        cut = t[0] + 0.8 * (t[-1] - t[0])
        train_s, score_s = (t[0], cut), (cut, t[-1] + 1.0)
    if train_s is None:
        train_s = (t[0], t[-1] + 1.0) if score_path is not None else (t[0], score_s[0])
    if score_s is None:
        score_s = (ts[0], ts[-1] + 1.0) if score_path is not None else (train_s[1], t[-1] + 1.0)
    train_mask = (t >= train_s[0]) & (t < train_s[1])
    mask = (ts >= score_s[0]) & (ts < score_s[1])
    for rows_, what, flag in ((train_mask, "fitted", "train"), (mask, "scored", "score")):
        if rows_.sum() < 100:
            raise SystemExit(f"--{flag}: {int(rows_.sum())} rows {what} (at least 100); the recording runs {t[0]:g}-{t[-1]:g} s")
    same_file = score_path is None or pathlib.Path(score_path).resolve() == pathlib.Path(path).resolve()
    if same_file and np.any(mask & (ts >= train_s[0]) & (ts < train_s[1])):
        raise SystemExit("the fitted and scored stretches overlap: score on motion the fit never saw")
    if label is None:
        name = pathlib.Path(path).name
        other = "" if score_path is None else f"{pathlib.Path(score_path).name} "
        def span(a, b, end):
            return f"{round(a, 2):g}-{round(min(b, end), 2):g}"

        label = f"{name} {span(*train_s, t[-1])} -> {other}{span(*score_s, ts[-1])} s"
    pmodel = pinocchio_chain(urdf, m.joint_names)
    check_regressor(m, pmodel, data, label)
    return compare(label, m, pmodel, rows(data, train_mask), {"data": scored, "mask": mask}, log)


def baxter(log, torque_scale=1.0, train_s=(0.0, 120.0), score_s=None):
    """The real Baxter recording: trained on ``train_s`` = [from, until) s, scored on
    ``score_s`` (default: the last 30 s)."""
    folder = os.environ.get("ADMITTANCE_DATA")
    path = pathlib.Path(folder or "") / "baxter_rand" / "baxter_rand.csv"
    if not folder or not path.is_file():
        log(f"Baxter: {path} not found (set ADMITTANCE_DATA): skipped")
        return []
    urdf = ROOT / "models" / "baxter_left_arm.urdf"
    m = adm.Model.from_urdf(str(urdf))
    data = load_recording(path, m)
    t_end = data["t"][-1]
    if score_s is None:
        label = "Baxter (real), 120 s -> 30 s" if train_s == (0.0, 120.0) else f"Baxter {train_s[0]:g}-{train_s[1]:g} s -> last 30 s"
        score_s = (t_end - 30.0 + 1e-9, t_end + 1.0)
    else:
        label = f"Baxter {train_s[0]:g}-{train_s[1]:g} -> {score_s[0]:g}-{score_s[1]:g} s"
    return recording_points(log, urdf, m, path, train_s, score_s, torque_scale=torque_scale, label=label, data=data)


def drop_rows(data, fraction, seed):
    """``data`` without a random ``fraction`` of its rows (the first and last kept)."""
    if fraction <= 0.0:
        return data
    keep = np.random.default_rng(seed).random(len(data["t"])) >= fraction
    keep[[0, -1]] = True
    return {k: (np.asarray(v)[keep] if k in ("t", "q", "qdot", "qddot", "tau") else v) for k, v in data.items()}


class LinkTorqueSensor:
    """A joint torque sensor on the link side of each joint, as on torque-controlled arms
    (Franka, KUKA LBR iiwa): it reads the torque the link receives, the URDF arm's rigid-body
    torque of each step (``rnea`` at the state before it and the step's change of velocity),
    not the motor's command (no friction, damping or rotor inertia in it), plus a constant
    offset (the same in every recording of the arm: one sensor) and white noise, up to
    ``OFFSET`` and ``NOISE`` (standard deviation) times the joint's effort limit (0.04 and
    0.09 N m on the Panda's 87 N m joints)."""

    NOISE = 1e-3
    OFFSET = 5e-4

    def __init__(self, m, dt, seed):
        effort = np.where(np.isfinite(m.effort_limit) & (np.asarray(m.effort_limit) > 0), m.effort_limit, 87.0)
        self.m, self.dt = m, dt
        self.rng = np.random.default_rng(seed)
        self.noise = self.NOISE * effort
        self.offset = self.OFFSET * effort * np.random.default_rng(10).uniform(-1.0, 1.0, m.n)

    def __call__(self, q, qdot, arm, tau):
        acceleration = (arm.qdot() - qdot) / self.dt
        rigid = np.asarray(adm.rnea(self.m, q, qdot, acceleration))
        return rigid + self.offset + self.noise * self.rng.standard_normal(self.m.n)


def mujoco_arm(name, log, cfg, torque_scale=1.0, dropped=0.0, period=None, link_torque=False):
    """``period``: the training excitation's period in s (default: the arms table's, which
    repeats; the training duration: motion that does not repeat, so that the identification
    offers springs and judges them on held-out stretches). ``link_torque``: the recorded
    torque is a link-side torque sensor's (:class:`LinkTorqueSensor`), not the command."""
    from admittance.mujoco import _arms
    from admittance.mujoco._plant import MujocoArm

    path, base, tip = _arms.arm_source(name, cfg)
    m = adm.Model.from_urdf(str(path), base=base, tip=tip)
    tip = tip or m.tip_link
    arm = MujocoArm(path.read_text(), m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale)
    if period is None:
        train_motion, _ = _arms.excitation_motion(m, cfg.training_duration, cfg.training_seed, cfg.dt)
    else:
        e = adm.excitation(
            m, cfg.training_duration, seed=cfg.training_seed, rate_hz=1.0 / cfg.dt, period=period, **_arms.WHOLE_RANGE
        )
        train_motion = {k: np.asarray(e[k]) for k in ("t", "q", "qdot", "qddot")}
    eval_motion, _ = _arms.excitation_motion(m, cfg.evaluation_duration, cfg.evaluation_seed, cfg.dt)
    gains = _arms.recording_gains(m, train_motion["q"].mean(axis=0), arm.terms)
    rng = np.random.default_rng(cfg.seed)
    sensor = (lambda seed: LinkTorqueSensor(m, cfg.dt, seed)) if link_torque else (lambda seed: None)
    train, _, _ = _arms.record(arm, m, train_motion, gains, cfg, rng, torque_sensor=sensor(11))
    free, _, _ = _arms.record(arm, m, eval_motion, gains, cfg, rng, torque_sensor=sensor(12))
    train, free = scale_torque(train, torque_scale), scale_torque(free, torque_scale)
    train = drop_rows(train, dropped, 7)  # the scored recording stays whole: a loop's even rate
    scored = {"data": free, "mask": free["t"] >= cfg.evaluation_start}
    pmodel = pinocchio_chain(path, m.joint_names)
    check_regressor(m, pmodel, train, name)
    return compare(f"MuJoCo {name}", m, pmodel, train, scored, log)


def check_regressor(m, pmodel, data, label):
    """Pinocchio's regressor times the URDF's parameters is the project's RNEA (same model)."""
    ls = LeastSquares(pmodel)
    k = np.linspace(0, len(data["t"]) - 1, 20).astype(int)
    q, qd, qdd = (np.asarray(data[key])[k] for key in ("q", "qdot", "qddot"))
    n = pmodel.nv
    pin_tau = (body_regressor(pmodel, q, qd, qdd) @ ls.prior[: 10 * n]).reshape(q.shape)
    ours = np.array([adm.rnea(m, q[i], qd[i], qdd[i]) for i in range(len(k))])
    if not np.allclose(pin_tau, ours, rtol=1e-6, atol=1e-6 * (1 + np.abs(ours).max())):
        raise SystemExit(f"{label}: Pinocchio's regressor and the project's RNEA differ by {np.abs(pin_tau - ours).max():.3g} N m")


def timing(names, cfg, log, csv_dir=None, repeats=3):
    """`adm.identify` on `cfg.training_duration` s at 1 kHz of motion that does not repeat (an
    excitation whose period is the whole recording, so the delay scan and the spring trials
    run, as on a real recording), the cut-off chosen (`None`) and given (4 Hz): the fastest of
    `repeats` calls each; with `csv_dir`, each recording also written there as ARM.csv (the
    free-motion CSV that `admittance identify --data` reads, to time the command line)."""
    from admittance.mujoco import _arms
    from admittance.mujoco._plant import MujocoArm

    for name in names:
        path, base, tip = _arms.arm_source(name, cfg)
        m = adm.Model.from_urdf(str(path), base=base, tip=tip)
        arm = MujocoArm(path.read_text(), m.joint_names, tip or m.tip_link, m.effort_limit, cfg.dt, cfg.friction_scale)
        duration = cfg.training_duration
        e = adm.excitation(m, duration, seed=cfg.training_seed, rate_hz=1.0 / cfg.dt, period=duration, **_arms.WHOLE_RANGE)
        motion = {k: np.asarray(e[k]) for k in ("t", "q", "qdot", "qddot")}
        gains = _arms.recording_gains(m, motion["q"].mean(axis=0), arm.terms)
        train, _, _ = _arms.record(arm, m, motion, gains, cfg, np.random.default_rng(cfg.seed))
        if csv_dir:
            out = pathlib.Path(csv_dir) / f"{name}.csv"
            header = ["t"] + [f"{kind}.{j}" for kind in ("q", "qdot", "qddot", "tau") for j in m.joint_names]
            table = np.column_stack([train["t"]] + [np.asarray(train[kind]) for kind in ("q", "qdot", "qddot", "tau")])
            partial = out.with_name(f".{out.name}.partial")
            np.savetxt(partial, table, delimiter=",", header=",".join(header), comments="", fmt="%.17g")
            partial.replace(out)
            log(f"wrote {out} (URDF: {path})")
        for hz in (None, 4.0):
            seconds = []
            for _ in range(repeats):
                start = time.perf_counter()
                ident = adm.identify(train, m, input_filter_hz=hz)
                seconds.append(time.perf_counter() - start)
            chosen = ident.summary["input_filter_hz"]
            log(f"{name} ({m.n} joints, {len(train['t'])} samples): identify, cut-off "
                f"{'chosen' if hz is None else 'given'} ({chosen:g} Hz): {min(seconds):.2f} s "
                f"(runs {', '.join(f'{x:.2f}' for x in seconds)}; bar < 2 s)")


def main():
    from admittance.mujoco import _arms

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", nargs="*", help="MuJoCo arms (default: all of the arms table; with --urdf, that arm alone)")
    parser.add_argument(
        "--urdf",
        help="an arm of your own URDF: the recorded arm's with --recording, else recorded in MuJoCo as the table's arms are",
    )
    parser.add_argument("--base", help="with --urdf: the chain's base link (default: the URDF's root)")
    parser.add_argument("--tip", help="with --urdf: the chain's tip link (default: the end of the only chain)")
    parser.add_argument(
        "--recording",
        metavar="CSV",
        help="your own arm's free-motion CSV (t, q.J, qdot.J, qddot.J, tau.J, qdot and qddot optional; with --urdf), "
        "instead of the Baxter "
        "recording and the MuJoCo arms (add --arms to run those too)",
    )
    parser.add_argument("--train", metavar="FROM,UNTIL", help="with --recording: the stretch fitted on, in s (default: all but the last fifth)")
    parser.add_argument("--score", metavar="FROM,UNTIL", help="with --recording: the stretch scored, in s (default: the last fifth)")
    parser.add_argument(
        "--score-recording",
        metavar="CSV",
        help="with --recording: score on this other recording of the arm (--score: a stretch of it; default all of it, "
        "and the whole of --recording fitted)",
    )
    parser.add_argument("--no-baxter", action="store_true", help="leave out the real Baxter recording")
    parser.add_argument("--baxter-train", default="0,120", help="the Baxter stretch fitted on, FROM,UNTIL in s (0,120)")
    parser.add_argument("--baxter-score", help="the Baxter stretch scored, FROM,UNTIL in s (default: the last 30 s)")
    parser.add_argument("--training-duration", type=float, default=60.0, help="MuJoCo training recording (s)")
    parser.add_argument("--evaluation-duration", type=float, default=30.0, help="MuJoCo scored recording (s)")
    parser.add_argument(
        "--training-period",
        type=float,
        help="the MuJoCo training excitation's period (s; default: the arms table's, which repeats); the training "
        "duration gives motion that does not repeat, where springs are offered",
    )
    parser.add_argument("--json", help="write every point to this file")
    parser.add_argument(
        "--speed-flags",
        action="store_true",
        help="also print, per point, the scored rows faster than the identification's training speeds (what the loop "
        "flags as faster_than_training) and both fits' rms there and elsewhere",
    )
    parser.add_argument(
        "--drop-rows",
        type=float,
        default=0.0,
        help="drop this fraction of the MuJoCo training recordings' rows at random (a logger that lost samples)",
    )
    parser.add_argument(
        "--torque-scale",
        type=float,
        default=1.0,
        help="multiply every recorded torque by this (a torque constant or gear ratio off against the URDF)",
    )
    parser.add_argument(
        "--link-torque",
        action="store_true",
        help="the MuJoCo recordings' torque is a link-side joint torque sensor's (rigid-body torque, a constant "
        "offset and noise) instead of the command",
    )
    parser.add_argument(
        "--timing",
        action="store_true",
        help="only time identify on non-repeating recordings of --arms (60 s at 1 kHz by default)",
    )
    parser.add_argument("--write-csv", metavar="DIR", help="with --timing: write each recording to DIR/ARM.csv (made if missing; never over a file)")
    args = parser.parse_args()

    def stretch(text, flag):
        try:
            a, b = (float(v) for v in text.split(","))
        except ValueError:
            parser.error(f"{flag} {text}: needs FROM,UNTIL in seconds")
        if not a < b:
            parser.error(f"{flag} {text}: FROM must come before UNTIL")
        return (a, b)

    if args.training_period is not None and not args.training_period > 0:
        parser.error(f"--training-period {args.training_period}: needs a period > 0 s")
    stretches = {flag: stretch(text, f"--{flag.replace('_', '-')}") if text else None
                 for flag, text in (("train", args.train), ("score", args.score), ("baxter_train", args.baxter_train), ("baxter_score", args.baxter_score))}
    urdf_arms = {}
    if args.recording:
        if not args.urdf:
            parser.error("--recording needs --urdf (the recorded arm's URDF)")
        if not pathlib.Path(args.urdf).is_file():
            parser.error(f"--urdf {args.urdf}: no such file")
        if args.timing:
            parser.error("--timing times identify on MuJoCo arms (--arms), not on --recording")
        if args.arms is None:
            args.arms = []
    elif args.train or args.score or args.score_recording:
        parser.error("--train, --score and --score-recording go with --recording")
    elif args.urdf:
        if not pathlib.Path(args.urdf).is_file():
            parser.error(f"--urdf {args.urdf}: no such file")
        urdf_arms[pathlib.Path(args.urdf).stem] = [str(pathlib.Path(args.urdf).resolve()), args.base, args.tip]
    elif args.base or args.tip:
        parser.error("--base and --tip go with --urdf")
    if args.arms is None:
        args.arms = list(urdf_arms) or list(_arms.ARMS)
    unknown = [a for a in args.arms if a not in _arms.ARMS and a not in urdf_arms]
    if unknown:
        parser.error(f"--arms: unknown {unknown}; choose among {list(_arms.ARMS) + list(urdf_arms)}")
    cfg = _arms.ArmsConfig(
        training_duration=args.training_duration, evaluation_duration=args.evaluation_duration, urdf_arms=urdf_arms
    )

    def log(text):
        print(text, flush=True)

    global SPEED_FLAGS
    SPEED_FLAGS = args.speed_flags
    if args.timing:
        if args.write_csv:
            taken = [a for a in args.arms if (pathlib.Path(args.write_csv) / f"{a}.csv").exists()]
            if taken:
                parser.error(f"--write-csv {args.write_csv}: {taken[0]}.csv exists; remove it or choose another folder")
            pathlib.Path(args.write_csv).mkdir(parents=True, exist_ok=True)
        timing(args.arms, cfg, log, args.write_csv)
        return

    log(f"{'recording':<28} {'input':>6} {'identify':>8} {'LS':>8} {'ratio':>7}  physical  (LS physical)   rms false torque, N m")
    if args.recording:
        try:
            m = adm.Model.from_urdf(str(args.urdf), base=args.base, tip=args.tip)
        except ValueError as e:
            parser.error(str(e))
        points = recording_points(
            log,
            pathlib.Path(args.urdf).resolve(),
            m,
            args.recording,
            stretches["train"],
            stretches["score"],
            args.score_recording,
            args.torque_scale,
        )
    else:
        points = [] if args.no_baxter else baxter(log, args.torque_scale, stretches["baxter_train"], stretches["baxter_score"])
    for name in args.arms:
        points += mujoco_arm(name, log, cfg, args.torque_scale, args.drop_rows, args.training_period, args.link_torque)
    ratios = [p["ratio"] for p in points]
    if not ratios:
        sys.exit("no recording")
    geo = math.exp(sum(math.log(r) for r in ratios) / len(ratios))
    worse = [p for p in points if p["ratio"] > 1.0]
    unphysical = [p for p in points if not p["project_physical"]]
    log(f"geometric mean of the ratios: {geo:.3f} over {len(ratios)} points (bar: <= 0.900)")
    log(f"points with ratio > 1.0: {len(worse)}" + "".join(
        f"\n  {p['recording']} at {'raw' if p['input_filter_hz'] == 0 else str(p['input_filter_hz']) + ' Hz'}: {p['ratio']:.3f}" for p in worse))
    log(f"points whose fitted joint terms are not physical: {len(unphysical)}")
    flagged = [p["faster_than_training"] for p in points if "faster_than_training" in p]
    if flagged:
        pooled = {k: sum(f[k] for f in flagged) for k in flagged[0] if k != "rows"}
        pooled["rows"] = sum(f["rows"] for f in flagged) / len(flagged)
        log("over every point, " + speed_flag_text(pooled) + " (rows: the mean share)")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps({"points": points, "geometric_mean": geo}, indent=1))


if __name__ == "__main__":
    main()
