"""The floor the observers' filters set under the pushes of `python -m admittance.mujoco.arms`:
MuJoCo's true external torque of the pushed evaluation recording passed through the filter
chain every observer's estimate passes (the 40 Hz sensor filter, the 10 Hz input
conditioning, the momentum observer's first-order lag K_O = 50 1/s, the 5 Hz estimate
low-pass), stage by stage, scored with the table's NRMSE. A perfect model scores this.

    python scripts/mujoco/arms_filter_floor.py ARM      # e.g. ur5 (the names of --list)

docs/experiments.md ("Why the UR3 and the UR5 miss 0.2") has the numbers.
"""
import math
import sys

import numpy as np

import admittance as adm
from admittance.mujoco import _arms as A
from admittance.mujoco._plant import MujocoArm
name = sys.argv[1]
cfg = A.ArmsConfig()
robots = A.robots_dir(); rel, base, tip = A.ARMS[name]; path = robots / rel
m = adm.Model.from_urdf(str(path)); tip = m.tip_link
arm = MujocoArm(path.read_text(), m.joint_names, tip, m.effort_limit, cfg.dt, cfg.friction_scale)
# The table's pushed recording, exactly: the same motions, gains and generator draws as
# _arms.run_arm (the training, validation and free recordings draw the noise first).
train, _ = A.excitation_motion(m, cfg.training_duration, cfg.training_seed, cfg.dt)
ev, _ = A.excitation_motion(m, cfg.evaluation_duration, cfg.evaluation_seed, cfg.dt)
valid, _ = A.excitation_motion(m, cfg.validation_duration, cfg.validation_seed, cfg.dt)
gains = A.recording_gains(m, train["q"].mean(axis=0), arm.terms)
rng = np.random.default_rng(cfg.seed)
for motion in (train, valid, ev):
    A.record(arm, m, motion, gains, cfg, rng)
push, peak, windows = A.push_schedule(cfg, m, cfg.evaluation_duration, rng)
data, true, _ = A.record(arm, m, ev, gains, cfg, rng, push)
t = data["t"]; n = m.n
def chain(x, stages):
    y = x
    for s in stages:
        if s[0] == "bw":
            c = adm.InputConditioner(n, s[1], 1000.0); out = np.zeros_like(y)
            for k in range(len(y)): out[k] = c.update(np.zeros(n), y[k])[3]
            y = out
        else:
            a = cfg.dt / (cfg.dt + 1.0 / s[1]); out = np.zeros_like(y); z = np.zeros(n)
            for k in range(len(y)): z += a * (y[k] - z); out[k] = z
            y = out
    return y
w5 = 2*math.pi*5
for label, st in [("5 Hz only (oracle)", [("lp", w5)]), ("+ K_O 50", [("lp", 50.0), ("lp", w5)]),
                  ("+ 10 Hz conditioning", [("bw", 10.0), ("lp", 50.0), ("lp", w5)]),
                  ("+ 40 Hz sensors (whole chain)", [("bw", 40.0), ("bw", 10.0), ("lp", 50.0), ("lp", w5)]),
                  ("whole chain, 20 Hz estimate", [("bw", 40.0), ("bw", 10.0), ("lp", 50.0), ("lp", 2*math.pi*20)])]:
    print(name, label, round(A.push_nrmse(chain(true, st), true, t, cfg), 3))
