"""``python -m admittance.sweep SCENARIO --out DIR --grid KEY=V1,V2 [--seeds 1,2] ...``:
``admittance run`` over a grid of ``--set`` values and seeds, every core at once (or a Ray
cluster with ``--ray ADDRESS``), one run folder per point and a summary table. Exit codes:
0 every job finished, 1 some job failed (the others are kept: run the same command again to
run only those), 2 bad arguments or Ray missing, 3 the --out folder cannot be used, 130
interrupted (finished folders kept)."""

from __future__ import annotations

import argparse
import pathlib
import sys


def split_values(text: str) -> list:
    """``a,b,[1,2]`` -> ``["a", "b", "[1,2]"]``: commas inside brackets or quotes stay."""
    out, depth, quote, cur = [], 0, None, ""
    for c in text:
        if quote:
            quote = None if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c in "[{(":
            depth += 1
        elif c in "]})":
            depth -= 1
        elif c == "," and depth == 0:
            out.append(cur)
            cur = ""
            continue
        cur += c
    out.append(cur)
    return [v.strip() for v in out if v.strip()]


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m admittance.sweep",
        description="admittance run over a grid of --set values and seeds: one run folder per point "
        "(written atomically), all cores at once or a Ray cluster, and a summary table (summary.csv).",
    )
    p.add_argument("scenario", help="the scenario file (TOML)")
    p.add_argument("--out", required=True, help="the sweep's folder: one folder per job, and summary.csv")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a swept value: one job per value (repeatable: every combination)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a value set in every job")
    p.add_argument("--seeds", help="comma-separated seeds of the sensor noise: one job per seed")
    p.add_argument("--variant", action="append", default=[], metavar="NAME", help="run only this variant (repeatable)")
    p.add_argument("--no-recording", action="store_true", help="skip each run's MCAP recording")
    p.add_argument("--jobs", type=int, default=None, help="jobs at once (default: every core)")
    p.add_argument("--ray", metavar="ADDRESS", help="run the jobs on the Ray cluster at ADDRESS ('auto': the running one; "
                   "'local': a Ray instance started on this machine)")
    p.add_argument("--retries", type=int, default=0, help="re-run a failed job at once, alone, up to this many times (0)")
    p.add_argument("--force", action="store_true", help="replace job folders that hold other settings or were not written by a sweep")
    p.add_argument("--column", action="append", metavar="METRIC", help="a metric column of the printed table (repeatable; default: the first few)")
    p.add_argument("--admittance-bin", help="the admittance binary (default: $ADMITTANCE_BIN, or admittance on PATH)")
    p.add_argument("--quiet", action="store_true", help="no progress and no table on the terminal")
    a = p.parse_args(argv)

    from admittance import _progress

    from . import SweepError, grid, run_sweep, summary_table

    if a.quiet:
        _progress.set_quiet(True)
    if a.jobs is not None and a.jobs < 1:
        p.error("--jobs must be at least 1")
    if a.retries < 0:
        p.error("--retries must be >= 0")
    if not pathlib.Path(a.scenario).is_file():
        p.error(f"{a.scenario}: no such scenario file")
    axes = {}
    for g in a.grid:
        key, eq, values = g.partition("=")
        if not eq or not key.strip() or not split_values(values):
            p.error(f"--grid {g!r}: expected KEY=V1,V2,... (e.g. --grid observer.cutoff_hz=5,10,20)")
        if key.strip() in axes:
            p.error(f"--grid {key.strip()} given twice: list every value in one --grid")
        axes[key.strip()] = split_values(values)
    for s in a.set:
        if "=" not in s:
            p.error(f"--set {s!r}: expected KEY=VALUE")
    seeds = None
    if a.seeds:
        try:
            seeds = [int(s) for s in split_values(a.seeds)]
        except ValueError:
            p.error(f"--seeds {a.seeds!r}: expected comma-separated integers")
    jobs = grid(a.scenario, axes, seeds, a.set, a.variant, a.no_recording)
    try:
        result = run_sweep(jobs, a.out, a.jobs, a.ray, a.retries, a.force, a.admittance_bin)
    except (SweepError, OSError) as e:
        print(f"admittance.sweep: {e}", file=sys.stderr)
        return 3
    except RuntimeError as e:  # Ray missing or unreachable
        print(f"admittance.sweep: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"admittance.sweep: interrupted; the finished job folders in {a.out} are kept: run the same "
              "command again to go on", file=sys.stderr)
        return 130
    if not a.quiet:
        print(summary_table(result.rows, a.column), end="")
    done = len(jobs) - len(result.failed)
    print(f"admittance.sweep: {done} of {len(jobs)} jobs finished ({len(result.skipped)} earlier); "
          f"summary: {pathlib.Path(a.out) / 'summary.csv'}", file=sys.stderr)
    if result.failed:
        print(f"admittance.sweep: {len(result.failed)} failed ({', '.join(result.failed)}); run the same "
              "command again to run only those", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
