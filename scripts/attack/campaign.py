#!/usr/bin/env python3
"""The attack campaign of issue 34, repeatable: damaged bags, broken CSVs, edited
identification files (checksum recomputed), foreign networks, special files and planted
links, absurd samples through the C ABI, bad arrays through the Python API.

    .venv-ci/bin/python scripts/attack/campaign.py                  # every family, every case
    .venv-ci/bin/python scripts/attack/campaign.py --limit 20       # at most 20 cases a family
    .venv-ci/bin/python scripts/attack/campaign.py --families bags,cabi --seed 3 --keep

Each case runs in its own process (the CLI, or a Python interpreter for the API and the
C ABI through ctypes), sequentially, with a timeout, and is classified:
  panic           exit 101, `panicked` or a PanicException
  abort           killed by a signal (exit 134, SIGSEGV, SIGKILL of the OOM killer, ...)
  hang            still running at the timeout
  wrong-success   exit 0 / no exception, but the input had to be refused, or the output is
                  non-finite, physically impossible, or not what a clean run gives
  refusal         non-zero exit or exception, its message in one or two lines
  refusal-unclear a refusal without a message, or with a message of more than two lines
  refused-valid   a control case (a valid input, or the clean run a C ABI case compares
                  with) was refused: the campaign no longer tests what it means to
  ok              exit 0 and the output passes the case's checks
A table per family, then the totals; exit 1 if any case is a panic, abort, hang,
wrong-success or refused-valid. Needs target/release/admittance and target/release/libadmittance_ffi.so
(`cargo build --release -p admittance-cli -p admittance-ffi`) and the `admittance` Python
package in the interpreter that runs this (docs/python.md).
"""
import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))

import families_api  # noqa: E402
import families_files  # noqa: E402
from common import Env  # noqa: E402

FAILURES = ("panic", "abort", "hang", "wrong-success", "refused-valid")
COLUMNS = ("cases", "ok", "refusal", "refusal-unclear") + FAILURES
FAMILIES = {
    "bags": families_files.bags,
    "csv": families_files.csvs,
    "ident": families_files.identification_files,
    "crossfile": families_files.cross_files,
    "special": families_files.special_files,
    "cabi": families_api.c_abi,
    "python": families_api.python_api,
}


def run_process(argv, timeout, cwd, case_dir):
    """Runs argv with its output in files; returns (exit code or None on timeout, stdout,
    stderr, peak RSS in MB as sampled every 10 ms, seconds). A negative code is the signal
    that killed it."""
    out_path, err_path = case_dir / "stdout", case_dir / "stderr"
    start = time.monotonic()
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        proc = subprocess.Popen(
            argv, cwd=cwd, stdout=out, stderr=err, stdin=subprocess.DEVNULL,
            start_new_session=True)
    code, rss = None, 0.0
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            code = -os.WTERMSIG(status) if os.WIFSIGNALED(status) else os.WEXITSTATUS(status)
            proc.returncode = code
            break
        rss = max(rss, _hwm_mb(proc.pid))
        if time.monotonic() - start > timeout:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            _, status, usage = os.wait4(proc.pid, 0)
            proc.returncode = -9
            break
        time.sleep(0.01)
    seconds = time.monotonic() - start
    read = lambda p: p.read_bytes().decode("utf-8", "replace")  # noqa: E731
    return code, read(out_path), read(err_path), rss, seconds


def _hwm_mb(pid):
    """The process's peak resident memory so far (MB), from /proc (0 when gone)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def message_lines(stderr):
    """The lines of a refusal's message: stderr without progress and warnings."""
    lines = [l for l in stderr.splitlines() if l.strip()]
    keep = [l for l in lines if not l.lower().startswith(("warning", "  "))]
    return keep[-3:] if keep else lines[-3:]


def classify(case, code, stdout, stderr):
    """(class, detail) of one finished case."""
    if code is None:
        return "hang", f"still running after {case.timeout:.0f} s"
    if code == 101 or "panicked" in stderr or "PanicException" in stderr:
        line = next((l for l in stderr.splitlines() if "panicked" in l or "Panic" in l), "")
        return "panic", line[:300]
    if code < 0 or code in (134, 137, 139):
        return "abort", f"exit {code}: {stderr.strip().splitlines()[-1][:300] if stderr.strip() else ''}"
    if code == 0:
        if case.expect == "refuse":
            return "wrong-success", "exit 0, but this input had to be refused"
        problem = case.check(stdout, stderr) if case.check else None
        if problem:
            return "wrong-success", problem
        return "ok", ""
    lines = message_lines(stderr)
    text = " | ".join(lines)
    if not lines:
        return "refusal-unclear", f"exit {code} without a message"
    error_lines = [l for l in stderr.splitlines() if "error" in l.lower() or l.startswith("admittance")]
    if len(error_lines) > 2 and len(lines) > 2 and case.kind == "cli":
        return "refusal-unclear", text[:400]
    if "checksum mismatch" in stderr and case.family == "ident":
        return "refusal-unclear", "the campaign did not recompute the checksum: " + text[:200]
    if case.expect == "ok":
        return "refused-valid", text[:300]
    return "refusal", text[:300]


def run_case(case, env, index):
    case_dir = env.work / "cases" / f"{case.family}-{index:04d}"
    case_dir.mkdir(parents=True, exist_ok=True)
    if case.prepare:
        case.prepare(case_dir)
    argv = case.argv(case_dir) if callable(case.argv) else case.argv
    code, stdout, stderr, rss, seconds = run_process(argv, case.timeout, case.cwd or case_dir, case_dir)
    kind, detail = classify(case, code, stdout, stderr)
    if kind == "ok" and case.after:
        problem = case.after(case_dir)
        if problem:
            kind, detail = "wrong-success", problem
    elif case.after and kind != "hang":
        problem = case.after(case_dir)
        if problem:  # a refused run must not have written through a link either
            kind, detail = "wrong-success", f"{kind}, but {problem}"
    if kind not in FAILURES and not env.keep:
        shutil.rmtree(case_dir, ignore_errors=True)
    return kind, detail, rss, seconds


def table(rows):
    width = max(len(r[0]) for r in rows)
    head = f"{'family':<{width}} " + " ".join(f"{c:>15}" for c in COLUMNS)  # noqa: E231
    print(head)
    for name, counts in rows:
        print(f"{name:<{width}} " + " ".join(f"{counts.get(c, 0):>15}" for c in COLUMNS))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--limit", type=int, default=0, help="at most this many cases a family (a seeded sample)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds a case may run")
    ap.add_argument("--keep", action="store_true", help="keep every case's folder (failures are always kept)")
    ap.add_argument("--verbose", action="store_true", help="one line per case")
    args = ap.parse_args()
    binary = ROOT / "target/release/admittance"
    library = ROOT / "target/release/libadmittance_ffi.so"
    for f in (binary, library):
        if not f.exists():
            sys.exit(f"{f} is missing: cargo build --release -p admittance-cli -p admittance-ffi")
    work = Path(tempfile.mkdtemp(prefix="admittance-attack-"))
    env = Env(root=ROOT, binary=binary, library=library, python=sys.executable, work=work,
              seed=args.seed, timeout=args.timeout, keep=args.keep)
    print(f"work folder: {work}", flush=True)
    started = time.monotonic()
    env.prepare()
    print(f"fixtures ready after {time.monotonic() - started:.0f} s", flush=True)
    rows, failures, slowest = [], [], (0.0, "")
    for name in args.families.split(","):
        cases = list(FAMILIES[name](env))
        if args.limit and len(cases) > args.limit:
            cases = random.Random(args.seed).sample(cases, args.limit)
        counts = {"cases": len(cases)}
        family_start = time.monotonic()
        peak = 0.0
        for i, case in enumerate(cases):
            case.family = name
            kind, detail, rss, seconds = run_case(case, env, i)
            counts[kind] = counts.get(kind, 0) + 1
            peak = max(peak, rss)
            slowest = max(slowest, (seconds, f"{name}: {case.name}"))
            if args.verbose or kind in FAILURES:
                print(f"  [{kind}] {name}: {case.name} ({seconds:.1f} s, {rss:.0f} MB){': ' + detail if detail else ''}", flush=True)
            if kind in FAILURES:
                failures.append((name, case, kind, detail, i))
        counts["seconds"] = time.monotonic() - family_start
        print(f"{name}: {len(cases)} cases in {counts['seconds']:.0f} s, peak RSS {peak:.0f} MB", flush=True)
        rows.append((name, counts))
    totals = {c: sum(r[1].get(c, 0) for r in rows) for c in COLUMNS}
    print()
    table(rows + [("total", totals)])
    print(f"\n{totals['cases']} cases in {time.monotonic() - started:.0f} s; slowest case {slowest[0]:.1f} s ({slowest[1]})")
    for name, case, kind, detail, i in failures:
        argv = case.argv(env.work / "cases" / f"{name}-{i:04d}") if callable(case.argv) else case.argv
        print(f"FAIL [{kind}] {name}: {case.name}\n    {' '.join(map(str, argv))}\n    {detail}")
    if failures:
        print(f"kept: {work}")
        sys.exit(1)
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
