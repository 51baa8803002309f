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


def _so101_on_a_platform(path):
    """The SO-101 of example-robot-data on a platform that also carries an antenna whose
    inertia MuJoCo refuses (not positive definite, as one of TIAGo's): the kind of tree a
    mobile manipulator's URDF is."""
    import xml.etree.ElementTree as ET

    from admittance.mujoco._arms import ARMS, robots_dir

    root = ET.fromstring((robots_dir() / ARMS["so101"][0]).read_text())
    for name, parent in (("platform", None), ("antenna", "platform")):
        link = ET.SubElement(root, "link", {"name": name})
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "mass", {"value": "0.5"})
        moments = {"ixx": "0.001", "iyy": "0.001", "izz": "0.001", "ixy": "0.01" if parent else "0", "ixz": "0", "iyz": "0"}
        ET.SubElement(inertial, "inertia", moments)
    for name, parent, child in (("mount", "platform", "base_link"), ("antenna_mount", "platform", "antenna")):
        joint = ET.SubElement(root, "joint", {"name": name, "type": "fixed"})
        ET.SubElement(joint, "parent", {"link": parent})
        ET.SubElement(joint, "child", {"link": child})
        ET.SubElement(joint, "origin", {"xyz": "0.1 0 0.3", "rpy": "0 0 0"})
    path.write_text(ET.tostring(root, encoding="unicode"))


def test_your_own_urdf_through_the_command_line(tmp_path):
    import json

    from admittance.mujoco.arms import main

    urdf = tmp_path / "platform_arm.urdf"
    _so101_on_a_platform(urdf)
    out = tmp_path / "out"
    args = ["--urdf", str(urdf), "--base", "base_link", "--out", str(out), "--training-duration", "20",
            "--validation-duration", "10", "--evaluation-duration", "12", "--nodes", "100", "--jobs", "1", "--quiet"]
    assert main(args) == 0
    (arm,) = json.loads((out / "results.json").read_text())["arms"]
    assert arm["arm"] == "platform_arm" and arm["urdf"] == str(urdf.resolve()) and arm["n"] == 5
    obs = arm["observers"]
    assert obs["momentum_identified"]["free_false_torque_rms"] < 0.5 * obs["momentum_urdf"]["free_false_torque_rms"], obs


def test_a_urdf_without_effort_limits_is_recorded(tmp_path):
    """A URDF whose joints state no effort limit (effort="0"): the recording's PD bounds its
    torque by the effort the plant's friction rule assumes for them (87 N m), instead of
    refusing the arm; joints with a limit keep theirs."""
    import xml.etree.ElementTree as ET

    import numpy as np

    import admittance as adm
    from admittance.mujoco._arms import ARMS, recording_gains, robots_dir
    from admittance.mujoco._plant import FR3_LARGE, unknown_joint_terms

    source = robots_dir() / ARMS["so101"][0]
    first = adm.Model.from_urdf(str(source)).joint_names[0]
    root = ET.fromstring(source.read_text())
    next(j for j in root.findall("joint") if j.get("name") == first).find("limit").set("effort", "0")
    urdf = tmp_path / "no_effort.urdf"
    urdf.write_text(ET.tostring(root, encoding="unicode"))
    m = adm.Model.from_urdf(str(urdf))
    effort = np.asarray(m.effort_limit)
    assert effort[0] == 0 and np.all(effort[1:] > 0)
    q = np.zeros(m.n)
    gains = recording_gains(m, q, unknown_joint_terms(m.effort_limit))
    assert gains["safe_hold"]["effort_limits"] == [FR3_LARGE["effort"], *effort[1:].tolist()]
    ctl = adm.PdController(m, gains)  # refused without the bound
    zeros = np.zeros(m.n)
    assert np.all(np.isfinite(ctl.step(0.0, q, zeros, q, zeros, zeros, zeros, 0.001)))
    with pytest.raises(ValueError, match="effort"):
        adm.PdController(m, {k: v for k, v in gains.items() if k != "safe_hold"})


@pytest.mark.parametrize("rpy", ["0 0 0", "3.141592653589793 0 0.3", "1.5707963267948966 0.2 0"])
def test_a_turned_mount_gives_mujocos_gravity(tmp_path, rpy):
    """An arm hung from a ceiling or a wall in a larger URDF (the base link turned against the
    root): our model's gravity torques equal MuJoCo's, which simulates the whole tree from the
    root."""
    import xml.etree.ElementTree as ET

    import mujoco
    import numpy as np

    import admittance as adm
    from admittance.mujoco._arms import ARMS, robots_dir
    from admittance.mujoco._plant import chain_urdf

    root = ET.fromstring((robots_dir() / ARMS["so101"][0]).read_text())
    # cell -> (turned) world -> base_link: an arm's file whose own root is called "world",
    # wrapped in a workcell's (MuJoCo would take that link as its world body).
    for name in ("cell", "world"):
        ET.SubElement(root, "link", {"name": name})
    for name, parent, child, pose in (("mount", "cell", "world", rpy), ("world_joint", "world", "base_link", "0 0 0")):
        joint = ET.SubElement(root, "joint", {"name": name, "type": "fixed"})
        ET.SubElement(joint, "parent", {"link": parent})
        ET.SubElement(joint, "child", {"link": child})
        ET.SubElement(joint, "origin", {"xyz": "0 0 2" if parent == "cell" else "0 0 0", "rpy": pose})
    urdf = tmp_path / "hung.urdf"
    urdf.write_text(ET.tostring(root, encoding="unicode"))
    m = adm.Model.from_urdf(str(urdf), base="base_link")
    assert abs(np.linalg.norm(m.gravity) - 9.81) < 1e-12
    assert (m.gravity[2] == -9.81) == (rpy == "0 0 0")
    plant = mujoco.MjSpec.from_string(chain_urdf(urdf.read_text(), m.joint_names, m.tip_link)).compile()
    data = mujoco.MjData(plant)
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = rng.uniform(m.lower, m.upper)
        for name, value in zip(m.joint_names, q):
            data.qpos[plant.joint(name).qposadr[0]] = value
        mujoco.mj_forward(plant, data)
        theirs = np.array([data.qfrc_bias[plant.joint(name).dofadr[0]] for name in m.joint_names])
        ours = np.asarray(adm.rnea(m, q, np.zeros(m.n), np.zeros(m.n)))
        # MuJoCo's compiler bounds the SO-101's tiny link masses and inertias (`boundmass`,
        # `balanceinertia`): a few 1e-5 of the torque, upright too. A wrong gravity direction
        # is an error of the torque's own size.
        np.testing.assert_allclose(ours, theirs, rtol=1e-4, atol=1e-4 * np.abs(theirs).max())


@pytest.mark.parametrize(
    "args, message",
    [
        (["--urdf", "no/such.urdf"], "--urdf no/such.urdf: no such file"),
        (["--tip", "link_7"], "--base, --tip and --name go with --urdf"),
        (["--urdf", "{urdf}", "--name", "panda"], "--name panda: an arm of the table has that name"),
        (["--urdf", "{urdf}", "--tip", "no_such_link"], "no_such_link"),
    ],
)
def test_your_own_urdf_refused_with_a_reason(tmp_path, capsys, args, message):
    from admittance.mujoco.arms import main

    urdf = tmp_path / "platform_arm.urdf"
    _so101_on_a_platform(urdf)
    with pytest.raises(SystemExit) as e:
        main([a.replace("{urdf}", str(urdf)) for a in args] + ["--out", str(tmp_path / "out")])
    assert e.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
