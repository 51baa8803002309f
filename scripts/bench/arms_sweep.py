"""The arms table (``python -m admittance.mujoco.arms``) on one core against every core, and
through a local Ray instance (issue 33, part 4). Runs, in the same conditions one after the
other: the table pinned to one core (``taskset -c 0``, one arm at a time), the table on the
process pool over every core (``--jobs`` = the cores), and with ``--ray`` the table through
``--ray local``. Prints the wall times, the ratio pool / one core (bar: at most 0.6 on 2
cores), and whether each arm's ``result.json`` (less its timings) is the same in every run.

Needs the package with the ``mujoco`` extra, example-robot-data (and ray for ``--ray``) in
the running Python (e.g. .venv-ci). Arguments after ``--`` go to every table run
(e.g. ``-- --arms ur3,ur5 --training-duration 20``).

    .venv-ci/bin/python scripts/bench/arms_sweep.py --ray
"""

import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time


def table(out, extra, jobs, ray=None, one_core=False):
    cmd = [sys.executable, "-m", "admittance.mujoco.arms", "--out", str(out), "--quiet", *extra]
    cmd += ["--ray", ray] if ray else ["--jobs", str(jobs)]
    if one_core:
        cmd = ["taskset", "-c", "0", *cmd]
    started = time.perf_counter()
    cpu = _children_cpu()
    p = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - started
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    print(f"  {' '.join(cmd[cmd.index('--out') + 1:cmd.index('--out') + 2])}: wall {seconds:.1f} s, "
          f"CPU {_children_cpu() - cpu:.1f} s", flush=True)
    return seconds


def _children_cpu():
    """User + system CPU seconds of the finished child processes (a Ray run's workers are
    not children: its CPU is not counted)."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def results(out):
    """Each arm's result.json without its timings."""
    got = {}
    for f in sorted(pathlib.Path(out).glob("*/result.json")):
        r = json.loads(f.read_text())
        r.pop("seconds", None)
        got[f.parent.name] = r
    return got


def clock(s):
    s = round(s)
    return f"{s // 60} min {s % 60} s"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ray", action="store_true", help="also run the table through a local Ray instance")
    p.add_argument("--keep", help="keep the run folders under this folder")
    p.add_argument("--rounds", type=int, default=1, help="rounds of (one core, pool), the order alternating (1)")
    p.add_argument("extra", nargs="*", help="arguments for every table run (after --)")
    a = p.parse_args()
    cores = os.cpu_count() or 1
    root = pathlib.Path(a.keep or tempfile.mkdtemp(prefix="arms-sweep-"))
    root.mkdir(parents=True, exist_ok=True)
    try:
        ratios = []
        for r in range(a.rounds):
            load = os.getloadavg()
            # Alternate the order: a load that grows or fades over the rounds favours neither.
            for kind in (("one", "pool") if r % 2 == 0 else ("pool", "one")):
                # A fresh folder each time: the table keeps finished arms and would skip them.
                shutil.rmtree(root / ("one_core" if kind == "one" else "pool"), ignore_errors=True)
                if kind == "one":
                    one = table(root / "one_core", a.extra, 1, one_core=True)
                else:
                    pool = table(root / "pool", a.extra, cores)
            load_after = os.getloadavg()
            ratios.append(pool / one)
            print(f"round {r + 1}: load average {load[0]:.2f} -> {load_after[0]:.2f} ({cores} cores); "
                  f"one core (taskset -c 0, --jobs 1) {clock(one)}, process pool (--jobs {cores}) {clock(pool)}, "
                  f"ratio {pool / one:.2f} (bar <= 0.6)", flush=True)
        if a.rounds > 1:
            print(f"ratios over {a.rounds} rounds: {', '.join(f'{r:.2f}' for r in ratios)}")
        shutil.rmtree(root / "ray", ignore_errors=True)
        ray = table(root / "ray", a.extra, cores, ray="local") if a.ray else None
        base = results(root / "pool")
        print(f"arms: {len(base)}; one core's results equal the pool's: {results(root / 'one_core') == base}")
        if ray is not None:
            print(f"local Ray (--ray local):       {clock(ray)}  ratio {ray / one:.2f}")
            print(f"Ray's results equal the pool's, arm by arm: {results(root / 'ray') == base}")
    finally:
        if not a.keep:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
