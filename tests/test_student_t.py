"""Student's t without SciPy, against SciPy's own."""

import math

import numpy as np
import pytest
from scipy.special import stdtr, stdtrit

from anklelab._student_t import t_cdf, t_quantile

DEGREES = [*range(1, 60), 99, 100, 399, 3199]


@pytest.mark.parametrize("df", DEGREES)
def test_the_cdf_is_scipys(df):
    x = np.concatenate([np.linspace(-12.0, 12.0, 97), [-300.0, -1e-3, 1e-3, 50.0]])
    ours = np.array([t_cdf(df, v) for v in x])
    np.testing.assert_allclose(ours, stdtr(df, x), rtol=0, atol=1e-13)


@pytest.mark.parametrize("df", DEGREES)
def test_the_quantile_is_scipys_and_inverts_the_cdf(df):
    for p in (1e-4, 0.025, 0.1, 0.5, 0.6, 0.9, 0.975, 0.9999):
        q = t_quantile(df, p)
        assert q == pytest.approx(stdtrit(df, p), rel=1e-10)
        assert t_cdf(df, q) == pytest.approx(p, rel=1e-10)


def test_one_degree_of_freedom_is_cauchy_and_the_ends_are_exact():
    assert t_cdf(1, 1e-9) == 0.5 + math.atan(1e-9) / math.pi  # SciPy rounds this to 0.5
    assert t_cdf(5, math.inf) == 1.0 and t_cdf(5, -math.inf) == 0.0
    assert math.isnan(t_cdf(5, math.nan))
    assert t_quantile(5, 0.0) == -math.inf and t_quantile(5, 1.0) == math.inf
    assert math.isnan(t_quantile(5, 1.5))
    t_quantile(1, 0.975)  # cached: a bool must not find it
    for df in (2.5, 0, True, math.nan, math.inf, "3"):
        for function in (t_cdf, t_quantile):
            with pytest.raises(ValueError, match=r"degrees of freedom: got .*; expected a whole"):
                function(df, 0.975)
