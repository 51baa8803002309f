"""Model and dynamics functions: against the committed Pinocchio fixtures (the references the
Rust tests use), against the `admittance dynamics` command of the same checkout, and their
errors."""

import json
import subprocess

import numpy as np
import pytest

import admittance as adm
from conftest import BAXTER, FIXTURES, Q0

TOLERANCE = 1e-9  # the Rust oracle test's: ||ours - pinocchio|| <= 1e-9 ||pinocchio||


def close(ours, theirs):
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    assert ours.shape == theirs.shape
    err = np.linalg.norm(ours - theirs)
    assert err <= TOLERANCE * max(np.linalg.norm(theirs), 1e-12 / TOLERANCE), err


def fixture_files():
    return sorted((FIXTURES / "pinocchio").glob("*.json"))


def test_fixtures_present():
    # 32 random arms and Baxter; the parametrised test below would pass vacuously otherwise.
    assert len(fixture_files()) == 33


@pytest.mark.parametrize("path", fixture_files(), ids=lambda p: p.stem)
def test_agrees_with_pinocchio(path):
    fx = json.loads(path.read_text())
    m = adm.Model.from_urdf(FIXTURES / fx["urdf"], base=fx["base"], tip=fx["tip"]).with_gravity(fx["gravity"])
    assert m.joint_names == fx["joints"]
    for c in fx["cases"]:
        close(adm.rnea(m, c["q"], c["v"], c["a"]), c["tau"])
        close(adm.crba(m, c["q"]), c["mass_matrix"])
        close(adm.gravity(m, c["q"]), c["gravity_torque"])
        close(adm.coriolis(m, c["q"], c["v"]), c["coriolis"])
        close(adm.aba(m, c["q"], c["v"], c["aba_tau"]), c["aba_qddot"])
        position, rotation = adm.tip_pose(m, c["q"])
        close(position, c["tip_position"])
        close(rotation, c["tip_rotation"])
        close(adm.tip_jacobian(m, c["q"]), c["jacobian"])


def test_agrees_with_the_cli(baxter, admittance_bin):
    rng = np.random.default_rng(1)
    for _ in range(3):
        q = Q0 + rng.uniform(-0.5, 0.5, 7)
        v, a = rng.uniform(-1, 1, 7), rng.uniform(-2, 2, 7)
        fmt = lambda x: ",".join(repr(float(e)) for e in x)
        out = subprocess.run(
            [str(admittance_bin), "dynamics", "--urdf", str(BAXTER), "--base", "base", "--tip", "left_hand",
             "--q", fmt(q), "--v", fmt(v), "--a", fmt(a)],
            check=True, capture_output=True, text=True,
        )
        cli = json.loads(out.stdout)
        assert cli["joints"] == baxter.joint_names
        # Same code, same inputs: equal to the last bit (the CLI's JSON round-trips floats).
        np.testing.assert_array_equal(adm.rnea(baxter, q, v, a), cli["tau"])
        np.testing.assert_array_equal(adm.crba(baxter, q), cli["mass_matrix"])
        np.testing.assert_array_equal(adm.gravity(baxter, q), cli["gravity"])
        np.testing.assert_array_equal(adm.coriolis(baxter, q, v), cli["coriolis"])
        position, rotation = adm.tip_pose(baxter, q)
        np.testing.assert_array_equal(position, cli["position"])
        np.testing.assert_array_equal(rotation, cli["rotation"])
        np.testing.assert_array_equal(adm.tip_jacobian(baxter, q), cli["jacobian"])


def test_model_attributes(baxter):
    assert baxter.n == 7
    assert baxter.joint_names[0] == "left_s0" and len(baxter.joint_names) == 7
    assert baxter.base_link == "base" and baxter.tip_link == "left_hand"
    for name in ("lower", "upper", "velocity_limit", "effort_limit"):
        values = getattr(baxter, name)
        assert values.shape == (7,) and values.dtype == np.float64
    assert np.all(baxter.lower < baxter.upper)
    assert baxter.effort_limit[0] == 50.0  # the URDF's left_s0
    np.testing.assert_array_equal(baxter.gravity, [0.0, 0.0, -9.81])
    assert baxter.total_moving_mass > 10.0
    assert "n=7" in repr(baxter)


def test_array_likes_and_out(baxter):
    q = Q0
    expected = adm.rnea(baxter, q, np.zeros(7), np.zeros(7))
    # Lists, tuples, integers, float32, non-contiguous views: all converted.
    np.testing.assert_array_equal(adm.rnea(baxter, list(q), (0,) * 7, [0] * 7), expected)
    strided = np.zeros(14)[::2]
    np.testing.assert_array_equal(adm.rnea(baxter, q, strided, strided), expected)
    assert np.allclose(adm.rnea(baxter, q.astype(np.float32), strided, strided), expected, rtol=1e-6, atol=1e-5)
    out = np.full(7, np.nan)
    assert adm.rnea(baxter, q, strided, strided, out=out) is out
    np.testing.assert_array_equal(out, expected)
    m_out = np.empty((7, 7))
    assert adm.crba(baxter, q, out=m_out) is m_out
    np.testing.assert_array_equal(m_out, adm.crba(baxter, q))
    j_out = np.empty((6, 7))
    assert adm.tip_jacobian(baxter, q, out=j_out) is j_out
    # Gravity = rnea at rest; rnea(q, v, aba(q, v, tau)) = tau.
    np.testing.assert_allclose(adm.gravity(baxter, q), expected, rtol=0, atol=1e-12)
    v, tau = np.linspace(-1, 1, 7), np.linspace(2, -2, 7)
    np.testing.assert_allclose(adm.rnea(baxter, q, v, adm.aba(baxter, q, v, tau)), tau, atol=1e-9)
    # A changed gravity changes G and nothing else.
    moon = baxter.with_gravity([0, 0, -1.62])
    np.testing.assert_allclose(adm.gravity(moon, q), expected * (1.62 / 9.81), atol=1e-12)
    heavy = baxter.with_scaled_inertias(1.25)
    np.testing.assert_allclose(adm.crba(heavy, q), 1.25 * adm.crba(baxter, q), rtol=1e-12)


@pytest.mark.parametrize("bad,shape", [(np.zeros(6), "(6,)"), (np.zeros((7, 1)), "(7, 1)"), (1.0, "()")])
def test_shape_errors_name_the_argument(baxter, bad, shape):
    with pytest.raises(ValueError, match=rf"`v` must have shape \(7,\).*got shape {shape.replace('(', '[(]').replace(')', '[)]')}"):
        adm.rnea(baxter, Q0, bad, np.zeros(7))
    with pytest.raises(ValueError, match=r"`q` must have shape \(7,\)"):
        adm.crba(baxter, bad)


def test_non_numeric_is_a_type_error(baxter):
    with pytest.raises(TypeError, match=r"`q` must be a float64 array-like of shape \(7,\)"):
        adm.gravity(baxter, ["a"] * 7)


@pytest.mark.parametrize("fn", ["rnea", "aba"])
def test_nan_is_an_error_naming_the_element(baxter, fn):
    v = np.zeros(7)
    v[4] = np.nan
    with pytest.raises(ValueError, match=r"`v\[4\]` is NaN"):
        getattr(adm, fn)(baxter, Q0, v, np.zeros(7))
    q = Q0.copy()
    q[0] = np.inf
    with pytest.raises(ValueError, match=r"`q\[0\]` is inf"):
        adm.tip_pose(baxter, q)


def test_bad_out_arrays(baxter):
    with pytest.raises(ValueError, match=r"`out` must be a writeable float64 numpy array of shape \(7,\)"):
        adm.gravity(baxter, Q0, out=np.empty(6))
    with pytest.raises(ValueError, match="`out`"):
        adm.gravity(baxter, Q0, out=np.empty(7, dtype=np.float32))
    frozen = np.empty(7)
    frozen.flags.writeable = False
    with pytest.raises(ValueError, match="writeable"):
        adm.gravity(baxter, Q0, out=frozen)
    with pytest.raises(ValueError, match=r"shape \(7, 7\)"):
        adm.crba(baxter, Q0, out=np.empty((7, 6)))


def test_urdf_errors(tmp_path):
    with pytest.raises(OSError, match="missing.urdf"):
        adm.Model.from_urdf(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="r">\n  <link name="a"/>\n  <joint name="j" type="floating">\n'
                   '    <parent link="a"/><child link="b"/>\n  </joint>\n  <link name="b"/>\n</robot>\n')
    with pytest.raises(ValueError, match="bad.urdf"):
        adm.Model.from_urdf(bad)
    with pytest.raises(ValueError, match="nowhere"):
        adm.Model.from_urdf(BAXTER, base="base", tip="nowhere")
    text = BAXTER.read_text()
    m = adm.Model.from_urdf_string(text, base="base", tip="left_hand")
    assert m.n == 7
    with pytest.raises(ValueError, match="scale"):
        m.with_scaled_inertias(-1.0)


def test_load_options_and_warnings(tmp_path):
    from conftest import BAXTER

    text = BAXTER.read_text().replace('ixx="0.00017588"', 'ixx="0.5"')
    broken = tmp_path / "arm.urdf"
    broken.write_text(text)
    m = adm.Model.from_urdf(broken, tip="left_hand")
    assert len(m.warnings) == 1 and "left_hand" in m.warnings[0]
    with pytest.raises(ValueError, match="left_hand"):
        adm.Model.from_urdf(broken, tip="left_hand", strict=True)
    with pytest.raises(ValueError, match="head_pan"):
        adm.Model.from_urdf(BAXTER, drop=["head_pan"])
    assert adm.Model.from_urdf(BAXTER).warnings == []
