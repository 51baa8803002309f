"""`python -m admittance.mujoco.arms` shortened to one arm of example-robot-data (the SO-101,
5 joints): trained on 20 s of excitation, judged on other motion. The identification-based
observers must beat the momentum observer on the URDF, which reads the plant's unknown
joint friction as external torque. The bars are measured on the full table
(docs/experiments.md, "Every arm of example-robot-data on MuJoCo")."""

import importlib.metadata
import math

import pytest

pytest.importorskip("mujoco", reason="mujoco is not installed (pip install mujoco)")
try:
    importlib.metadata.distribution("example-robot-data")
except importlib.metadata.PackageNotFoundError:
    pytest.skip("example-robot-data is not installed (pip install example-robot-data==6.0.0)", allow_module_level=True)

from admittance.mujoco._arms import (  # noqa: E402
    ESTIMATE_CUTOFFS_HZ, ESTIMATE_NOISE_MARGIN, OBSERVERS, ArmsConfig, run_arm, table_markdown,
)


def test_one_arm_short(tmp_path):
    cfg = ArmsConfig(
        out=str(tmp_path), arms=["so101"], training_duration=20.0, validation_duration=10.0,
        evaluation_duration=12.0, nodes=100,
    )
    r = run_arm("so101", cfg, log=lambda s: None)
    obs = r["observers"]
    assert set(obs) == set(OBSERVERS)
    for name, v in obs.items():
        assert math.isfinite(v["push_nrmse"]) and math.isfinite(v["free_false_torque_rms"]), name
    urdf = obs["momentum_urdf"]
    # The plant's friction (0.40 N m frictionloss per joint) is what the URDF misses; the
    # identification has it: in free motion on new motion, at most half the false torque.
    for name in ("momentum_identified", "hybrid"):
        assert obs[name]["free_false_torque_rms"] < 0.5 * urdf["free_false_torque_rms"], (name, obs)
        assert obs[name]["push_nrmse"] < 0.5 * urdf["push_nrmse"], (name, obs)
    # The pushes reach the joints: MuJoCo's J^T f is not negligible.
    assert r["pushed_torque_rms"] > 0.3
    assert "| so101 | 5 |" in table_markdown([r])
    # The estimate's low-pass is chosen on the validation recording: the fastest candidate
    # within the noise margin of the slowest.
    scan = r["estimate_cutoff_scan"]
    assert r["estimate_cutoff_hz"] in ESTIMATE_CUTOFFS_HZ and len(scan) == len(ESTIMATE_CUTOFFS_HZ)
    floor = scan[str(ESTIMATE_CUTOFFS_HZ[0])]
    assert scan[str(r["estimate_cutoff_hz"])] <= floor * (1 + ESTIMATE_NOISE_MARGIN)
    faster = [hz for hz in ESTIMATE_CUTOFFS_HZ if hz > r["estimate_cutoff_hz"]]
    assert all(scan[str(hz)] > floor * (1 + ESTIMATE_NOISE_MARGIN) for hz in faster)
