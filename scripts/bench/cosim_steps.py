"""The co-simulation's control steps per second (issue 33, part 3): MuJoCo alone (a Python
loop of ``mj_step`` on the same arm) against a variant of ``python -m admittance.mujoco``
stepped by its Python loop (``run_variant_stepwise``) and in Rust (``adm.CosimStepper``,
what the command runs), in rounds that alternate the three, on the Panda with the push
(or ``--contact wall``).
Prints steps/s by the wall clock and by this process's CPU time (the machine may be
shared), the ratios to MuJoCo alone, and whether both loops ended in the same state with
the same metrics.

Needs the package with the ``mujoco`` extra in the running Python (e.g. .venv-ci):

    .venv-ci/bin/python scripts/bench/cosim_steps.py --variants momentum,oracle --rounds 3
"""

import argparse
import pathlib
import statistics
import time

import numpy as np

import admittance as adm
from admittance.mujoco import _cosim
from admittance.mujoco._plant import MujocoArm

ROOT = pathlib.Path(__file__).resolve().parents[2]
TIMINGS = {"controller_step_median_us"}


def timed(fn):
    wall, cpu = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - wall, time.process_time() - cpu


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--urdf", default=str(ROOT / "models" / "franka_panda.urdf"))
    p.add_argument("--tip", default="panda_hand_tcp")
    p.add_argument("--variants", default="momentum,oracle", help="variants without a network")
    p.add_argument("--duration", type=float, default=30.0)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--contact", choices=["push", "wall"], default="push")
    a = p.parse_args()
    cfg = _cosim.CosimConfig(urdf=a.urdf, tip=a.tip, duration=a.duration, contact=a.contact)
    m = adm.Model.from_urdf(cfg.urdf, tip=cfg.tip)
    q0 = _cosim.home_pose(m)
    pd = _cosim.pd_gains(m, q0)
    text = pathlib.Path(cfg.urdf).read_text()

    def arm(wall=None):
        return MujocoArm(text, m.joint_names, cfg.tip, m.effort_limit, cfg.dt, cfg.friction_scale, wall)

    contact = _cosim.plan_contact(cfg, m, q0, arm())
    steps = int(round(cfg.duration / cfg.dt))
    results = {}

    def mujoco_alone():
        plant = arm(contact.wall)
        plant.set_q(q0)
        step, model, data = plant.mj.mj_step, plant.model, plant.data
        for _ in range(steps):
            step(model, data)

    for r in range(a.rounds):
        t = timed(mujoco_alone)
        results.setdefault("MuJoCo alone (mj_step loop)", []).append(t)
        for variant in a.variants.split(","):
            for stepwise in (r % 2 == 0, r % 2 != 0):
                plant, box = arm(contact.wall), {}

                def run():
                    box["rec"], *_ = _cosim.run_variant(variant, plant, m, {}, q0, pd, cfg, np.random.default_rng(8),
                                                       contact, stepwise=stepwise)
                t = timed(run)
                name = f"{variant}, {'Python loop' if stepwise else 'Rust (CosimStepper)'}"
                results.setdefault(name, []).append(t)
                metrics = {k: v for k, v in box["rec"].metrics.items() if k not in TIMINGS}
                results.setdefault(("check", variant), []).append((metrics, plant.data.qpos.tobytes(), plant.data.qvel.tobytes()))
    alone = statistics.median(steps / w for w, _ in results["MuJoCo alone (mj_step loop)"])
    print(f"{steps} steps per run, median of {a.rounds} rounds")
    print("| loop | steps/s (wall) | steps/s (CPU) | wall ratio to MuJoCo alone |")
    print("|---|---|---|---|")
    for name, times in results.items():
        if isinstance(name, tuple):
            continue
        wall = statistics.median(steps / w for w, _ in times)
        cpu = statistics.median(steps / c for _, c in times)
        print(f"| {name} | {wall:,.0f} | {cpu:,.0f} | {wall / alone:.2f} |")
    for (_, variant), runs in ((k, v) for k, v in results.items() if isinstance(k, tuple)):
        same = all(x == runs[0] for x in runs)
        print(f"{variant}: the Python loop and the Rust steps give the same state and metrics: {same}")


if __name__ == "__main__":
    main()
