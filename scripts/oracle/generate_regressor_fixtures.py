#!/usr/bin/env python3
"""Pinocchio's joint-torque regressor on the oracle arms (fixtures of admittance-dynamics).

Writes crates/dynamics/tests/fixtures/regressor/<name>.json for every random arm of
arms/ and for models/baxter_left_arm.urdf: random states
(q, v, a) with `pin.computeJointTorqueRegressor` and `pin.rnea`, after checking that
`Y @ pi == rnea` with pi from `Inertia.toDynamicParameters` (Pinocchio's own consistency).
Run through scripts/oracle/generate_fixtures.sh (same virtual environment).
"""
import json
import os
import sys

import numpy as np
import pinocchio as pin

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import generate_fixtures as gf  # noqa: E402  (the Arm class and the JSON layout)

SEED = 20261125
CASES = 4
OUT = os.path.join(os.path.dirname(gf.OUT_DIR), "regressor")


def cases(arm, rng):
    m, d = arm.model, arm.data
    pi = np.concatenate([m.inertias[i].toDynamicParameters() for i in range(1, m.njoints)])
    out = []
    for _ in range(CASES):
        q, v, a = arm.random_state(rng)
        qp = arm.q_pin(q)
        y = pin.computeJointTorqueRegressor(m, d, qp, v, a).copy()
        tau = pin.rnea(m, d, qp, v, a).copy()
        assert np.allclose(y @ pi, tau, rtol=1e-10, atol=1e-10), (arm.path, y @ pi - tau)
        out.append({"q": q.tolist(), "v": v.tolist(), "a": a.tolist(),
                    "regressor": y.tolist(), "tau": tau.tolist()})
    return pi, out


def write(name, urdf_rel, arm, rng):
    pi, cs = cases(arm, rng)
    doc = {"urdf": urdf_rel, "base": arm.base, "tip": arm.tip,
           "joints": [j["name"] for j in arm.moving],
           "pinocchio_version": pin.__version__,
           "parameters": pi.tolist(), "cases": cs}
    with open(os.path.join(OUT, name + ".json"), "w") as f:
        f.write(gf.dump(doc) + "\n")


def main():
    rng = np.random.default_rng(SEED)
    os.makedirs(OUT, exist_ok=True)
    names = sorted(f[:-5] for f in os.listdir(gf.ARMS_DIR) if f.endswith(".urdf"))
    for name in names:
        path = os.path.join(gf.ARMS_DIR, name + ".urdf")
        tip = json.load(open(os.path.join(gf.OUT_DIR, name + ".json")))["tip"]
        write(name, "../arms/%s.urdf" % name, gf.Arm(path, "base_link", tip), rng)
    write("baxter_left_arm", "../../../../../models/baxter_left_arm.urdf",
          gf.Arm(gf.BAXTER, "base", "left_hand"), rng)
    print("pinocchio %s: regressor of %d arms x %d cases, Y pi == rnea checked"
          % (pin.__version__, len(names) + 1, CASES))


if __name__ == "__main__":
    sys.exit(main())
