"""Training, growing, saving and loading the observer's network: the same results as
`admittance train` / `admittance grow`, the data forms, the errors, and the GIL released
while it fits."""

import subprocess
import threading
import time

import numpy as np
import pytest

import admittance as adm
from conftest import BAXTER, free_motion, write_csv


def inputs(data, rows=slice(0, 200)):
    return data["q"][rows], data["qdot"][rows], data["qddot"][rows]


def test_train_reports_and_predicts(baxter, motion, network):
    assert network.nodes == 80 and network.n_inputs == 21 and network.n_outputs == 7
    # Blocked cross-validation: every row trains, every row is scored by a fit on the others.
    assert network.samples == 8000 and network.validation_samples == 0
    assert network.can_grow and not network.friction_features and network.ridge_lambda > 0
    assert network.seconds > 0
    nrmse = network.validation_nrmse
    assert nrmse.shape == (7,) and np.all(nrmse < 0.5), nrmse
    # With `validation_fraction` the reported NRMSE is that of its predictions on the
    # held-out rows.
    tail = adm.train(motion, baxter, 80, validation_fraction=0.2)
    assert tail.samples == 6400 and tail.validation_samples == 1600
    held = slice(6400, 8000)
    err = tail.predict(*inputs(motion, held)) - motion["tau"][held]
    np.testing.assert_allclose(
        np.sqrt(np.mean(err**2, axis=0)) / np.std(motion["tau"][held], axis=0), tail.validation_nrmse, rtol=1e-9
    )
    # One sample at a time equals the batch; out= is written.
    batch = network.predict(*inputs(motion))
    assert batch.shape == (200, 7)
    np.testing.assert_array_equal(network.predict(motion["q"][7], motion["qdot"][7], motion["qddot"][7]), batch[7])
    out = np.empty((200, 7))
    assert network.predict(*inputs(motion), out=out) is out
    np.testing.assert_array_equal(out, batch)
    assert "nodes=80" in repr(network)


def test_csv_column_dict_and_cli_give_the_same_network(baxter, motion, tmp_path, admittance_bin):
    csv = tmp_path / "free_motion.csv"
    write_csv(csv, motion, baxter.joint_names)
    from_dict = adm.train(motion, baxter, 60, friction_features=True, seed=7)
    from_csv = adm.train(csv, baxter, 60, friction_features=True, seed=7)
    columns = {"t": motion["t"]}
    for s in ("q", "qdot", "qddot", "tau"):
        for i, j in enumerate(baxter.joint_names):
            columns[f"{s}.{j}"] = motion[s][:, i]
    from_columns = adm.train(columns, baxter, 60, friction_features=True, seed=7)
    x = inputs(motion)
    for other in (from_csv, from_columns):
        np.testing.assert_array_equal(other.predict(*x), from_dict.predict(*x))
    assert from_dict.friction_features
    # `admittance train` with the same settings writes the same network.
    cli_model = tmp_path / "cli.broad"
    out = subprocess.run(
        [str(admittance_bin), "train", "--data", str(csv), "--urdf", str(BAXTER), "--base", "base", "--tip",
         "left_hand", "--nodes", "60", "--friction-features", "--seed", "7", "--out", str(cli_model), "--quiet"],
        check=True, capture_output=True, text=True,
    )
    cli = adm.load_network(cli_model)
    np.testing.assert_array_equal(cli.predict(*x), from_dict.predict(*x))
    printed = out.stdout.split("validation nrmse: [")[1].split("]")[0]
    np.testing.assert_allclose([float(v) for v in printed.split(",")], from_dict.validation_nrmse, atol=5e-5)
    # And `admittance grow` grows it the same way as Network.grow.
    cli_grown = tmp_path / "cli_grown.broad"
    subprocess.run(
        [str(admittance_bin), "grow", "--model", str(cli_model), "--nodes", "15", "--data", str(csv),
         "--out", str(cli_grown), "--quiet"],
        check=True, capture_output=True, text=True,
    )
    from_dict.grow(15, motion)
    assert from_dict.nodes == 75
    np.testing.assert_allclose(adm.load_network(cli_grown).predict(*x), from_dict.predict(*x), rtol=0, atol=1e-9)


def test_grow_save_and_load(baxter, motion, tmp_path):
    net = adm.train(motion, baxter, 50, validation_fraction=0.2)
    before = net.validation_nrmse.copy()
    net.grow(30, motion)
    assert net.nodes == 80
    assert np.all(np.isfinite(net.validation_nrmse)) and not np.array_equal(net.validation_nrmse, before)
    # Under cross-validation (the default) a growth holds no rows out.
    cv = adm.train(motion, baxter, 50)
    cv.grow(10, motion)
    assert cv.nodes == 60 and cv.validation_nrmse is None
    path = tmp_path / "net.broad"
    net.save(path)
    loaded = adm.load_network(str(path))
    x = inputs(motion)
    np.testing.assert_array_equal(loaded.predict(*x), net.predict(*x))
    assert loaded.validation_nrmse is None and loaded.seconds is None and loaded.can_grow
    assert loaded.samples == 6400
    # A loaded network grows with the default (cross-validation: every row) unless told.
    loaded.grow(10, motion, validation_fraction=0.2)
    assert loaded.nodes == 90 and loaded.validation_nrmse.shape == (7,)
    # Growth needs the training data: other data is refused.
    other = free_motion(baxter, 40.0, rate=200.0, seed=5)
    with pytest.raises(ValueError, match="growth data does not match the training data"):
        net.grow(5, other)
    with pytest.raises(OSError):
        adm.load_network(tmp_path / "missing.broad")
    garbage = tmp_path / "garbage.broad"
    garbage.write_bytes(b"not a network")
    with pytest.raises(ValueError, match="garbage.broad"):
        adm.load_network(garbage)


def test_separate_validation_set(baxter, motion):
    other = free_motion(baxter, 10.0, rate=200.0, seed=3)
    net = adm.train(motion, baxter, 40, validation=other)
    assert net.samples == 8000 and net.validation_samples == 2000
    with pytest.raises(ValueError, match="separate validation set"):
        net.grow(5, motion)
    net.grow(5, motion, validation=other)
    assert net.nodes == 45
    with pytest.raises(ValueError, match="not both"):
        adm.train(motion, baxter, 40, validation=other, validation_fraction=0.3)


def test_data_errors_name_key_row_and_joint(baxter, motion, tmp_path):
    def with_(key, value):
        d = dict(motion)
        d[key] = value
        return d

    qd = motion["qdot"].copy()
    qd[12, 3] = np.nan
    with pytest.raises(ValueError, match=r"`data`: 'qdot' row 12, joint 3 is NaN"):
        adm.train(with_("qdot", qd), baxter, 10)
    t = motion["t"].copy()
    t[100] = t[99]
    with pytest.raises(ValueError, match=r"`data\['t'\]` does not increase strictly at row 100"):
        adm.train(with_("t", t), baxter, 10)
    with pytest.raises(ValueError, match=r"`data\['q'\]` must have shape \(N, 7\), got shape \(8000, 6\)"):
        adm.train(with_("q", motion["q"][:, :6]), baxter, 10)
    with pytest.raises(ValueError, match=r"`data\['tau'\]` must have shape \(8000, 7\)"):
        adm.train(with_("tau", motion["tau"][:10]), baxter, 10)
    no_tau = {k: v for k, v in motion.items() if k != "tau"}
    with pytest.raises(ValueError, match=r"neither 'tau' .* nor the column 'tau.left_s0'"):
        adm.train(no_tau, baxter, 10)
    with pytest.raises(ValueError, match=r"no key 't'"):
        adm.train({"q": motion["q"]}, baxter, 10)
    with pytest.raises(ValueError, match=r"`validation_fraction` is 1.5"):
        adm.train(motion, baxter, 10, validation_fraction=1.5)
    with pytest.raises(ValueError, match="friction_features"):
        adm.train(motion, baxter, 10, friction_scales=[0.1])
    with pytest.raises(ValueError, match="width_scale|width"):
        adm.train(motion, baxter, 10, width_scale=-1.0)
    with pytest.raises(TypeError, match="path of a free-motion CSV file or a dict"):
        adm.train(42, baxter, 10)
    with pytest.raises(OSError, match="missing.csv"):
        adm.train(tmp_path / "missing.csv", baxter, 10)
    bad_csv = tmp_path / "bad.csv"
    write_csv(bad_csv, {k: v[:20] for k, v in motion.items()}, baxter.joint_names)
    lines = bad_csv.read_text().splitlines()
    lines[5] = lines[5].replace(",", ",x", 1)
    bad_csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"bad.csv:6: column `q.left_s0`"):
        adm.train(bad_csv, baxter, 10)
    renamed = tmp_path / "renamed.csv"
    write_csv(renamed, motion, [f"j{i}" for i in range(7)])
    with pytest.raises(ValueError, match=r"joints \[j0, .*\] are not the arm's \[left_s0"):
        adm.train(renamed, baxter, 10)


def test_predict_errors(network):
    z = np.zeros(7)
    with pytest.raises(ValueError, match=r"`q` must have shape \(7,\) or \(N, 7\), got shape \(6,\)"):
        network.predict(np.zeros(6), z, z)
    with pytest.raises(ValueError, match="same shape"):
        network.predict(z, np.zeros((2, 7)), z)
    bad = z.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="non-finite value NaN in inputs, row 0, column 9"):
        network.predict(z, bad, z)
    with pytest.raises(ValueError, match="`out`"):
        network.predict(z, z, z, out=np.empty((1, 7)))


def test_the_gil_is_released_while_training(baxter):
    """The main thread keeps running Python while another thread trains: it records the
    time of every 100th pass of a loop, and some of those passes fall in the middle of the
    training call (where nothing but the fit runs), which cannot happen while the fit holds
    the GIL."""
    data = free_motion(baxter, 20.0, rate=500.0, seed=4)
    done = threading.Event()
    span = {}

    def work():
        span["start"] = time.perf_counter()
        span["net"] = adm.train(data, baxter, 600)
        span["end"] = time.perf_counter()
        done.set()

    thread = threading.Thread(target=work)
    stamps = []
    thread.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        if ticks % 100 == 0:
            stamps.append(time.perf_counter())
    thread.join()
    assert span["net"].nodes == 600
    start, end = span["start"], span["end"]
    middle = [s for s in stamps if start + 0.3 * (end - start) < s < start + 0.7 * (end - start)]
    assert len(middle) > 10, (len(middle), len(stamps), end - start)
