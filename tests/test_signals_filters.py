"""Zero-phase Butterworth low-pass and the VAF metric."""

import numpy as np
import pytest

from anklelab.errors import ParameterError
from anklelab.signals import lowpass, lowpass_min_samples, vaf

FS = 1000.0


def _tone(freq_hz, n=4000):
    return np.sin(2 * np.pi * freq_hz * np.arange(n) / FS)


def _gain(freq_hz, **kw):
    y = lowpass(_tone(freq_hz), FS, **kw)[1000:-1000]
    return np.sqrt(2 * np.mean(y**2))


def test_gain_is_squared_butterworth_and_phase_is_zero():
    # forward-backward: |H|^2 of the design, so exactly 1/2 at the cutoff
    assert _gain(20.0, cutoff_hz=20.0) == pytest.approx(0.5, abs=0.01)
    assert _gain(2.0) == pytest.approx(1.0, abs=1e-3)
    assert _gain(100.0) < 1e-5
    x = _tone(5.0)
    y = lowpass(x, FS)
    lag = np.argmax(np.correlate(y[1000:-1000], x[1000:-1000], "full")) - 1999
    assert lag == 0


def test_order_steepens_the_rolloff():
    assert _gain(40.0, order=8) < _gain(40.0, order=4) < _gain(40.0, order=2)


def test_batch_equals_one_by_one_along_any_axis():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(3, 4, 500))
    batch = lowpass(x, FS)
    assert np.allclose(batch[1, 2], lowpass(x[1, 2], FS))
    assert np.allclose(lowpass(np.moveaxis(x, -1, 0), FS, axis=0), np.moveaxis(batch, -1, 0))


@pytest.mark.parametrize(
    ("kw", "match"), [({"cutoff_hz": 600.0}, "cutoff_hz"), ({"order": 0}, "order")]
)
def test_bad_settings_name_the_parameter(kw, match):
    with pytest.raises(ParameterError, match=match):
        lowpass(np.zeros(100), FS, **kw)


def test_vaf_per_signal_and_pooled():
    rng = np.random.default_rng(1)
    y = rng.normal(size=(2, 1000)) * [[1.0], [3.0]] + 5.0
    noise = rng.normal(size=(2, 1000)) * 0.5
    per = vaf(y, y + noise)
    expected = 100 * (1 - noise.var(axis=1) / y.var(axis=1))
    assert np.allclose(per, expected)
    pooled = vaf(y, y + noise, pool=0)
    assert pooled == pytest.approx(100 * (1 - noise.var(axis=1).sum() / y.var(axis=1).sum()))
    # an offset in the prediction does not count (each channel's mean is removed)
    assert np.allclose(vaf(y, y + 7.0), 100.0)


@pytest.mark.parametrize("order", [1, 4, 5])
def test_too_short_signal_names_the_minimum_length(order):
    need = lowpass_min_samples(FS, 20.0, order=order)
    assert need == 3 * (order + 1) + 1  # scipy's padlen for a Butterworth design, plus one
    assert lowpass(np.ones((2, need)), FS, order=order) == pytest.approx(1.0)
    with pytest.raises(ParameterError, match=rf"x: {need - 1} samples .*at least {need}"):
        lowpass(np.ones((2, need - 1)), FS, order=order)
    with pytest.raises(ParameterError, match="x: 5 samples along axis 0"):
        lowpass(np.ones((5, 100)), FS, order=order, axis=0)
