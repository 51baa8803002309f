"""Survey: `admittance model` on every URDF that the `example-robot-data` package ships, and
`admittance dynamics` against Pinocchio's reduced model for every file that loads.

For each file: load it with the defaults (root link to the default tip). When the default
tip is ambiguous (several chains end at the same depth: legged robots, two-armed robots,
hands), the refusal lists the candidate tips and the file is loaded again with the first
candidate, so that each row says whether its chains load. Every other refusal is printed
with its reason, to be judged: truly unsupported (e.g. no moving joint, a closed loop) or
refused wrongly.

For each loaded chain, Pinocchio (`pin`) builds the whole URDF with a fixed base and locks
every joint off the chain at the positions `admittance model` reports (branches held at
0 unless told otherwise: `buildReducedModel`); RNEA and the mass matrix are compared at
random states inside the joint limits. The worst relative error is printed per file. Then
the same for the arm chains inside larger robots that docs/experiments.md runs (`--base`
below the root, some turned against it: gravity must follow the mount).

Run through scripts/survey/example_robot_data.sh (it makes the virtual environment).
"""

import argparse
import json
import math
import pathlib
import re
import subprocess
import sys

import numpy as np
import pinocchio as pin

ROOT = pathlib.Path(__file__).resolve().parents[2]


# Arm chains inside larger robots (a chain whose base is not the root, sometimes turned
# against it: iCub's chest has its y axis up), as docs/experiments.md runs them:
# (file under robots/, base link, tip link).
ARM_CHAINS = [
    ("tiago_description/robots/tiago_no_hand.urdf", "torso_lift_link", "arm_7_link"),
    ("g1_description/urdf/g1_29dof_rev_1_0.urdf", "torso_link", "left_wrist_yaw_link"),
    ("pr2_description/urdf/pr2.urdf", "torso_lift_link", "l_wrist_roll_link"),
    ("tiago_pro_description/robots/tiago_pro.urdf", "torso_lift_link", "arm_left_7_link"),
    ("icub_description/robots/icub_reduced.urdf", "chest", "l_hand"),
    ("romeo_description/urdf/romeo.urdf", "torso", "l_wrist"),
    ("baxter_description/urdf/baxter.urdf", "right_arm_mount", "right_wrist"),
    ("centauro_description/urdf/centauro.urdf", "torso_2", "arm1_6"),
    ("talos_data/robots/talos_full_v2.urdf", "torso_2_link", "arm_right_7_link"),
    ("alex_description/urdf/alex_nub_hands.urdf", "Torso", "LeftGripperYawLink"),
    ("anymal_b_simple_description/robots/anymal-kinova.urdf", "j2s6s200_link_base", "j2s6s200_link_6"),
    ("b1_description/urdf/b1-z1.urdf", "link00", "link06"),
]

# Refusals that are right: there is no serial arm to model in the file.
UNSUPPORTED = [
    ("no <link> elements", "an empty description (a xacro macro file)"),
    ("no moving joint below the base link", "nothing moves: a rigid body"),
]


def admittance(binary, args):
    out = subprocess.run([binary, *args], capture_output=True, text=True, timeout=120)
    return out.returncode, out.stdout, out.stderr.strip()


def urdf_files():
    """The package's URDFs: cmeel.prefix/share/example-robot-data/robots/**.urdf."""
    found = []
    for site in map(pathlib.Path, sys.path):
        robots = site / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if robots.is_dir():
            found = sorted(robots.rglob("*.urdf"))
            break
    if not found:
        sys.exit("example-robot-data is not installed in this environment")
    return found


def load(binary, urdf):
    """(status, tip, chain text, locked positions, message)."""
    code, out, err = admittance(binary, ["model", "--urdf", str(urdf)])
    tip = None
    status = "loaded"
    if code != 0 and "ambiguous" in err:
        m = re.search(r"end at the same depth: ([^ ]+) \(joint", err)
        if m:
            tip = m.group(1)
            code, out, err = admittance(binary, ["model", "--urdf", str(urdf), "--tip", tip])
            status = "loaded (several chains; --tip {})".format(tip)
    if code != 0:
        return "refused", tip, None, {}, err.splitlines()[-1] if err else f"exit {code}"
    chain = re.search(r"^chain\s+(.*)$", out, re.M).group(1)
    locked = {}
    for m in re.finditer(r"held at ([^;)]*)", out):
        for item in m.group(1).split(", "):
            name, value = item.rsplit("=", 1)
            locked[name] = float(value)
    warnings = len(re.findall(r"^  .*:\d+: ", out, re.M))
    if warnings:
        status += f", {warnings} inertia warning(s)"
    return status, tip, chain, locked, None


def compare(binary, urdf, tip, rng, states, base=None):
    """Worst relative difference of RNEA and CRBA against Pinocchio's reduced model (built
    from the root: joint torques do not depend on the frame the base is expressed in, so a
    chain below a turned base compares as it is)."""
    tip_args = (["--tip", tip] if tip else []) + (["--base", base] if base else [])
    code, out, err = admittance(binary, ["dynamics", "--urdf", str(urdf), *tip_args, "--q", "0"])
    # The first call only learns the joint names (it fails on the count, naming them).
    _, model_out, _ = admittance(binary, ["model", "--urdf", str(urdf), *tip_args])
    rows = re.findall(r"^\s*\d+\s+(\S+)\s+(revolute|continuous|prismatic)\s", model_out, re.M)
    names = [r[0] for r in rows]
    locked = {}
    for m in re.finditer(r"held at ([^;)]*)", model_out):
        for item in m.group(1).split(", "):
            name, value = item.rsplit("=", 1)
            locked[name] = float(value)
    try:
        full = pin.buildModelFromUrdf(str(urdf))
    except Exception as e:  # Pinocchio's own refusal of the file
        return None, f"Pinocchio cannot build it: {str(e).splitlines()[0][:80]}"
    q_lock = pin.neutral(full)
    lock_ids = []
    for jid in range(1, full.njoints):
        name = full.names[jid]
        if name in names:
            continue
        lock_ids.append(jid)
        j = full.joints[jid]
        if name in locked and j.nq == 1:
            q_lock[j.idx_q] = locked[name]
        elif name in locked and j.nq == 2:  # continuous: cos, sin
            q_lock[j.idx_q] = math.cos(locked[name])
            q_lock[j.idx_q + 1] = math.sin(locked[name])
    try:
        reduced = pin.buildReducedModel(full, lock_ids, q_lock)
    except Exception as e:
        return None, f"Pinocchio cannot reduce it: {str(e).splitlines()[0][:80]}"
    data = reduced.createData()
    ours = [reduced.getJointId(n) for n in names]
    if any(j >= reduced.njoints for j in ours) or reduced.nv != len(names):
        return None, "joint sets differ"
    worst = 0.0
    for _ in range(states):
        q, v, a = [], [], []
        pq = pin.neutral(reduced)
        for n, jid in zip(names, ours):
            j = reduced.joints[jid]
            lo, hi = reduced.lowerPositionLimit[j.idx_q], reduced.upperPositionLimit[j.idx_q]
            if j.nq == 2 or not (np.isfinite(lo) and np.isfinite(hi)) or hi - lo > 2 * math.pi:
                x = rng.uniform(-math.pi, math.pi)
            else:
                x = rng.uniform(lo, hi)
            q.append(x)
            if j.nq == 2:
                pq[j.idx_q], pq[j.idx_q + 1] = math.cos(x), math.sin(x)
            else:
                pq[j.idx_q] = x
        v = rng.uniform(-1, 1, len(names))
        a = rng.uniform(-1, 1, len(names))
        pv = np.zeros(reduced.nv)
        pa = np.zeros(reduced.nv)
        for k, jid in enumerate(ours):
            pv[reduced.joints[jid].idx_v] = v[k]
            pa[reduced.joints[jid].idx_v] = a[k]
        fmt = lambda xs: ",".join(repr(float(x)) for x in xs)  # noqa: E731
        code, out, err = admittance(
            binary,
            ["dynamics", "--urdf", str(urdf), *tip_args, "--q", fmt(q), "--v", fmt(v), "--a", fmt(a)],
        )
        if code != 0:
            return None, err.splitlines()[-1]
        result = json.loads(out)
        tau_pin = pin.rnea(reduced, data, pq, pv, pa)
        m_pin = pin.crba(reduced, data, pq)
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        idx = [reduced.joints[j].idx_v for j in ours]
        tau_ours = np.array(result["tau"])
        m_ours = np.array(result["mass_matrix"])
        scale_t = max(1.0, np.abs(tau_pin[idx]).max())
        scale_m = max(1.0, np.abs(m_pin[np.ix_(idx, idx)]).max())
        worst = max(
            worst,
            np.abs(tau_ours - tau_pin[idx]).max() / scale_t,
            np.abs(m_ours - m_pin[np.ix_(idx, idx)]).max() / scale_m,
        )
    return worst, None


def judge(label, worst, why, failures, excused):
    """The comparison's cell text; a relative error above 1e-9, or a chain not compared
    (unless ``excused``), is appended to ``failures``."""
    if worst is None:
        if not excused:
            failures.append(f"{label}: {why}")
        return f"not compared: {why}"
    if worst > 1e-9:
        failures.append(f"{label}: relative error {worst:.1e}")
    return f"{worst:.1e}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--admittance", default=str(ROOT / "target" / "release" / "admittance"))
    parser.add_argument("--states", type=int, default=5)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    files = urdf_files()
    print(f"{len(files)} URDF files in example-robot-data")
    counts = {"loaded": 0, "refused": 0}
    worst_all = 0.0
    failures = []
    print(f"{'file':<58} {'result':<52} {'chain':<40} {'vs Pinocchio'}")
    for f in files:
        short = str(f).split("/robots/")[-1]
        status, tip, chain, _, message = load(args.admittance, f)
        if status == "refused":
            counts["refused"] += 1
            reason = message.split(".urdf", 1)[-1].lstrip(":0123456789 ")
            unsupported = [why for pattern, why in UNSUPPORTED if pattern in message]
            if unsupported:
                print(f"{short:<58} refused, unsupported ({unsupported[0]}): {reason}")
            else:
                failures.append(f"{short}: refused: {reason}")
                print(f"{short:<58} REFUSED: {reason}")
            continue
        counts["loaded"] += 1
        worst, why = compare(args.admittance, f, tip, rng, args.states)
        # Pinocchio's own refusal of a file is not ours.
        text = judge(short, worst, why, failures, excused=bool(why) and why.startswith("Pinocchio"))
        worst_all = max(worst_all, worst or 0.0)
        print(f"{short:<58} {status:<52} {chain:<40} {text}")
    print()
    print(f"loaded {counts['loaded']} of {len(files)}, refused {counts['refused']}; "
          f"worst relative error against Pinocchio {worst_all:.1e} (bar 1e-9)")
    root = next(p for p in files[0].parents if p.name == "robots")
    worst_chains = 0.0
    print()
    print(f"{'arm chain inside a larger robot':<58} {'base -> tip':<52} {'vs Pinocchio'}")
    for rel, base, tip in ARM_CHAINS:
        worst, why = compare(args.admittance, root / rel, tip, rng, args.states, base=base)
        text = judge(f"{rel} {base} -> {tip}", worst, why, failures, excused=False)
        worst_chains = max(worst_chains, worst or 0.0)
        print(f"{rel:<58} {base + ' -> ' + tip:<52} {text}")
    print(f"{len(ARM_CHAINS)} arm chains: worst relative error against Pinocchio {worst_chains:.1e} (bar 1e-9)")
    for f in failures:
        print("  FAILED:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
