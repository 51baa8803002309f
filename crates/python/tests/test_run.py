"""`adm.run`: a scenario run as `admittance run` does it, with the same folder rules."""

import json

import pytest

import admittance as adm
from conftest import ROOT

DEADZONE = ROOT / "scenarios" / "deadzone.toml"
SHORT = {"duration": 0.3, "evaluation_start": 0.1}


def test_a_short_run_returns_the_summary_it_writes(tmp_path):
    out = tmp_path / "run"
    summary = adm.run(DEADZONE, out, variant="pd", overrides=SHORT, report=False)
    written = json.loads((out / "summary.json").read_text())
    assert summary == written
    assert summary["format"] == "admittance-run"
    assert list(summary["variants"]) == ["pd"]
    metrics = summary["variants"]["pd"]
    assert metrics["diverged"] is False
    assert metrics["torque_limit_violations"] == 0
    assert (out / "pd.csv").is_file()
    # The overrides are in the scenario as run.
    assert "duration = 0.3" in (out / "scenario.toml").read_text()


def test_overrides_as_strings_and_a_seed(tmp_path):
    summary = adm.run(
        DEADZONE, tmp_path / "run", "pd", ["duration=0.3", "evaluation_start=0.1"], seed=2,
        report=False,
    )
    assert summary["variants"]["pd"]["diverged"] is False


def test_a_bad_override_names_its_key(tmp_path):
    with pytest.raises(ValueError, match="durration"):
        adm.run(DEADZONE, tmp_path / "run", "pd", {"durration": 1.0}, report=False)
    assert not (tmp_path / "run").exists()


def test_a_folder_of_the_users_is_refused_and_kept(tmp_path):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    with pytest.raises(FileExistsError):
        adm.run(DEADZONE, mine, "pd", SHORT, report=False)
    assert (mine / "notes.txt").read_text() == "keep me"


def test_a_diverged_run_raises_run_failed_with_its_summary(tmp_path):
    out = tmp_path / "run"
    overrides = dict(SHORT, **{"plant.gravity": [0.0, 0.0, -1e9]})
    with pytest.raises(adm.RunFailed) as info:
        adm.run(DEADZONE, out, "pd", overrides, report=False)
    assert info.value.summary["variants"]["pd"]["diverged"] is True
    assert (out / "summary.json").is_file()
