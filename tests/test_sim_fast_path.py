"""The twin's fast path: its PCHIP equals SciPy's, its kernel's sine and cosine equal the math
library's, threads change no bit, and analysing recorded data imports neither numba nor the twin
(the filter designs: test_signals_iir.py)."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from anklelab.experiments import simulate_perturberator
from anklelab.sim._pchip import pchip


@pytest.mark.parametrize(
    ("x", "y"),
    [
        ([0.0, 0.03, 0.12, 0.25, 0.45, 0.7, 0.85, 1.0], [0, 0, 0.08, 0.1, 0.12, 0.14, 0.18, 0.2]),
        ([0.0, 0.1, 0.3, 0.6, 0.8, 1.0], [0.0, -0.07, 0.03, 0.12, 0.15, -0.15]),
        ([0.0, 1.0], [2.0, 3.0]),
        ([0.0, 0.3, 0.5, 1.0], [1.0, 0.0, 0.0, 2.0]),
    ],
)
def test_pchip_equals_scipys(x, y):
    at = np.linspace(-0.2, 1.2, 3001)
    ours = pchip(x, y, at)
    theirs = PchipInterpolator(x, y, extrapolate=False)(at)
    assert np.array_equal(np.isnan(ours), np.isnan(theirs))
    np.testing.assert_allclose(ours, theirs, atol=1e-14, equal_nan=True)


def test_the_kernels_cosine_and_sine_are_the_math_librarys_to_one_unit_in_the_last_place():
    from anklelab.sim._kernels import _cos_sin

    for x in [*np.linspace(-0.3, 0.3, 2001), 1e-300, -0.0, 0.25, np.nextafter(0.25, 1), 2.0]:
        cos, sin = _cos_sin(x)
        assert abs(cos - math.cos(x)) <= np.spacing(abs(math.cos(x))), x
        assert abs(sin - math.sin(x)) <= np.spacing(abs(math.sin(x))), x


def test_threads_change_no_bit_of_the_session():
    kwargs = dict(trials_per_point=2, n_unperturbed=3, n_calibration=1, bench=False, seed=4)
    one = simulate_perturberator(threads=1, **kwargs)
    two = simulate_perturberator(threads=2, **kwargs)
    for a, b in zip(
        (*one.calibration, *one.walking), (*two.calibration, *two.walking), strict=True
    ):
        a = getattr(a, "recording", a)
        b = getattr(b, "recording", b)
        for name, values in a.columns.items():
            assert values.tobytes() == b.columns[name].tobytes(), name


def test_analysing_recorded_data_imports_no_numba_and_no_twin():
    code = (
        "import sys\n"
        "from anklelab.commands import analyze\n"
        "import anklelab.pipelines.walking, anklelab.data, anklelab.studies.batch\n"
        "print(sorted(m for m in ('numba', 'anklelab.sim', 'anklelab.experiments')"
        " if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def _needs_compiling(cache: str | None) -> str:
    env = dict(os.environ)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    code = "from anklelab.sim.drivetrain import kernel_needs_compiling as k; print(k())"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    return out.stdout.strip()


def test_a_fresh_install_knows_it_must_compile_and_a_warm_one_does_not(tmp_path):
    simulate_perturberator(trials_per_point=1, n_unperturbed=1, n_calibration=0, bench=False)
    assert _needs_compiling(str(tmp_path / "empty-cache")) == "True"
    assert _needs_compiling(os.environ.get("NUMBA_CACHE_DIR")) == "False"


def test_compiling_is_announced_on_one_progress_line(monkeypatch):
    from anklelab.commands import _kernels
    from anklelab.platforms import load_platform
    from anklelab.sim import drivetrain

    shown = []
    monkeypatch.setattr(drivetrain, "kernel_needs_compiling", lambda: True)
    _kernels.prepare_kernel(
        load_platform("perturberator"), lambda text: shown.append(text) or (lambda *_: None)
    )
    assert shown == ["compiling simulation kernels, once"]
