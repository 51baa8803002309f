"""Sweeps: many independent jobs (scenario variants over ``--set`` grids, seeds, the arms
table's arms, push sweeps) on every core of this machine, or on a Ray cluster (issue 33
part 4; docs/python.md, "Sweeps").

Each job runs in a process of its own and writes its own folder ``OUT/<job>``: written in a
hidden temporary folder inside ``OUT`` and renamed when complete, so a folder under a job's
name is a finished job (with ``job.json``: its spec, status, time and metrics). A job that
fails or is killed is reported and leaves no folder; running the same sweep again runs only
the jobs without a finished folder (``retries`` re-runs them at once, each alone). The
summary table ``OUT/summary.csv`` gathers every job's metrics.

``python -m admittance.sweep --help`` for the command; from Python::

    jobs = sweep.grid("scenarios/deadzone.toml", {"observer.cutoff_hz": [5, 10]}, seeds=[1, 2])
    result = sweep.run_sweep(jobs, "runs/sweep")          # all cores
    result = sweep.run_sweep(jobs, "runs/sweep", ray="auto")  # a Ray cluster
"""

from __future__ import annotations

import concurrent.futures
import csv
import io
import itertools
import os
import pathlib
import shutil
import sys
from dataclasses import dataclass, field

from .. import _progress
from ._jobs import JOB_FILE, RESULT_FILE, Job, Outcome, commit, execute, folder_name, read_job_file, temp_folder

__all__ = [
    "Job", "Outcome", "SweepResult", "SweepError", "run_job", "call_job", "grid", "run_sweep",
    "summary_table", "JOB_FILE", "RESULT_FILE",
]


class SweepError(ValueError):
    """A sweep that cannot start: a bad job list or an ``OUT`` folder it must not touch."""


def run_job(scenario, sets=(), seed=None, variants=(), name=None, no_recording=False) -> Job:
    """A job that runs ``admittance run SCENARIO --set K=V ... [--seed S] [--variant V]``."""
    sets = [f"{k}={v}" for k, v in sets.items()] if isinstance(sets, dict) else list(sets)
    if name is None:
        parts = [pathlib.Path(scenario).stem, *sets] + ([f"seed={seed}"] if seed is not None else [])
        name = ",".join(parts)
    spec = {"scenario": str(pathlib.Path(scenario).resolve()), "set": sets, "variant": list(variants), "seed": seed}
    if no_recording:
        spec["no_recording"] = True
    return Job(folder_name(name), "run", spec)


def call_job(function: str, params: dict, name: str) -> Job:
    """A job that calls ``function`` (``"module:name"``, importable where the job runs) as
    ``f(folder, **params)``; ``params`` must be JSON values."""
    return Job(folder_name(name), "call", {"function": function, "params": params})


def grid(scenario, axes: dict, seeds=None, fixed=(), variants=(), no_recording=False) -> list:
    """One run job per point of the grid: every combination of ``axes`` (key -> values, as
    ``--set key=value``) and of ``seeds``; ``fixed``: ``--set`` given to every job."""
    keys = list(axes)
    jobs = []
    for values in itertools.product(*(axes[k] for k in keys)):
        for seed in seeds if seeds else [None]:
            point = [f"{k}={v}" for k, v in zip(keys, values)]
            name = ",".join(point + ([f"seed={seed}"] if seed is not None else [])) or pathlib.Path(scenario).stem
            jobs.append(run_job(scenario, list(fixed) + point, seed, variants, name, no_recording))
    return jobs


@dataclass
class SweepResult:
    """The rows of the summary (one per job, in the jobs' order), what failed, and where."""

    out: pathlib.Path
    rows: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    ran: list = field(default_factory=list)
    skipped: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.failed


def _check(jobs, out: pathlib.Path, force: bool):
    """Refuses duplicate names, and a folder under a job's name that is not that job's."""
    names = [j.name for j in jobs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise SweepError(f"two jobs named {dup[0]!r}: give each job its own name")
    finished = {}
    for job in jobs:
        folder = out / job.name
        if not folder.exists():
            continue
        doc = read_job_file(folder)
        if doc is None or doc.get("spec") != job.spec or doc.get("kind") != job.kind:
            if force:
                continue
            why = "was not written by a sweep" if doc is None else "holds a different job (other settings)"
            raise SweepError(
                f"{folder} {why}: choose another --out, or --force to replace it"
            )
        finished[job.name] = doc
    return finished


def _log(text):
    _progress.log_line(text)


def run_sweep(jobs, out, jobs_n=None, ray=None, retries=0, force=False, binary=None, log=_log) -> SweepResult:
    """Runs every job of ``jobs`` that has no finished folder in ``out``: ``jobs_n`` at a
    time (default: every core), or on the Ray cluster at ``ray``; failed jobs are re-run
    alone up to ``retries`` times. Writes ``out/summary.csv``; returns the ``SweepResult``."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    jobs = list(jobs)
    finished = _check(jobs, out, force)
    todo = [j for j in jobs if j.name not in finished]
    result = SweepResult(out, skipped=[j.name for j in jobs if j.name in finished])
    if result.skipped:
        log(f"sweep: {len(result.skipped)} of {len(jobs)} jobs already finished in {out} (kept)")
    outcomes = {}
    bar = _progress.Bar(f"sweep: {len(todo)} jobs", len(todo))
    try:
        for attempt in range(retries + 1):
            if not todo:
                break
            if attempt:
                log(f"sweep: re-running {len(todo)} failed job(s), one at a time (retry {attempt} of {retries})")
            width = 1 if attempt else jobs_n
            for job, outcome in _run_all(todo, out, width, ray, binary):
                outcomes[job.name] = outcome
                result.ran.append(job.name)
                if outcome.finished:
                    bar.update()
                else:
                    log(f"sweep: {job.name} failed: {outcome.error}")
            todo = [j for j in todo if not outcomes[j.name].finished]
    finally:
        bar.close()
    result.failed = [j.name for j in todo]
    for job in jobs:
        if job.name in finished:
            doc = finished[job.name]
            row = _row(job, doc["status"], doc.get("seconds"), doc.get("error"), doc.get("metrics", {}))
        else:
            o = outcomes.get(job.name) or Outcome("failed", 0.0, "not run")
            row = _row(job, o.status, o.seconds, o.error, o.metrics)
        result.rows.append(row)
    _write_csv(out / "summary.csv", result.rows)
    return result


def _run_all(todo, out, width, ray, binary):
    """Yields ``(job, outcome)`` as jobs finish; commits the folders of finished ones."""
    if ray is not None:
        from ._ray import run_on_ray, unpack

        for job, outcome, blob in run_on_ray(ray, todo, binary):
            if outcome.finished:
                tmp = temp_folder(out, job.name)
                unpack(blob, tmp)
                commit(job, tmp, out, outcome)
            yield job, outcome
        return
    width = max(1, min(width or os.cpu_count() or 1, len(todo)))
    # Threads only wait: every job runs in a process of its own (execute), so a killed or
    # crashed job fails alone.
    with concurrent.futures.ThreadPoolExecutor(max_workers=width) as pool:
        futures = {pool.submit(_local, job, out, binary): job for job in todo}
        try:
            for f in concurrent.futures.as_completed(futures):
                yield futures[f], f.result()
        except BaseException:
            for f in futures:
                f.cancel()
            raise


def _local(job, out, binary):
    tmp = temp_folder(out, job.name)
    try:
        outcome = execute(job, tmp, binary)
    except Exception as e:  # noqa: BLE001  (the job's failure, reported)
        outcome = Outcome("failed", 0.0, f"{type(e).__name__}: {e}")
    if outcome.finished:
        try:
            commit(job, tmp, out, outcome)
            return outcome
        except OSError as e:
            outcome = Outcome("failed", outcome.seconds, f"could not commit the folder: {e}")
    shutil.rmtree(tmp, ignore_errors=True)
    return outcome


def _params(job):
    if job.kind == "run":
        p = {}
        for kv in job.spec.get("set") or []:
            k, _, v = kv.partition("=")
            p[k] = v
        if job.spec.get("seed") is not None:
            p["seed"] = job.spec["seed"]
        return p
    return {k: v for k, v in job.spec.get("params", {}).items() if not isinstance(v, (dict, list))}


def _row(job, status, seconds, error, metrics):
    row = {"job": job.name, "status": status, "seconds": None if seconds is None else round(seconds, 2)}
    row.update({f"param.{k}": v for k, v in _params(job).items()})
    row.update(metrics)
    row["error"] = error or ""
    return row


def _columns(rows):
    cols = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    cols.remove("error")
    return cols + ["error"]


def _write_csv(path: pathlib.Path, rows):
    """The summary, written atomically (a temporary file beside it, renamed)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=_columns(rows) if rows else ["job"], lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    import tempfile

    fd, tmp = tempfile.mkstemp(prefix=".summary.csv.", dir=path.parent)
    with os.fdopen(fd, "w") as f:
        f.write(buf.getvalue())
    os.replace(tmp, path)


def summary_table(rows, columns=None, max_columns=8) -> str:
    """The summary as aligned text: job, status, seconds, the parameters, then ``columns``
    (default: the first metrics, up to ``max_columns`` in all)."""
    if not rows:
        return "(no jobs)\n"
    allc = _columns(rows)
    base = [c for c in allc if c in ("job", "status", "seconds") or c.startswith("param.")]
    if columns is None:
        extra = [c for c in allc if c not in base and c != "error"][: max(0, max_columns - len(base))]
    else:
        extra = list(columns)
    cols = base + extra + (["error"] if any(r.get("error") for r in rows) else [])

    def cell(v):
        if isinstance(v, float):
            return f"{v:.4g}"
        return "" if v is None else str(v)

    table = [[c.removeprefix("param.") for c in cols]] + [[cell(r.get(c)) for c in cols] for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(cols))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(row, widths)).rstrip() for row in table]
    return "\n".join(lines) + "\n"


def print_summary(result: SweepResult, columns=None, file=sys.stdout):
    print(summary_table(result.rows, columns), end="", file=file)
