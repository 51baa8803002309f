"""`python -m admittance.mujoco` as a command (issue 25): without MuJoCo it names the extra
to install, Ctrl-C ends it with one line and exit 130, and the run folder it writes has
ordinary permissions and finds the tip as the CLI does. The pin of the `mujoco` extra is
the one .ci/test installs."""

import os
import re
import signal
import stat
import subprocess
import sys
import time
import types

import pytest

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
    ci = re.search(r"\bmujoco==(\S+)", (ROOT / ".ci" / "test").read_text())
    assert ci, ".ci/test does not pin mujoco"
    assert extra.group(1) == ci.group(1)


def test_an_interrupt_is_one_line_and_exit_130(monkeypatch, capsys, tmp_path):
    from admittance.mujoco import __main__ as cmd
    from admittance.mujoco import _cosim

    def interrupted(cfg, log=print):
        raise KeyboardInterrupt

    monkeypatch.setitem(sys.modules, "mujoco", types.ModuleType("mujoco"))
    monkeypatch.setattr(_cosim, "run_cosimulation", interrupted)
    code = cmd.main(["--urdf", str(PANDA), "--out", str(tmp_path / "run")])
    assert code == 130
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "interrupted (Ctrl-C)" in err
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "rules, expected",
    [(["effort_saturation", "estimate_beyond_effort"], 4), (["divergence"], 1), (["hand_error", "nonfinite_metric"], 1)],
)
def test_a_failed_run_exits_as_admittance_run(monkeypatch, capsys, tmp_path, rules, expected):
    """A broken health rule exits 4, a divergence or a metric not finite 1 (docs/python.md)."""
    from admittance.mujoco import __main__ as cmd
    from admittance.mujoco import _cosim

    def failed(cfg, log=print):
        verdicts = [{"rule": r, "severity": "failure", "message": f"{r} broken"} for r in rules]
        return {
            "failures": [f"variant `learned`: {r} broken" for r in rules],
            "health": {"status": "failure", "variants": {"learned": {"verdicts": verdicts}}},
        }

    monkeypatch.setitem(sys.modules, "mujoco", types.ModuleType("mujoco"))
    monkeypatch.setattr(_cosim, "run_cosimulation", failed)
    code = cmd.main(["--urdf", str(PANDA), "--out", str(tmp_path / "run")])
    assert code == expected
    err = capsys.readouterr().err
    assert "the run failed" in err and f"(exit {expected})" in err and rules[0] in err


def test_ctrl_c_during_a_run(tmp_path):
    """A real SIGINT while the co-simulation records its training data."""
    pytest.importorskip("mujoco", reason="mujoco is not installed (pip install './crates/python[mujoco]')")
    out = tmp_path / "run"
    code = (
        "import runpy, sys; sys.argv = ['python -m admittance.mujoco'] + sys.argv[1:]; "
        "runpy.run_module('admittance.mujoco', run_name='__main__', alter_sys=True)"
    )
    p = subprocess.Popen(
        [sys.executable, "-c", code, "--urdf", str(PANDA), "--tip", "panda_hand_tcp",
         "--out", str(out), "--training-duration", "2000"],
        stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )
    time.sleep(4.0)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("admittance.mujoco: interrupted (Ctrl-C)")
    assert not out.exists()


def test_the_run_folder_is_ordinary_and_the_tip_is_found(tmp_path):
    pytest.importorskip("mujoco", reason="mujoco is not installed (pip install './crates/python[mujoco]')")
    import admittance as adm
    from admittance.mujoco import CosimConfig, run_cosimulation

    out = tmp_path / "run"
    old = os.umask(0o022)
    try:
        cfg = CosimConfig(urdf=str(PANDA), out=str(out), duration=3.0, variants=["oracle"])
        summary = run_cosimulation(cfg, log=lambda s: None)
    finally:
        os.umask(old)
    assert summary["failures"] == []
    assert stat.S_IMODE(out.stat().st_mode) == 0o755
    files = [f for f in out.iterdir() if f.is_file()]
    assert files and all(stat.S_IMODE(f.stat().st_mode) == 0o644 for f in files)
    # No --tip: the run used the CLI's tip (Model.from_urdf's default) instead of stopping.
    assert adm.Model.from_urdf(PANDA).tip_link


def test_variant_repeats_and_the_folder_loads_as_a_scenario(tmp_path, admittance_bin):
    """`--variant` can be repeated (duplicates once); the run folder's scenario.toml is a
    scenario the loader runs, and `admittance report` draws the folder."""
    pytest.importorskip("mujoco", reason="mujoco is not installed (pip install './crates/python[mujoco]')")
    import json

    import admittance as adm

    out = tmp_path / "run"
    p = run_module(["--urdf", str(PANDA), "--out", str(out), "--duration", "3",
                    "--variant", "oracle", "--variant", "momentum,oracle"], timeout=300)
    assert p.returncode == 0, p.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["variant_order"] == ["oracle", "momentum"]
    assert summary["plant"] == "mujoco" and summary["cosim"]["settings"]["duration"] == 3.0
    rerun = adm.run(out / "scenario.toml", tmp_path / "rerun", variant="momentum",
                    overrides={"duration": 0.2, "evaluation_start": 0.1}, report=False)
    assert rerun["variants"]["momentum"]["steps"] == 200
    r = subprocess.run([str(admittance_bin), "report", str(out)], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert (out / "report.md").is_file()
