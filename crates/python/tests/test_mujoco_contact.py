"""`python -m admittance.mujoco.contact` shortened to one arm (the SO-100): the floor from
free motion in several recordings, judged on other motion and on pushes, run as a sweep job
whose folder is kept across runs with the same settings. The bars are measured on the full
table (docs/experiments.md, "Contact detection")."""

import importlib.metadata
import json

import pytest

pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco)")
try:
    importlib.metadata.distribution("example-robot-data")
except importlib.metadata.PackageNotFoundError:
    pytest.skip("example-robot-data is not installed (pip install example-robot-data==6.0.0)", allow_module_level=True)

from admittance.mujoco import contact  # noqa: E402

SHORT = ["--arms", "so100", "--calibration", "40", "--segment", "20", "--free", "20",
         "--push-seconds", "12", "--repeats", "1", "--jobs", "1"]


def test_one_arm_short_as_a_sweep_job(tmp_path, capsys):
    out = tmp_path / "contact"
    assert contact.main([*SHORT, "--out", str(out)]) == 0
    doc = json.loads((out / "results.json").read_text())
    (arm,) = doc["arms"]
    assert arm["arm"] == "so100"
    # One recording of 20 s, its first second added: 20 s of free motion counted (to the
    # last sample's period).
    assert arm["free"]["recordings"] == 1 and abs(arm["free"]["minutes"] - 20 / 60) < 0.01 / 60
    floor = arm["floor"]
    n = arm["n"]
    for key in ("contact_thresholds", "moving_drop", "rest_width", "reversal_gain", "knee_gain"):
        assert len(floor[key]) == n, key
    assert all(0.0 <= d < 1.0 for d in floor["moving_drop"])
    pushes = arm["pushes"]["floor"]
    assert 0.0 <= pushes["isolation_strict"] <= pushes["isolation"] <= 1.0
    assert (out / "so100" / "result.json").is_file()
    assert "| so100 | floor |" in (out / "table.md").read_text()
    # The same settings again: the arm's folder is kept, the table written anew.
    first = (out / "so100" / "result.json").read_text()
    assert contact.main([*SHORT, "--out", str(out)]) == 0
    assert (out / "so100" / "result.json").read_text() == first
    # Other settings into the same folder: refused, nothing replaced.
    capsys.readouterr()
    assert contact.main([*SHORT, "--rate", "2", "--out", str(out)]) == 3
    assert "other settings" in capsys.readouterr().err
    assert (out / "so100" / "result.json").read_text() == first
