"""`python -m admittance.mujoco` as a command (issue 25): without MuJoCo it names the extra
to install. The pin of the `mujoco` extra is the one .ci/run installs."""

import re
import subprocess
import sys

from conftest import ROOT

PANDA = ROOT / "models" / "franka_panda.urdf"


def run_module(args, block_mujoco=False, timeout=120):
    """`python -m admittance.mujoco ARGS` in a fresh interpreter; with `block_mujoco`, as if
    MuJoCo were not installed (`import mujoco` raises ImportError)."""
    block = "sys.modules['mujoco'] = None; " if block_mujoco else ""
    code = (
        "import runpy, sys; " + block
        + "sys.argv = ['python -m admittance.mujoco'] + sys.argv[1:]; "
        + "runpy.run_module('admittance.mujoco', run_name='__main__', alter_sys=True)"
    )
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          timeout=timeout)


def test_without_mujoco_one_line_names_the_extra(tmp_path):
    out = tmp_path / "run"
    p = run_module(["--urdf", str(PANDA), "--out", str(out)], block_mujoco=True)
    assert p.returncode == 2, p.stderr
    assert "Traceback" not in p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, p.stderr
    assert "pip install './crates/python[mujoco]'" in lines[0]
    assert not out.exists()


def test_help_works_without_mujoco():
    p = run_module(["--help"], block_mujoco=True)
    assert p.returncode == 0, p.stderr
    assert "--tip" in p.stdout


def test_the_extra_pins_the_mujoco_that_ci_installs():
    pyproject = (ROOT / "crates" / "python" / "pyproject.toml").read_text()
    extra = re.search(r'^mujoco\s*=\s*\["mujoco==([^"]+)"\]', pyproject, re.M)
    assert extra, "pyproject.toml has no `mujoco` extra pinning mujoco"
    ci = re.search(r"\bmujoco==(\S+)", (ROOT / ".ci" / "run").read_text())
    assert ci, ".ci/run does not pin mujoco"
    assert extra.group(1) == ci.group(1)
