"""Progress on long work: drawn on a terminal only, never when stderr is not a terminal, when
`CI` is set or with --quiet; the Python package's bar and the `admittance` binary's."""

import os
import pty
import select
import subprocess
import sys
import time

import pytest

from admittance import _progress
from conftest import ROOT

BAR_SCRIPT = """
import time
from admittance import _progress
if {quiet}:
    _progress.set_quiet(True)
for _ in _progress.steps(range(30), "counting"):
    time.sleep(0.01)
with _progress.spinner("thinking"):
    time.sleep(0.5)
print("done", flush=True)
"""


def on_terminal(cmd, env, timeout=120):
    """Runs ``cmd`` with stdout and stderr on a pseudo-terminal; returns what it wrote."""
    leader, follower = pty.openpty()
    p = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=follower, stderr=follower, env=env, cwd=ROOT)
    os.close(follower)
    out = b""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([leader], [], [], 0.2)
        if ready:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the child closed the terminal
                break
            if not chunk:
                break
            out += chunk
        elif p.poll() is not None:
            break
    p.wait(timeout=10)
    os.close(leader)
    return p.returncode, out.decode(errors="replace")


def env_without_ci(**extra):
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    env.update(extra)
    return env


def test_nothing_is_drawn_when_stderr_is_not_a_terminal(capfd):
    assert not _progress.enabled()
    for _ in _progress.steps(range(5), "counting"):
        pass
    with _progress.spinner("thinking"):
        pass
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("quiet,ci,drawn", [(False, False, True), (True, False, False), (False, True, False)])
def test_the_python_bar_on_a_terminal(quiet, ci, drawn):
    env = env_without_ci(**({"CI": "true"} if ci else {}))
    code, out = on_terminal([sys.executable, "-c", BAR_SCRIPT.format(quiet=quiet)], env)
    assert code == 0 and "done" in out, out
    assert ("counting [" in out and "thinking (0:00)" in out) == drawn, out
    assert ("\r" in out.replace("\r\n", "\n")) == drawn, out


@pytest.mark.parametrize("flag,ci,drawn", [(None, False, True), ("--quiet", False, False), (None, True, False)])
def test_admittance_run_on_a_terminal(admittance_bin, tmp_path, flag, ci, drawn):
    """A run of several seconds (the PD variant of experiment A, 600 simulated s: about 5 s,
    well past the 1 s after which the bar appears): its stage and bar on a terminal; none
    with --quiet or in CI."""
    cmd = [str(admittance_bin), "run", "scenarios/deadzone.toml", "--variant", "pd", "--set", "duration=600",
           "--no-recording", "--out", str(tmp_path / "run")] + ([flag] if flag else [])
    code, out = on_terminal(cmd, env_without_ci(**({"CI": "true"} if ci else {})))
    assert code == 0, out
    assert ("pd: simulating the closed loop" in out) == drawn, out
