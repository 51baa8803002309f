"""Python call overhead of the bindings (issue 15, part 4): `obs.update` of the momentum
observer and `ctl.step` of the paper's neural controller on the Baxter arm, called from Python,
against the same call made from Rust on the same object in the same process.

Each round times `--calls` calls from a Python loop (time.perf_counter_ns around the loop, so
the loop's own cost counts as overhead) and `--calls` calls of the same Rust method with the
same arguments from a Rust loop (the objects' `_rust_update_seconds` / `_rust_step_seconds`
hooks), the two in alternating order from round to round so that both see the same machine
load. Prints every round and the medians of the per-call times, of their difference and of
their ratio. Run through python_overhead.sh, which builds the package in release mode.
"""

import argparse
import pathlib
import statistics
import time

import numpy as np

import admittance as adm

ROOT = pathlib.Path(__file__).resolve().parents[2]
Q0 = np.array([0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5])
DT = 1e-3


def python_seconds(call, calls):
    start = time.perf_counter_ns()
    for _ in range(calls):
        call()
    return (time.perf_counter_ns() - start) * 1e-9 / calls


def cases(m):
    rng = np.random.default_rng(0)
    q = Q0 + rng.uniform(-0.05, 0.05, 7)
    qd, qdd = rng.uniform(-0.3, 0.3, 7), rng.uniform(-1.0, 1.0, 7)
    tau = adm.rnea(m, q, qd, qdd)
    est = np.zeros(7)
    obs = adm.MomentumObserver(m, gain=50.0)
    ctl = adm.NeuralController(m)  # the paper's experiment A: two 512-node networks
    out = np.empty(7)
    obs_args = (0.0, q, qd, qdd, tau, DT)
    # At rest: the same measured q at every call with a velocity would be a stale
    # measurement, and the controller would run its (cheaper) safe hold instead of its law.
    ctl_args = (0.0, q, np.zeros(7), Q0, np.zeros(7), np.zeros(7), est, DT)
    cases.objects = (obs, ctl)
    return [
        ("MomentumObserver.update", lambda: obs.update(*obs_args),
         lambda n: obs._rust_update_seconds(*obs_args, n)),
        ("MomentumObserver.update(out=)", lambda: obs.update(*obs_args, out=out),
         lambda n: obs._rust_update_seconds(*obs_args, n)),
        ("NeuralController.step", lambda: ctl.step(*ctl_args),
         lambda n: ctl._rust_step_seconds(*ctl_args, n)),
        ("NeuralController.step(out=)", lambda: ctl.step(*ctl_args, out=out),
         lambda n: ctl._rust_step_seconds(*ctl_args, n)),
    ]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rounds", type=int, default=9)
    p.add_argument("--calls", type=int, default=20000)
    args = p.parse_args()
    m = adm.Model.from_urdf(ROOT / "models" / "baxter_left_arm.urdf", base="base", tip="left_hand")
    rows = []
    for name, py_call, rust_call in cases(m):
        py_call(), rust_call(100)  # warm up
        py_us, rust_us = [], []
        for r in range(args.rounds):
            if r % 2 == 0:
                py_us.append(python_seconds(py_call, args.calls) * 1e6)
                rust_us.append(rust_call(args.calls) * 1e6)
            else:
                rust_us.append(rust_call(args.calls) * 1e6)
                py_us.append(python_seconds(py_call, args.calls) * 1e6)
        for obj in cases.objects:
            # Every timed call ran the normal law, not a fault path.
            assert obj.fault is None and obj.fault_count == 0, (name, obj.fault)
        diff = [a - b for a, b in zip(py_us, rust_us)]
        ratio = [a / b for a, b in zip(py_us, rust_us)]
        print(f"{name}: rounds (python us / rust us): "
              + ", ".join(f"{a:.2f}/{b:.2f}" for a, b in zip(py_us, rust_us)))
        rows.append((name, statistics.median(py_us), statistics.median(rust_us),
                     statistics.median(diff), statistics.median(ratio), max(diff)))
    print()
    print(f"medians over {args.rounds} alternating rounds of {args.calls} calls (Baxter, 7 joints)")
    print(f"{'call':<32}{'python us':>10}{'rust us':>10}{'diff us':>10}{'ratio':>8}{'max diff':>10}")
    for name, py, rust, diff, ratio, worst in rows:
        print(f"{name:<32}{py:>10.3f}{rust:>10.3f}{diff:>10.3f}{ratio:>8.2f}{worst:>10.3f}")
    worst_median = max(r[3] for r in rows)
    print(f"bar (at most 2 us above the Rust call): {'met' if worst_median <= 2.0 else 'NOT met'}"
          f" (largest median difference {worst_median:.3f} us)")


if __name__ == "__main__":
    main()
