"""`EstimateLowPass`: the loop's first-order estimate low-pass (`observer.cutoff_hz`), the one
the arms table filters its estimates with: the recursion `y += alpha (x - y)` from rest, bit
for bit, one sample at a time or a whole recording at once."""

import math

import numpy as np
import pytest

import admittance as adm


def reference(x, cutoff_hz, dt):
    """The first-order recursion written out (what the arms table computed in Python)."""
    alpha = dt / (dt + 1.0 / (2 * math.pi * cutoff_hz))
    out = np.zeros_like(x)
    y = np.zeros(x.shape[1])
    for k in range(len(x)):
        y += alpha * (x[k] - y)
        out[k] = y
    return out


@pytest.mark.parametrize("cutoff_hz", [5.0, 10.0, 20.0, 40.0])
def test_filter_and_update_are_the_recursion_bit_for_bit(cutoff_hz):
    x = np.random.default_rng(1).standard_normal((2000, 7))
    want = reference(x, cutoff_hz, 1e-3)
    assert np.array_equal(adm.EstimateLowPass(7, cutoff_hz, 1.0 / 1e-3).filter(x), want)
    f = adm.EstimateLowPass(7, cutoff_hz, 1000.0)
    rows = np.array([f.update(row) for row in x])
    assert np.array_equal(rows, want)
    f.reset()
    assert np.array_equal(f.filter(x[:10]), want[:10])


def test_zero_passes_through_and_bad_input_is_refused():
    x = np.arange(6.0).reshape(3, 2)
    assert np.array_equal(adm.EstimateLowPass(2, 0.0, 1000.0).filter(x), x)
    with pytest.raises(ValueError, match="observer.cutoff_hz"):
        adm.EstimateLowPass(2, -1.0, 1000.0)
    with pytest.raises(ValueError, match="raw"):
        adm.EstimateLowPass(2, 5.0, 1000.0).filter(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="finite"):
        adm.EstimateLowPass(2, 5.0, 1000.0).update([math.nan, 0.0])
