"""Fake sweep jobs for tests/test_sweep.py (imported by the job processes: the test puts this
folder on PYTHONPATH). Each appends its name to a log file, so a test sees which jobs ran."""

import json
import os
import pathlib
import signal


def square(folder, x, log, kill_flag=None):
    """Writes ``value.json`` with ``x`` squared; killed by SIGKILL half-way when the file
    ``kill_flag`` exists (a job that dies mid-way, its folder half written)."""
    with open(log, "a") as f:
        f.write(f"{x}\n")
    folder = pathlib.Path(folder)
    (folder / "partial.txt").write_text("started\n")
    if kill_flag and os.path.exists(kill_flag):
        os.kill(os.getpid(), signal.SIGKILL)
    (folder / "value.json").write_text(json.dumps({"x": x, "square": x * x}) + "\n")
    return {"x": x, "square": x * x, "nested": {"double": 2 * x}}


def fails(folder, message):
    raise ValueError(message)
