"""What the Python API refuses before any work (issue 34, items 7, 8 and the Python build
bullet): arrays that are not numbers, non-finite or absurdly large samples, zero nodes,
a recording without motion, an identification file edited into a physically impossible one
(with its checksum recomputed), and a FIFO given as a file."""

import json
import os

import numpy as np
import pytest

import admittance as adm
from conftest import Q0


def canonical(value):
    """The payload's JSON text as the writer hashes it (serde_json's compact form): keys
    sorted, no spaces, floats in their shortest form with exponents as `1e-5`, `1e300`."""
    if isinstance(value, dict):
        return "{" + ",".join(f"{json.dumps(k)}:{canonical(value[k])}" for k in sorted(value)) + "}"
    if isinstance(value, list):
        return "[" + ",".join(canonical(v) for v in value) + "]"
    if isinstance(value, float):
        return shortest(value)
    return json.dumps(value)


def shortest(x):
    """A float as serde_json writes it (the ryu crate's format): Python's shortest digits,
    decimal for 1e-5 <= |x| < 1e16, else `1.5e-7`, `1e300`."""
    if x == 0.0:
        return "-0.0" if str(x).startswith("-") else "0.0"
    sign = "-" if x < 0 else ""
    text = repr(abs(x))
    mantissa, _, exponent = text.partition("e")
    whole, _, frac = mantissa.partition(".")
    raw = whole + frac
    leading = len(raw) - len(raw.lstrip("0"))
    digits = raw.strip("0")
    n = len(digits)
    kk = len(whole) - leading + (int(exponent) if exponent else 0)
    if 0 <= kk - n and kk <= 16:
        out = digits + "0" * (kk - n) + ".0"
    elif 0 < kk <= 16:
        out = digits[:kk] + "." + digits[kk:]
    elif -5 < kk <= 0:
        out = "0." + "0" * (-kk) + digits
    elif n == 1:
        out = f"{digits}e{kk - 1}"
    else:
        out = f"{digits[0]}.{digits[1:]}e{kk - 1}"
    return sign + out


def fnv1a64(text):
    """The identification file's checksum (docs/outputs.md): FNV-1a 64 of the payload's JSON."""
    h = 0xCBF29CE484222325
    for b in text.encode():
        h ^= b
        h = (h * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def test_object_string_and_boolean_arrays_are_refused_naming_the_argument(baxter):
    for bad in (np.array([0.1] * 6 + ["x"], dtype=object), np.array(["0.1"] * 7), np.ones(7, dtype=bool)):
        with pytest.raises(TypeError, match=r"`q` must be a float64 array-like of shape \(7,\): it has dtype"):
            adm.rnea(baxter, bad, np.zeros(7), np.zeros(7))
    # Integers and float32 still convert.
    adm.rnea(baxter, np.zeros(7, dtype=np.int64), np.zeros(7, dtype=np.float32), [0] * 7)


def test_absurd_torques_are_refused_before_identification(baxter, motion):
    data = dict(motion)
    data["tau"] = motion["tau"] * 1e300
    with pytest.raises(ValueError, match=r"`data`: 'tau' row \d+, joint \d+ is .*beyond \+-1e12"):
        adm.identify(data, baxter)
    with pytest.raises(ValueError, match=r"beyond \+-1e12"):
        adm.train(data, baxter, 10)


def test_predict_names_the_first_non_finite_element(baxter, motion):
    ident = adm.identify(motion, baxter)
    qd = motion["qdot"][:20].copy()
    qd[3, 2] = np.nan
    with pytest.raises(ValueError, match=r"`qdot\[3, 2\]` is NaN"):
        ident.predict(motion["q"][:20], qd, motion["qddot"][:20])


def test_zero_nodes_and_motionless_data_are_refused(baxter, motion):
    with pytest.raises(ValueError, match=r"`nodes` is 0"):
        adm.train(motion, baxter, 0)
    n = len(motion["t"])
    still = {
        "t": motion["t"],
        "q": np.tile(Q0, (n, 1)),
        "qdot": np.zeros((n, 7)),
        "qddot": np.zeros((n, 7)),
        "tau": np.tile(adm.rnea(baxter, Q0, np.zeros(7), np.zeros(7)), (n, 1)),
    }
    with pytest.raises(ValueError, match=r"no motion"):
        adm.train(still, baxter, 10)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda p: p["inertial_parameters"].__setitem__(20, -5.0), r"body 2 .*mass -5 kg"),
        (lambda p: p["inertial_parameters"].__setitem__(14, 5e7), r"inertial_parameters\[14\].*5e7"),
        (lambda p: p["joint_terms"][3].__setitem__("armature", -1.5), r"joint_terms\[3\].*rotor inertia -1.5"),
    ],
)
def test_an_edited_identification_with_a_recomputed_checksum_is_refused(baxter, motion, tmp_path, edit, message):
    path = tmp_path / "ident.json"
    adm.identify(motion, baxter).save(path)
    doc = json.loads(path.read_text())
    # The recomputed checksum is right: the unedited file with it still loads.
    assert doc["checksum"] == fnv1a64(canonical(doc["payload"]))
    edit(doc["payload"])
    doc["checksum"] = fnv1a64(canonical(doc["payload"]))
    path.write_text(json.dumps(doc, indent=2))
    with pytest.raises(Exception, match=message):
        adm.load_identification(path, baxter)


def test_a_fifo_is_refused_as_a_file(baxter, tmp_path):
    fifo = tmp_path / "net.bin"
    os.mkfifo(fifo)
    with pytest.raises(Exception, match=r"FIFO"):
        adm.load_network(fifo)
    with pytest.raises(Exception, match=r"FIFO"):
        adm.load_identification(fifo, baxter)
