"""Side-by-side of the admittance-sim plant step with MuJoCo's mj_step on the same arm.

Run through compare_mujoco.sh (which makes the virtual environment and builds the Rust
timing example). What it does:

1. Loads the URDF in MuJoCo directly (a <mujoco><compiler discardvisual="true"
   balanceinertia="false" fusestatic="false"/></mujoco> block is inserted after <robot>),
   and checks the model against ours: per moving joint, the mass of the body it carries
   (fixed children folded in), and M(q0), G(q0) at the mid-range pose q0.
2. Configures MuJoCo like our plant: timestep = our plant step, integrator Euler
   (semi-implicit in velocity: v += h qacc, q += h v), contacts and all constraints
   (joint limits included) disabled, no joint damping, armature or friction loss (the
   URDF's <dynamics damping> is zeroed: our plant only has the friction it is configured
   with, here none).
3. Times mj_step like crates/sim/examples/plant_timing.rs times our step: from q0 at rest,
   a constant joint torque (qfrc_applied), timed batches of --steps steps (one
   mj_step(m, d, nstep) call each), the state reset to q0 every 10 batches outside the
   timed region, median over --batches batches of (batch time / steps). The MuJoCo and
   Rust timings are interleaved over --rounds rounds and the median of the rounds is
   reported, so that a load change on the machine hits both sides alike.
4. Agreement: 0.2 s of free fall (zero torque) from q0 with the same timestep; the joint
   angles of both simulations every 100 steps, and the largest difference.

Prints: ns per step of ours (semi-implicit Euler) and mj_step, the ratio (target <= 1.0),
the default integrator's (rk4_split) cost, the other lines of the Rust timing example,
and the agreement.
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import mujoco
import numpy as np

COMPILER = '<mujoco><compiler discardvisual="true" balanceinertia="false" fusestatic="false"/></mujoco>'


def load_mujoco(urdf, dt):
    with open(urdf) as f:
        text = f.read()
    text, count = re.subn(r"(<robot\b[^>]*>)", r"\1" + COMPILER, text, count=1)
    if count != 1:
        sys.exit(f"{urdf}: no <robot> element")
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.timestep = dt
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT) | int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    m.dof_damping[:] = 0.0
    m.dof_armature[:] = 0.0
    m.dof_frictionloss[:] = 0.0
    return m


def joint_names(m):
    return [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]


def carried_masses(m):
    """Mass carried by each joint's body, fixed (jointless) descendants folded in."""
    owner = {}
    for b in range(m.nbody):
        a = b
        while a > 0 and m.body_jntnum[a] == 0:
            a = m.body_parentid[a]
        owner[b] = a
    masses = []
    for j in range(m.njnt):
        body = m.jnt_bodyid[j]
        masses.append(sum(m.body_mass[b] for b in range(m.nbody) if owner[b] == body))
    return np.array(masses)


def mass_matrix_and_gravity(m, q):
    d = mujoco.MjData(m)
    d.qpos[:] = q
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    try:
        mujoco.mj_fullM(m, d, full)  # MuJoCo >= 3.4 signature
    except TypeError:
        mujoco.mj_fullM(m, full, d.qM)  # older releases
    return full, d.qfrc_bias.copy()


def time_mujoco(m, q0, tau, steps, batches, reset_every=10):
    d = mujoco.MjData(m)
    per_step = []
    for b in range(batches + 3):
        if b % reset_every == 0:
            mujoco.mj_resetData(m, d)
            d.qpos[:] = q0
            d.qvel[:] = 0.0
            d.qfrc_applied[:] = tau
        start = time.perf_counter_ns()
        mujoco.mj_step(m, d, nstep=steps)
        elapsed = time.perf_counter_ns() - start
        if b >= 3:
            per_step.append(elapsed / steps)
    if not np.all(np.isfinite(d.qpos)):
        sys.exit("MuJoCo state went non-finite")
    return statistics.median(per_step)


def run_rust(binary, urdf, tip, dt, steps, batches):
    out = subprocess.run(
        [binary, urdf, tip, "--dt", repr(dt), "--steps", str(steps), "--batches", str(batches)],
        check=True, capture_output=True, text=True,
    ).stdout
    lines = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 2:
            lines[parts[0]] = float(parts[1])
    return lines


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--rust-bin", required=True, help="the plant_timing example binary")
    p.add_argument("--urdf", default="models/baxter_left_arm.urdf")
    p.add_argument("--tip", default="left_hand")
    p.add_argument("--dt", type=float, default=2e-4, help="plant step (s), default 2e-4 (5 kHz)")
    p.add_argument("--steps", type=int, default=100, help="steps per timed batch")
    p.add_argument("--batches", type=int, default=1001)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--fall", type=float, default=0.2, help="free-fall time of the agreement check (s)")
    p.add_argument("--tolerance", type=float, default=1e-6, help="agreement bound (rad) for the same scheme")
    p.add_argument("--json", help="also write the results to this file")
    args = p.parse_args()

    check_steps = int(round(args.fall / args.dt))
    with tempfile.TemporaryDirectory() as tmp:
        check_file = os.path.join(tmp, "check.json")
        subprocess.run(
            [args.rust_bin, args.urdf, args.tip, "--dt", repr(args.dt), "--check", check_file,
             "--check-steps", str(check_steps), "--check-every", "100"],
            check=True,
        )
        with open(check_file) as f:
            ours = json.load(f)

    m = load_mujoco(args.urdf, args.dt)
    names = joint_names(m)
    if names != ours["joint_names"]:
        sys.exit(f"joint order differs: MuJoCo {names}, ours {ours['joint_names']}")
    q0 = np.array(ours["q0"])
    n = len(q0)
    tau = np.array([0.5 * (-1.0) ** i / (1.0 + i) for i in range(n)])

    print(f"# MuJoCo {mujoco.__version__}, {args.urdf} ({m.nbody} bodies, {m.nv} dofs), "
          f"timestep {args.dt:g} s, integrator Euler, contacts and constraints off, no damping")
    mass_diff = np.max(np.abs(carried_masses(m) - np.array(ours["body_mass"])))
    M, G = mass_matrix_and_gravity(m, q0)
    m_diff = np.max(np.abs(M - np.array(ours["mass_matrix"])))
    g_diff = np.max(np.abs(G - np.array(ours["gravity"])))
    print(f"model check: max |body mass diff| {mass_diff:.2e} kg, max |M(q0) diff| {m_diff:.2e} kg m^2 "
          f"(max |M| {np.max(np.abs(M)):.3f}), max |G(q0) diff| {g_diff:.2e} N m (max |G| {np.max(np.abs(G)):.2f})")
    model_ok = mass_diff < 1e-9 and m_diff < 1e-9 and g_diff < 1e-9

    # Agreement: free fall from q0, same timestep, zero torque.
    d = mujoco.MjData(m)
    d.qpos[:] = q0
    every = ours["every"]
    traj = []
    for s in range(1, check_steps + 1):
        mujoco.mj_step(m, d)
        if s % every == 0:
            traj.append(d.qpos.copy())
    traj = np.array(traj)
    sie = np.array(ours["trajectory_semi_implicit_euler"])
    rk4 = np.array(ours["trajectory_rk4_split"])
    diff_sie = np.max(np.abs(traj - sie))
    diff_rk4 = np.max(np.abs(traj - rk4))
    travel = np.max(np.abs(traj[-1] - q0))
    print(f"agreement over {args.fall:g} s of free fall ({check_steps} steps, largest joint travel {travel:.3f} rad): "
          f"max |q_ours - q_mujoco| semi_implicit_euler {diff_sie:.2e} rad, rk4_split {diff_rk4:.2e} rad "
          f"(the latter is Euler's own O(h) error)")
    agree_ok = diff_sie < args.tolerance

    mj, rust = [], []
    for r in range(args.rounds):
        mj.append(time_mujoco(m, q0, tau, args.steps, args.batches))
        rust.append(run_rust(args.rust_bin, args.urdf, args.tip, args.dt, args.steps, args.batches))
        print(f"# round {r + 1}: mj_step {mj[-1]:.1f} ns, ours {rust[-1]['semi_implicit_euler']:.1f} ns, "
              f"rk4_split {rust[-1]['rk4_split']:.1f} ns")
    mj_ns = statistics.median(mj)
    ours_ns = {k: statistics.median(r[k] for r in rust) for k in rust[0]}
    ratio = ours_ns["semi_implicit_euler"] / mj_ns
    w = 34
    print(f"{'mj_step':<{w}}{mj_ns:9.1f} ns/step")
    print(f"{'ours semi_implicit_euler':<{w}}{ours_ns['semi_implicit_euler']:9.1f} ns/step   ratio ours / mj_step = "
          f"{ratio:.3f} (target <= 1.0: {'met' if ratio <= 1.0 else 'NOT met'})")
    print(f"{'ours rk4_split (default)':<{w}}{ours_ns['rk4_split']:9.1f} ns/step   "
          f"({ours_ns['rk4_split'] / mj_ns:.2f} x mj_step)")
    for k, v in ours_ns.items():
        if k not in ("semi_implicit_euler", "rk4_split"):
            print(f"{'ours ' + k:<{w}}{v:9.1f} ns/step")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({
                "mujoco_version": mujoco.__version__, "dt": args.dt, "mj_step_ns": mj_ns, "ours_ns": ours_ns,
                "ratio": ratio, "rounds": {"mj_step_ns": mj, "ours_ns": rust},
                "model_check": {"body_mass": mass_diff, "mass_matrix": m_diff, "gravity": g_diff},
                "agreement_rad": {"semi_implicit_euler": diff_sie, "rk4_split": diff_rk4}, "fall_s": args.fall,
            }, f, indent=2)
    if not (model_ok and agree_ok):
        sys.exit("model check or agreement failed")


if __name__ == "__main__":
    main()
