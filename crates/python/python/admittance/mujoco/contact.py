"""Contact detection on the example-robot-data arms in MuJoCo (issue 31, item 5).

Per arm (the plant, recordings and identification of ``admittance.mujoco.arms``: FR3-like
joint friction, damping and armature unknown to every model, a noisy encoder, 40 Hz sensor
filter, 10 Hz input conditioning, the momentum observer on the identification, K_O = 50):

1. Identify on 60 s of the excitation (seed 1), settings chosen on 20 s of another (seed 3).
2. The contact floor (``adm.calibrate_contact``, 1 false alarm per hour) from free motion
   that the identification never saw (``--calibration`` s in recordings of ``--segment`` s,
   seeds 4, 41, 42, ...: a motion per recording, at its own speeds).
   The floor's data, the free motion and the pushed motion are multi-sines around the
   training's mean pose (``_cosim._multisine``: two incommensurate sines a joint, periods
   4-16 s; ``--motion excitation``: the optimised excitation, which repeats periods of at
   most 10 s, so 10 min of it are one 10 s stretch 60 times).
3. Free motion the floor never saw (``--free`` s in recordings of ``--segment`` s, seeds 5,
   51, 52, ...; 600 s = 10 min by default): false contact and collision events.
4. Pushes on three links (at the centres of mass of the child links of the last, the middle
   and the second joint)
   during other motion (seed 6): half-sines of 0.5 s at several peak forces, random
   directions, 1.5 s apart. Per push: detected (the contact flag during the push or within
   0.2 s after it), the delay from the moment the true torque first exceeds twice a joint's
   contact level (at the measured speed) to the flag, and the joint the detector names 50 ms
   after the push's peak: right when it is no earlier than the last joint whose true torque
   there exceeds its contact level and no later than the last joint the push loads at all
   (strict: exactly the former).
5. Beside two fixed thresholds per joint as vendors set them, on the same estimates and
   with the same hysteresis: 1.5 times the largest estimate seen on the calibration motion
   ("peak + margin"), and 10 % of the joint's effort limit ("catalogue default").

``python -m admittance.mujoco.contact --arms panda ur5 --out runs/contact`` writes a folder
per arm (``admittance.sweep`` jobs, ``--jobs`` at a time, default every core, or on a Ray
cluster with ``--ray``; an arm finished with the same settings is kept), then
``results.json`` and ``table.md`` there.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import time
from dataclasses import replace

import numpy as np

import admittance as adm

from ._arms import ARMS, ArmsConfig, _write_atomic, conditioned, excitation_motion, record, recording_gains, robots_dir
from ._cosim import _multisine
from ._plant import MujocoArm

WARM_UP_S = 1.0  # as admittance_scenario::CONTACT_WARM_UP_S
PUSH_SECONDS = 0.5
PUSH_GAP = 1.5
DETECT_WINDOW = 0.2  # after a push, still counted as detecting it
DELAY_BAR = 0.05


def push_on_body(arm, body):
    """``arm.step`` with the force at ``body``'s centre of mass instead of the tip."""

    def step(tau, push=None):
        mj, m, d = arm.mj, arm.model, arm.data
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[arm.dofs] = tau
        d.xfrc_applied[:] = 0.0
        if push is not None:
            # At the link's centre of mass (a link's frame origin often lies on its joint's
            # axis, where a force loads no joint of its own).
            d.xfrc_applied[body, :3] = push
        mj.mj_step(m, d)
        tau_ext = np.zeros(m.nv)
        if push is not None:
            mj.mj_jac(m, d, arm.jacp, arm.jacr, d.xipos[body], body)
            tau_ext += arm.jacp.T @ push
        return tau_ext[arm.dofs]

    return step


def multisine_motion(m, q0, seed, duration, dt):
    """``_cosim._multisine`` around ``q0`` sampled at the control rate."""
    at = _multisine(m, q0, np.random.default_rng(seed), duration, dt)
    t = np.arange(int(round(duration / dt)) + 1) * dt
    q, qdot, qddot = (np.array(x) for x in zip(*(at(tk) for tk in t)))
    return {"t": t, "q": q, "qdot": qdot, "qddot": qddot}


def detector_run(ident, floor, data, feed_raw, dt):
    """The Rust detector (momentum observer on ``ident`` + floor) over a recording: the
    estimate ``(N, n)``, the flags and the link per sample, and the signals it saw."""
    det = adm.ContactDetector(ident, floor)
    sig = data if feed_raw else conditioned(data, ArmsConfig())
    steps, n = data["q"].shape
    est = np.zeros((steps, n))
    flags = np.zeros((steps, 3), dtype=np.int64)
    for k in range(steps):
        est[k] = det.update(k * dt, sig["q"][k], sig["qdot"][k], sig["qddot"][k], sig["tau"][k], dt)
        flags[k] = (det.contact, det.collision, det.link)
    if not feed_raw:
        return est, flags, sig
    return est, flags, conditioned(data, ArmsConfig())


def fixed_flags(est, thresholds, release=0.7):
    """A fixed threshold per joint with the detector's hysteresis: the contact flag and the
    link per sample (vectorised)."""
    steps, n = est.shape
    idx = np.arange(steps)
    on = np.zeros((steps, n), dtype=bool)
    for i in range(n):
        a = np.abs(est[:, i])
        last_above = np.maximum.accumulate(np.where(a > thresholds[i], idx, -1))
        last_below = np.maximum.accumulate(np.where(a < release * thresholds[i], idx, -1))
        on[:, i] = last_above > last_below
    link = np.where(on.any(axis=1), n - 1 - np.argmax(on[:, ::-1], axis=1), -1)
    return on.any(axis=1), link


def events(flag, t, start=WARM_UP_S):
    f = flag & (t >= start)
    return int(np.sum(f[1:] & ~f[:-1]) + (1 if f[0] else 0))


def floor_dict(floor):
    return json.loads(floor.to_json())


def score_pushes(pushes, true, t, contact, link, lev, dt):
    """Per push: detected, delay after the 2x crossing, named link against the true one."""
    out = []
    for p in pushes:
        t0, t1 = p["t0"], p["t1"]
        w = (t >= t0) & (t <= t1 + DETECT_WINDOW)
        inside = (t >= t0) & (t <= t1)
        detected = bool(contact[w].any())
        first = float(t[w][np.argmax(contact[w])]) if detected else None
        over2 = np.abs(true) > 2.0 * lev
        cross = over2[inside].any(axis=1)
        t_cross = float(t[inside][np.argmax(cross)]) if cross.any() else None
        delay = None if (t_cross is None or first is None) else first - t_cross
        peak_k = np.flatnonzero(inside)[np.argmax(np.abs(true[inside]).max(axis=1))]
        significant = np.flatnonzero(np.abs(true[peak_k]) > lev[peak_k])
        true_last = int(significant[-1]) if significant.size else -1
        # Joints beyond the touched link carry none of the push's torque.
        loaded = np.flatnonzero(np.abs(true[peak_k]) > 1e-6 * np.abs(true[peak_k]).max())
        last_loaded = int(loaded[-1]) if loaded.size else -1
        # The estimate lags the true torque by the observer's 20 ms: the named link 50 ms
        # after the true peak.
        k_named = min(peak_k + int(0.05 / dt), len(t) - 1)
        out.append({
            **p,
            "true_peak_nm": np.abs(true[inside]).max(axis=0).tolist(),
            "detected": detected,
            "over_twice": t_cross is not None,
            "delay_s": delay,
            "within_50ms": bool(t_cross is not None and first is not None and delay <= DELAY_BAR),
            "true_last_joint": true_last,
            "last_loaded_joint": last_loaded,
            "named": int(link[k_named]),
        })
    return out


def summarise(scored, sizes):
    by_size = {}
    for s in sizes:
        ps = [p for p in scored if p["force"] == s]
        by_size[str(s)] = sum(p["detected"] for p in ps) / max(len(ps), 1)
    over = [p for p in scored if p["over_twice"]]
    named = [p for p in scored if p["detected"] and p["true_last_joint"] >= 0]
    delays = [p["delay_s"] for p in over if p["delay_s"] is not None]
    smallest95 = next((s for s in sizes if all(by_size[str(x)] >= 0.95 for x in sizes if x >= s)), None)
    return {
        "detection_rate_by_force": by_size,
        "smallest_force_detected_95": smallest95,
        "over_twice": len(over),
        "over_twice_within_50ms": sum(p["within_50ms"] for p in over) / max(len(over), 1),
        "median_delay_s": float(np.median(delays)) if delays else None,
        "isolation": sum(p["true_last_joint"] <= p["named"] <= p["last_loaded_joint"] for p in named) / max(len(named), 1),
        "isolation_strict": sum(p["named"] == p["true_last_joint"] for p in named) / max(len(named), 1),
    }


def run_arm(name, args, log=print):
    cfg = replace(ArmsConfig(), dt=1e-3)
    dt = cfg.dt
    rel, base, tip = ARMS[name]
    path = robots_dir() / rel
    m = adm.Model.from_urdf(str(path), base=base, tip=tip)
    tip = tip or m.tip_link
    arm = MujocoArm(path.read_text(), m.joint_names, tip, m.effort_limit, dt, cfg.friction_scale)
    started = time.perf_counter()
    motions = {k: excitation_motion(m, d, s, dt)[0] for k, d, s in (("train", 60.0, 1), ("valid", 20.0, 3))}
    q0 = motions["train"]["q"].mean(axis=0)
    def motion(seed, duration):
        # The excitation repeats periods of at most 10 s: the floor's data and the motion it
        # is judged on are multi-sines that do not repeat (two incommensurate sines a joint).
        if args.motion == "multisine":
            return multisine_motion(m, q0, seed, duration, dt)
        return excitation_motion(m, duration, seed, dt)[0]

    # The floor's data and the free motion as recordings of ``--segment`` s, each a motion
    # of its own seed (periods drawn anew: other speeds), as a user records several motions.
    # --seed S moves every motion the floor and the detector see to other seeds (the
    # identification's recordings stay): the same experiment on other motion.
    base = 1000 * args.seed
    for k, total, seed in (("calib", args.calibration, 4), ("free", args.free, 5)):
        count = max(1, round(total / args.segment)) if args.segment > 0 else 1
        seeds = [base + seed] + [base + 10 * seed + i for i in range(1, count)]
        # Each recording's first second (the filters' and the observer's start) is left out
        # of the floor and of the counts: it is added, so that ``total`` s are counted.
        motions[k] = [motion(s, total / count + WARM_UP_S) for s in seeds]
    motions["push"] = motion(base + 6, args.push_seconds)
    gains = recording_gains(m, q0, arm.terms)
    rng = np.random.default_rng(1)
    rec = {k: record(arm, m, motions[k], gains, cfg, rng)[0] for k in ("train", "valid")}
    for k in ("calib", "free"):
        rec[k] = [record(arm, m, x, gains, cfg, rng)[0] for x in motions[k]]
    ident = adm.identify(rec["train"], m, validation=rec["valid"], input_filter_hz=cfg.input_filter_hz)
    feed_raw = float(ident.summary.get("input_filter_hz", 0.0) or 0.0) > 0.0
    calib = rec["calib"] if feed_raw else [{"t": r["t"], **conditioned(r, cfg)} for r in rec["calib"]]
    floor = adm.calibrate_contact(calib, ident, false_alarms_per_hour=args.rate)
    fl = floor_dict(floor)
    log(f"{name}: floor\n{floor.describe()}")

    # Free motion the floor never saw.
    runs_c = [detector_run(ident, floor, r, feed_raw, dt)[0][r["t"] >= WARM_UP_S] for r in rec["calib"]]
    peak_calib = np.abs(np.concatenate(runs_c)).max(axis=0)
    vendors = {"peak_plus_margin": 1.5 * peak_calib, "catalogue_10pct_effort": 0.1 * np.asarray(m.effort_limit)}
    hours, counts, est_f = 0.0, {"contact_events": 0, "collision_events": 0}, []
    vendor_counts = dict.fromkeys(vendors, 0)
    for r in rec["free"]:
        est, flags, _ = detector_run(ident, floor, r, feed_raw, dt)
        t_f = r["t"]
        hours += (t_f[-1] - WARM_UP_S) / 3600.0
        counts["contact_events"] += events(flags[:, 0] > 0, t_f)
        counts["collision_events"] += events(flags[:, 1] > 0, t_f)
        est_f.append(est[t_f >= WARM_UP_S])
        for v, thr in vendors.items():
            vendor_counts[v] += events(fixed_flags(est, thr)[0], t_f)
    free = {
        "minutes": hours * 60.0,
        "recordings": len(rec["free"]),
        "floor": counts,
        "false_torque_rms": np.sqrt(np.mean(np.concatenate(est_f) ** 2, axis=0)).tolist(),
    }
    for v in vendors:
        free[v] = {"contact_events": vendor_counts[v]}

    # Pushes on three links during motion the floor never saw.
    n = m.n
    links = sorted({n - 1, n // 2, 1})
    prng = np.random.default_rng(7 + base)
    pushes = []
    t_now = 2.0
    for rep in range(args.repeats):
        for force in args.forces:
            for j in links:
                d = prng.standard_normal(3)
                pushes.append({"t0": t_now, "t1": t_now + PUSH_SECONDS, "force": force, "joint": j, "direction": (d / np.linalg.norm(d)).tolist()})
                t_now += PUSH_SECONDS + PUSH_GAP
    duration = min(t_now + 1.0, args.push_seconds)
    pushes = [p for p in pushes if p["t1"] + DETECT_WINDOW < duration]
    body_of = {j: int(arm.model.jnt_bodyid[arm.joint_ids[j]]) for j in links}
    steppers = {j: push_on_body(arm, body_of[j]) for j in links}
    plain_step = arm.step

    def schedule(t):
        for p in pushes:
            if p["t0"] <= t <= p["t1"]:
                return p, p["force"] * math.sin(math.pi * (t - p["t0"]) / PUSH_SECONDS) * np.asarray(p["direction"])
        return None, None

    def step(tau, push=None):
        p, f = schedule(step.t)
        step.t += dt
        return plain_step(tau) if p is None else steppers[p["joint"]](tau, f)

    step.t = 0.0
    arm.step = step
    try:
        pushed, true, _ = record(arm, m, motions["push"], gains, cfg, rng, push=lambda t: None)
    finally:
        arm.step = plain_step
    # record() passes push(t) (None here) and stores the torque of the step before each
    # sample, as for the tip pushes of the arms table.
    est_p, flags_p, sig_p = detector_run(ident, floor, pushed, feed_raw, dt)
    t_p = pushed["t"]
    lev = floor.contact_levels(sig_p["qdot"], sig_p["qddot"])
    scored = {"floor": score_pushes(pushes, true, t_p, flags_p[:, 0] > 0, flags_p[:, 2], lev, dt)}
    for v, thr in vendors.items():
        c, l = fixed_flags(est_p, thr)
        scored[v] = score_pushes(pushes, true, t_p, c, l, np.broadcast_to(thr, lev.shape), dt)
    result = {
        "arm": name,
        "n": n,
        "floor": {k: fl[k] for k in ("contact_thresholds", "collision_thresholds", "speed_gain", "acceleration_gain", "moving_drop", "rest_width", "reversal_gain", "knee_speed", "knee_gain")},
        "smallest_detected": fl["calibration"]["smallest_detected"],
        "vendor_thresholds": {k: v.tolist() for k, v in vendors.items()},
        "free": free,
        "pushes": {k: summarise(v, args.forces) for k, v in scored.items()},
        "push_details": scored["floor"],
        "seconds": time.perf_counter() - started,
    }
    log(json.dumps({k: result[k] for k in ("arm", "free", "pushes")}, indent=1))
    return result


def table(results, args):
    lines = [
        f"| arm | detector | false contact events in {round(args.free / 60, 1):g} min (collision) | detection rate by peak force {', '.join(str(f) for f in args.forces)} N | smallest force detected 95 % | > 2x level: within 50 ms | median delay (ms) | touched part named (strict) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        for det in ("floor", "peak_plus_margin", "catalogue_10pct_effort"):
            p = r["pushes"][det]
            fa = r["free"][det]
            coll = f" ({fa['collision_events']})" if "collision_events" in fa else ""
            rates = " / ".join(f"{p['detection_rate_by_force'][str(f)]:.2f}" for f in args.forces)
            delay = "-" if p["median_delay_s"] is None else f"{1000 * p['median_delay_s']:.0f}"
            lines.append(
                f"| {r['arm']} | {det} | {fa['contact_events']}{coll} | {rates} | {p['smallest_force_detected_95']} | "
                f"{p['over_twice_within_50ms']:.2f} of {p['over_twice']} | {delay} | {p['isolation']:.2f} ({p['isolation_strict']:.2f}) |"
            )
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", nargs="+", default=list(ARMS))
    ap.add_argument("--out", default="runs/contact")
    ap.add_argument("--rate", type=float, default=1.0, help="false alarms per hour promised")
    ap.add_argument("--calibration", type=float, default=300.0, help="s of free motion for the floor")
    ap.add_argument("--free", type=float, default=600.0, help="s of new free motion")
    ap.add_argument("--seed", type=int, default=0, help="other motions for the floor, the free test and the pushes (0: the documented ones)")
    ap.add_argument("--segment", type=float, default=60.0, help="s per recording of the floor's data and of the free motion (0: one recording each)")
    ap.add_argument("--push-seconds", type=float, default=95.0)
    ap.add_argument("--forces", type=float, nargs="+", default=[2.0, 5.0, 10.0, 20.0, 40.0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--motion", choices=["multisine", "excitation"], default="multisine",
                    help="the motion of the floor's data, the free test and the pushes")
    ap.add_argument("--jobs", type=int, default=None, help="arms at once, each in a process of its own (default: every core)")
    ap.add_argument("--ray", metavar="ADDRESS", help="run the arms on the Ray cluster at ADDRESS ('auto', 'local', or ray://HOST:PORT)")
    ap.add_argument("--force", action="store_true", help="replace arm folders in --out that hold other settings")
    args = ap.parse_args(argv)
    if args.jobs is not None and args.jobs < 1:
        ap.error("--jobs must be at least 1")
    unknown = sorted(set(args.arms) - set(ARMS))
    if unknown:
        ap.error(f"unknown arm {unknown[0]!r}: choose among {', '.join(ARMS)}")
    from admittance import sweep

    out = pathlib.Path(args.out)
    settings = {k: v for k, v in vars(args).items() if k not in ("arms", "out", "jobs", "ray", "force")}
    # Each arm is a job of its own (admittance.sweep): a folder per arm, kept across runs
    # with the same settings; the arms' results do not depend on how many run at once.
    jobs = [sweep.call_job("admittance.mujoco.contact:arm_job", {"name": name, "settings": settings}, name) for name in args.arms]
    try:
        done = sweep.run_sweep(jobs, out, args.jobs, args.ray, 0, args.force)
    except (sweep.SweepError, OSError) as e:
        print(f"admittance.mujoco.contact: {e}", file=sys.stderr)
        return 3
    results = [json.loads((out / name / sweep.RESULT_FILE).read_text()) for name in args.arms if name not in done.failed]
    _write_atomic(out / "results.json", json.dumps({"args": vars(args), "arms": results}, indent=1))
    _write_atomic(out / "table.md", table(results, args))
    print(table(results, args))
    if done.failed:
        print(f"failed: {', '.join(done.failed)} (their folders in {out} say why)", file=sys.stderr)
        return 1
    return 0


def arm_job(folder, name, settings):
    """One arm as a sweep job: ``run_arm`` with the command's settings; its result is the
    job's ``result.json``."""
    return run_arm(name, argparse.Namespace(**settings), log=lambda s: None)


if __name__ == "__main__":
    sys.exit(main())
