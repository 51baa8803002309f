"""`admittance.sweep`: jobs on every core give the folders a serial run gives; a job killed
mid-way is reported, leaves no folder, and is the only one run again; folders the sweep did
not write are refused; Ray (when installed) gives the pool's folders, file by file."""

import csv
import json
import os
import pathlib
import subprocess
import sys

import pytest

from admittance import sweep
from conftest import ROOT

TESTS = pathlib.Path(__file__).resolve().parent
DEADZONE = ROOT / "scenarios" / "deadzone.toml"
SHORT = ["evaluation_start=0.1"]
#: What differs between two identical runs: wall-clock timings.
VOLATILE_JOB_KEYS = ("seconds", "host", "finished_at")


@pytest.fixture(autouse=True)
def importable_fake_jobs(monkeypatch, admittance_bin):
    """The job processes import tests/sweep_jobs.py, and find the checkout's binary."""
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.setenv("ADMITTANCE_BIN", str(admittance_bin))


def tiny_grid():
    """Four short runs of the deadzone scenario's PD variant: two durations x two seeds."""
    return sweep.grid(DEADZONE, {"duration": [0.3, 0.4]}, seeds=[1, 2], fixed=SHORT, variants=["pd"], no_recording=True)


def square_jobs(tmp_path, xs=(1, 2, 3, 4), kill=None):
    log = tmp_path / "ran.log"
    return [
        sweep.call_job(
            "sweep_jobs:square",
            {"x": x, "log": str(log), **({"kill_flag": str(kill)} if kill and x == 3 else {})},
            f"x={x}",
        )
        for x in xs
    ], log


def _without_timings(value):
    if isinstance(value, dict):
        return {k: _without_timings(v) for k, v in value.items() if not k.endswith("_us")}
    return value


def folder_contents(folder: pathlib.Path) -> dict:
    """A job folder's files, with what wall-clock time changes taken out: job.json's time
    and host, summary.json's and report.md's step timings (report.html: left out)."""
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_dir() or p.name == "report.html":
            continue
        rel = str(p.relative_to(folder))
        if p.name == "job.json":
            doc = json.loads(p.read_text())
            out[rel] = {k: v for k, v in doc.items() if k not in VOLATILE_JOB_KEYS}
        elif p.name == "summary.json":
            out[rel] = _without_timings(json.loads(p.read_text()))
        elif p.name == "report.md":
            out[rel] = [line for line in p.read_text().splitlines() if "_us" not in line]
        else:
            out[rel] = p.read_bytes()
    return out


def sweep_contents(out: pathlib.Path, jobs) -> dict:
    return {j.name: folder_contents(out / j.name) for j in jobs}


def summary_rows(out):
    with open(out / "summary.csv") as f:
        return [{k: v for k, v in r.items() if k != "seconds"} for r in csv.DictReader(f)]


def test_a_grid_on_two_processes_gives_the_serial_folders(tmp_path):
    jobs = tiny_grid()
    assert len(jobs) == 4 and len({j.name for j in jobs}) == 4
    serial = sweep.run_sweep(jobs, tmp_path / "serial", jobs_n=1, log=lambda s: None)
    pool = sweep.run_sweep(jobs, tmp_path / "pool", jobs_n=2, log=lambda s: None)
    assert serial.ok and pool.ok, (serial.rows, pool.rows)
    assert sweep_contents(tmp_path / "serial", jobs) == sweep_contents(tmp_path / "pool", jobs)
    assert summary_rows(tmp_path / "serial") == summary_rows(tmp_path / "pool")
    rows = summary_rows(tmp_path / "pool")
    assert [r["job"] for r in rows] == [j.name for j in jobs]
    assert all(r["status"] == "ok" and r["pd.steps"] in ("300", "400") for r in rows), rows
    # Each folder is a complete run (the run folder of `admittance run`) with its job.json,
    # and no temporary folder is left behind.
    for j in jobs:
        assert (tmp_path / "pool" / j.name / "summary.json").is_file()
        assert json.loads((tmp_path / "pool" / j.name / "job.json").read_text())["status"] == "ok"
    assert not [p for p in (tmp_path / "pool").iterdir() if p.name.startswith(".")]


def test_call_jobs_on_two_processes_give_the_serial_folders(tmp_path):
    jobs, _ = square_jobs(tmp_path)
    a = sweep.run_sweep(jobs, tmp_path / "serial", jobs_n=1, log=lambda s: None)
    b = sweep.run_sweep(jobs, tmp_path / "pool", jobs_n=2, log=lambda s: None)
    assert a.ok and b.ok
    # The log path is in the params: the same in both, so the job specs are equal.
    assert sweep_contents(tmp_path / "serial", jobs) == sweep_contents(tmp_path / "pool", jobs)
    rows = summary_rows(tmp_path / "pool")
    assert [(r["job"], r["square"], r["nested.double"]) for r in rows] == [
        ("x=1", "1", "2"), ("x=2", "4", "4"), ("x=3", "9", "6"), ("x=4", "16", "8")
    ]


def test_a_job_killed_mid_way_is_reported_and_run_again_alone(tmp_path):
    kill = tmp_path / "kill-x3"
    kill.write_text("")
    jobs, log = square_jobs(tmp_path, kill=kill)
    out = tmp_path / "sweep"
    messages = []
    first = sweep.run_sweep(jobs, out, jobs_n=2, log=messages.append)
    assert first.failed == ["x=3"]
    row = next(r for r in first.rows if r["job"] == "x=3")
    assert row["status"] == "failed" and "killed by signal 9" in row["error"], row
    assert any("x=3 failed: killed by signal 9" in m for m in messages), messages
    # The killed job left no folder, not even its temporary one; the others are complete.
    assert not (out / "x=3").exists()
    assert sorted(p.name for p in out.iterdir()) == ["summary.csv", "x=1", "x=2", "x=4"]
    assert sorted(log.read_text().split()) == ["1", "2", "3", "4"]
    # Run again: only the killed job runs.
    kill.unlink()
    log.write_text("")
    second = sweep.run_sweep(jobs, out, jobs_n=2, log=messages.append)
    assert second.ok and second.ran == ["x=3"] and second.skipped == ["x=1", "x=2", "x=4"]
    assert log.read_text().split() == ["3"]
    assert json.loads((out / "x=3" / "value.json").read_text()) == {"x": 3, "square": 9}
    assert [r["status"] for r in summary_rows(out)] == ["ok"] * 4
    # The same folders as a sweep that never failed (but job.json: x=3's spec names the flag).
    clean, _ = square_jobs(tmp_path)
    sweep.run_sweep(clean, tmp_path / "clean", jobs_n=2, log=lambda s: None)

    def files(root):
        return {j: {k: v for k, v in c.items() if k != "job.json"} for j, c in sweep_contents(root, jobs).items()}

    assert files(out) == files(tmp_path / "clean")


def test_retries_run_a_failed_job_again_at_once(tmp_path):
    jobs = [sweep.call_job("sweep_jobs:fails", {"message": "always"}, "bad")]
    r = sweep.run_sweep(jobs, tmp_path / "s", jobs_n=2, retries=2, log=lambda s: None)
    assert r.failed == ["bad"] and r.ran == ["bad"] * 3
    assert "ValueError: always" in r.rows[0]["error"]


def test_folders_it_did_not_write_or_other_settings_are_refused(tmp_path):
    jobs, _ = square_jobs(tmp_path, xs=(1,))
    out = tmp_path / "s"
    (out / "x=1").mkdir(parents=True)
    (out / "x=1" / "mine.txt").write_text("the user's")
    with pytest.raises(sweep.SweepError, match="was not written by a sweep"):
        sweep.run_sweep(jobs, out, log=lambda s: None)
    assert (out / "x=1" / "mine.txt").read_text() == "the user's"
    (out / "x=1" / "mine.txt").unlink()
    (out / "x=1").rmdir()
    sweep.run_sweep(jobs, out, log=lambda s: None)
    (tmp_path / "elsewhere").mkdir()
    other, _ = square_jobs(tmp_path / "elsewhere", xs=(1,))
    with pytest.raises(sweep.SweepError, match="holds a different job"):
        sweep.run_sweep(other, out, log=lambda s: None)
    assert sweep.run_sweep(other, out, force=True, log=lambda s: None).ok
    with pytest.raises(sweep.SweepError, match="two jobs named"):
        sweep.run_sweep(jobs + jobs, out, log=lambda s: None)


def test_the_command_runs_a_grid_and_prints_its_table(tmp_path):
    out = tmp_path / "sweep"
    cmd = [sys.executable, "-m", "admittance.sweep", str(DEADZONE), "--out", str(out), "--variant", "pd",
           "--set", "evaluation_start=0.1", "--grid", "duration=0.3,0.4", "--seeds", "1,2", "--no-recording",
           "--jobs", "2", "--column", "pd.steps"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert lines[0].split() == ["job", "status", "seconds", "evaluation_start", "duration", "seed", "pd.steps"]
    assert len(lines) == 5 and all(" ok " in line for line in lines[1:]), p.stdout
    # Not a terminal: no progress drawn.
    assert "\r" not in p.stderr and "[" not in p.stderr, p.stderr
    assert "4 of 4 jobs finished (0 earlier)" in p.stderr
    again = subprocess.run(cmd, capture_output=True, text=True)
    assert again.returncode == 0 and "4 of 4 jobs finished (4 earlier)" in again.stderr, again.stderr
    bad = subprocess.run(cmd[:-4] + ["--grid", "duration"], capture_output=True, text=True)
    assert bad.returncode == 2 and "--grid 'duration': expected KEY=V1,V2" in bad.stderr


def test_values_with_commas_inside_brackets_stay_whole():
    from admittance.sweep.__main__ import split_values

    assert split_values("1,[2, 3],'a,b'") == ["1", "[2, 3]", "'a,b'"]


def test_on_a_local_ray_instance_the_folders_are_the_pools(tmp_path):
    pytest.importorskip("ray", reason="ray is not installed (pip install './crates/python[ray]')")
    calls, _ = square_jobs(tmp_path)
    jobs = tiny_grid()[:2] + calls
    pool = sweep.run_sweep(jobs, tmp_path / "pool", jobs_n=2, log=lambda s: None)
    ray = sweep.run_sweep(jobs, tmp_path / "ray", ray="local", log=lambda s: None)
    assert pool.ok and ray.ok, ray.rows
    assert sweep_contents(tmp_path / "ray", jobs) == sweep_contents(tmp_path / "pool", jobs)
    assert summary_rows(tmp_path / "ray") == summary_rows(tmp_path / "pool")


def test_the_ray_extra_pins_the_version_ci_installs():
    import re

    pyproject = (ROOT / "crates" / "python" / "pyproject.toml").read_text()
    extra = re.search(r'^ray\s*=\s*\["ray==([^"]+)"\]', pyproject, re.M)
    ci = re.search(r"\bray==(\S+)", (ROOT / ".ci" / "test").read_text())
    assert extra and ci and extra.group(1) == ci.group(1)
