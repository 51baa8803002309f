"""One job of a sweep: what it is (``Job``), how it runs into a folder (``execute``), and how
its folder is committed (``commit``): written whole in a hidden temporary folder inside the
sweep's folder, then renamed to the job's name, so a folder under that name is always a
finished job."""

from __future__ import annotations

import json
import math
import os
import pathlib
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

#: The file every finished job folder holds (its spec, status, time, metrics).
JOB_FILE = "job.json"
#: A call job's returned dict, in its folder.
RESULT_FILE = "result.json"
JOB_FORMAT = "admittance-sweep-job"

_NAME = re.compile(r"[^A-Za-z0-9._=,+-]")


def folder_name(text: str) -> str:
    """``text`` as a folder name: characters other than letters, digits and ``._=,+-``
    become ``_``; never empty or hidden."""
    name = _NAME.sub("_", text).strip("_") or "job"
    return "_" + name if name.startswith(".") else name


@dataclass(frozen=True)
class Job:
    """A job: ``kind`` ``"run"`` (``admittance run`` of ``spec["scenario"]`` with
    ``spec["set"]``, ``spec["variant"]``, ``spec["seed"]``) or ``"call"`` (the function
    ``spec["function"]``, ``"module:name"``, called as ``f(folder, **spec["params"])``; it
    writes what it likes into ``folder`` and returns a dict of results)."""

    name: str
    kind: str
    spec: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"name": self.name, "kind": self.kind, "spec": self.spec}

    @staticmethod
    def from_dict(d: dict) -> "Job":
        return Job(d["name"], d["kind"], d["spec"])


@dataclass
class Outcome:
    """How a job ended: ``status`` ``"ok"``, ``"unhealthy"`` (it finished; a health rule of
    the run failed: kept, not re-run) or ``"failed"`` (killed, crashed, refused: not kept)."""

    status: str
    seconds: float
    error: str | None = None
    metrics: dict = field(default_factory=dict)
    host: str = field(default_factory=socket.gethostname)

    @property
    def finished(self) -> bool:
        return self.status in ("ok", "unhealthy")


def describe_exit(code: int, stderr: str) -> str:
    """``killed by signal 9 (SIGKILL)`` or ``exit 3: <last lines of stderr>``."""
    if code < 0:
        try:
            sig = signal.Signals(-code).name
        except ValueError:
            sig = "?"
        what = f"killed by signal {-code} ({sig})"
    else:
        what = f"exit {code}"
    tail = " | ".join(line for line in stderr.strip().splitlines()[-3:] if line.strip())
    return f"{what}: {tail}" if tail else what


def admittance_bin(given: str | None = None) -> str:
    """The ``admittance`` binary: ``given``, ``$ADMITTANCE_BIN``, or the one on ``PATH``."""
    for candidate in (given, os.environ.get("ADMITTANCE_BIN")):
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    found = shutil.which("admittance")
    if found:
        return found
    raise FileNotFoundError(
        "no `admittance` binary: build it (cargo build --release -p admittance-cli) and put it on PATH, "
        "or set ADMITTANCE_BIN"
    )


def run_command(job: Job, dest: pathlib.Path, binary: str) -> list:
    """The ``admittance run`` command line of a run job writing ``dest``."""
    s = job.spec
    cmd = [binary, "run", s["scenario"], "--out", str(dest), "--quiet"]
    for v in s.get("variant") or []:
        cmd += ["--variant", v]
    for kv in s.get("set") or []:
        cmd += ["--set", kv]
    if s.get("seed") is not None:
        cmd += ["--seed", str(s["seed"])]
    if s.get("no_recording"):
        cmd.append("--no-recording")
    return cmd


def execute(job: Job, dest: pathlib.Path, binary: str | None = None) -> Outcome:
    """Runs ``job`` into the folder ``dest`` (empty or absent) in a process of its own, so a
    job that crashes or is killed takes nothing else down."""
    started = time.perf_counter()
    dest.mkdir(parents=True, exist_ok=True)
    if job.kind == "run":
        p = subprocess.run(run_command(job, dest, admittance_bin(binary)), capture_output=True, text=True)
        summary = dest / "summary.json"
        seconds = time.perf_counter() - started
        if p.returncode == 0 or (p.returncode in (1, 4) and summary.is_file()):
            metrics = run_metrics(json.loads(summary.read_text()))
            if p.returncode == 0:
                return Outcome("ok", seconds, metrics=metrics)
            return Outcome("unhealthy", seconds, describe_exit(p.returncode, p.stderr), metrics)
        return Outcome("failed", seconds, describe_exit(p.returncode, p.stderr))
    if job.kind == "call":
        p = subprocess.run(
            [sys.executable, "-m", "admittance.sweep._worker", str(dest)],
            input=json.dumps(job.to_dict()), capture_output=True, text=True,
        )
        seconds = time.perf_counter() - started
        result = dest / RESULT_FILE
        if p.returncode == 0 and result.is_file():
            return Outcome("ok", seconds, metrics=flat_metrics(json.loads(result.read_text()), depth=3))
        return Outcome("failed", seconds, describe_exit(p.returncode, p.stderr))
    return Outcome("failed", 0.0, f"unknown job kind {job.kind!r} (\"run\" or \"call\")")


def _scalar(v):
    if isinstance(v, bool) or v is None or isinstance(v, str):
        return v
    if isinstance(v, (int, float)):
        return v if math.isfinite(v) else str(v)
    return None


def flat_metrics(d: dict, prefix: str = "", depth: int = 2) -> dict:
    """The scalars (numbers, booleans, short strings) of a dict, nested dicts flattened to
    ``a.b`` up to ``depth`` levels; lists are left out (they are in the job's folder)."""
    out = {}
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            if depth > 1:
                out.update(flat_metrics(v, key + ".", depth - 1))
        elif not isinstance(v, (list, tuple)):
            s = _scalar(v)
            if s is not None and not (isinstance(s, str) and len(s) > 40):
                out[key] = s
    return out


def run_metrics(summary: dict) -> dict:
    """A run's scalar metrics per variant (``variant.metric``), from its summary.json;
    timings (``*_us``) are left out: they differ between identical runs."""
    out = {}
    for variant, metrics in (summary.get("variants") or {}).items():
        for k, v in flat_metrics(metrics, depth=1).items():
            if not k.endswith("_us"):
                out[f"{variant}.{k}"] = v
    return out


def temp_folder(out: pathlib.Path, name: str) -> pathlib.Path:
    """A new hidden folder in ``out`` for the job ``name`` to be written in (unpredictable
    name, created exclusively)."""
    return pathlib.Path(tempfile.mkdtemp(prefix=f".{name}.partial-", dir=out))


def commit(job: Job, tmp: pathlib.Path, out: pathlib.Path, outcome: Outcome) -> pathlib.Path:
    """Writes ``job.json`` into ``tmp`` and renames ``tmp`` to ``out/job.name`` (an earlier
    folder of that name, when ``--force`` lets the sweep replace it, is moved aside first
    and removed after)."""
    from admittance import __version__

    doc = {
        "format": JOB_FORMAT,
        "format_version": 1,
        "job": job.name,
        "kind": job.kind,
        "spec": job.spec,
        "status": outcome.status,
        "error": outcome.error,
        "seconds": round(outcome.seconds, 3),
        "host": outcome.host,
        "admittance_version": __version__,
        "finished_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "metrics": outcome.metrics,
    }
    (tmp / JOB_FILE).write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n")
    final = out / job.name
    old = None
    if final.exists():
        old = pathlib.Path(tempfile.mkdtemp(prefix=f".{job.name}.old-", dir=out))
        final.rename(old / "folder")
    os.rename(tmp, final)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return final


def read_job_file(folder: pathlib.Path) -> dict | None:
    """A finished job folder's ``job.json``, or ``None`` when absent or not one."""
    try:
        doc = json.loads((folder / JOB_FILE).read_text())
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) and doc.get("format") == JOB_FORMAT else None
