"""Shared fixtures of the Python package's tests: the repository's paths, the Baxter arm, the
`admittance` binary of the same checkout, and free-motion data made from the arm's own
inverse dynamics (no simulator needed)."""

import os
import pathlib
import shutil

import numpy as np
import pytest

import admittance as adm

ROOT = pathlib.Path(__file__).resolve().parents[3]
BAXTER = ROOT / "models" / "baxter_left_arm.urdf"
FIXTURES = ROOT / "crates" / "dynamics" / "tests" / "fixtures"
#: The pose of experiment A (scenarios/deadzone.toml).
Q0 = np.array([0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5])


@pytest.fixture(scope="session")
def baxter():
    return adm.Model.from_urdf(BAXTER, base="base", tip="left_hand")


@pytest.fixture(scope="session")
def admittance_bin():
    """The `admittance` binary of this checkout: $ADMITTANCE_BIN (CI sets it; then it must
    exist), else target/{debug,release}/admittance when built, else the test is skipped."""
    given = os.environ.get("ADMITTANCE_BIN")
    if given:
        path = pathlib.Path(given)
        assert path.is_file(), f"ADMITTANCE_BIN={given} does not exist"
        return path
    for profile in ("debug", "release"):
        path = ROOT / "target" / profile / "admittance"
        if path.is_file():
            return path
    found = shutil.which("admittance")
    if found:
        return pathlib.Path(found)
    pytest.skip("no `admittance` binary built (cargo build -p admittance-cli, or set ADMITTANCE_BIN)")


def multisine(t, n, seed=0, amplitude=0.4):
    """A smooth excitation q(t), qdot(t), qddot(t) about the pose Q0: three incommensurate
    sines per joint."""
    rng = np.random.default_rng(seed)
    periods = rng.uniform(1.5, 7.0, size=(3, n))
    phases = rng.uniform(0, 2 * np.pi, size=(3, n))
    w = 2 * np.pi / periods
    arg = t[:, None, None] * w[None] + phases[None]
    a = amplitude / 3
    q = Q0[:n] + a * np.sin(arg).sum(axis=1)
    qdot = a * (w[None] * np.cos(arg)).sum(axis=1)
    qddot = -a * (w[None] ** 2 * np.sin(arg)).sum(axis=1)
    return q, qdot, qddot


def free_motion(m, seconds, rate=200.0, seed=0, friction=0.0):
    """Free-motion data of `m` on a multi-sine: tau = RNEA(q, qdot, qddot) + viscous friction,
    as a dict of arrays in the format `train` takes."""
    t = np.arange(0.0, seconds, 1.0 / rate)
    q, qdot, qddot = multisine(t, m.n, seed)
    tau = np.array([adm.rnea(m, q[k], qdot[k], qddot[k]) for k in range(len(t))])
    tau += friction * qdot
    return {"t": t, "q": q, "qdot": qdot, "qddot": qddot, "tau": tau}


def write_csv(path, data, joints):
    """Writes free-motion data in the CLI's CSV format (docs/outputs.md), exactly (repr)."""
    cols = ["t"] + [f"{s}.{j}" for s in ("q", "qdot", "qddot", "tau") for j in joints]
    with open(path, "w") as f:
        f.write(",".join(cols) + "\n")
        for k in range(len(data["t"])):
            row = [data["t"][k]]
            for s in ("q", "qdot", "qddot", "tau"):
                row.extend(data[s][k])
            f.write(",".join(repr(float(v)) for v in row) + "\n")


@pytest.fixture(scope="session")
def motion(baxter):
    """40 s of free motion at 200 Hz (8000 rows) with viscous friction 0.3 qdot."""
    return free_motion(baxter, 40.0, rate=200.0, seed=0, friction=0.3)


@pytest.fixture(scope="session")
def network(baxter, motion):
    """A small network (80 nodes) on `motion`."""
    return adm.train(motion, baxter, 80)
