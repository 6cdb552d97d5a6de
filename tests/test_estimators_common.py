"""One suite over every estimator in anklelab.ident (STYLE.md item 2, scikit-learn's shape).

Each case builds a small problem the estimator can solve. The suite checks the contract: the
constructor takes keyword arguments only and only stores them (they are checked in ``fit``, with
one message shape: ``name: expected ..., got ...``), ``get_params`` returns them so that
``sklearn.base.clone`` works, ``predict`` before ``fit`` raises NotFittedError naming the class,
``fit`` returns self, leaves the parameters alone and adds only attributes ending in ``_``, and
``score`` is the VAF (%) of ``predict`` against the data it is given.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest
from scipy.signal import lfilter

import anklelab.ident as ident
from anklelab.errors import NotFittedError, ParameterError
from anklelab.experiments.capstan import IdentProtocol, simulate_ident
from anklelab.signals import lowpass, vaf

FS = 1000.0


@dataclass
class Case:
    """``make(**params).fit(*fit_args, **fit_kwargs)``, then ``predict(*x)`` against ``y``."""

    make: Callable[..., Any]
    fit_args: tuple
    x: tuple
    y: np.ndarray
    bad_params: dict[str, Any]  # one invalid constructor argument, which fit must reject
    fit_kwargs: dict[str, Any] = field(default_factory=dict)
    # score(estimator, y) with the estimator's own signature
    score: Callable[[Any, np.ndarray], float] | None = None
    # what predict models: the target as the estimator compares it (e.g. low-passed)
    target: Callable[[np.ndarray], np.ndarray] = lambda y: y


def impulse_response() -> Case:
    rng = np.random.default_rng(0)
    u = rng.standard_normal((3, 1, 2000))
    y = lfilter(0.8 ** np.arange(12), [1.0], u, axis=-1) + 0.05 * rng.standard_normal(u.shape)
    return Case(ident.ImpulseResponse, (u, y), (u,), y, {"n_lags": 0})


def platform_filters() -> Case:
    # two records of a multisine below 10 Hz (random phases) about the resting angle
    rng = np.random.default_rng(1)
    t = np.arange(3000) / FS
    w = 2 * np.pi * np.arange(1.0, 10.0)[:, None]
    phase = rng.uniform(0, 2 * np.pi, (2, w.size, 1))
    angle = 0.01 * np.sin(w * t + phase).sum(axis=-2)
    accel = -0.01 * (w**2 * np.sin(w * t + phase)).sum(axis=-2)
    forces = np.stack([3.0 * angle + 0.002 * accel, -1.0 * angle + 0.004 * accel], axis=-2)
    return Case(
        lambda **kw: ident.PlatformFilters(channels=("f1", "f2"), n_lags=20, **kw),
        (angle, forces),
        (angle,),
        forces,
        {"inputs": ("jerk",)},
        fit_kwargs={"fs": FS},
        target=lambda y: lowpass(y, FS, 20.0, order=4),  # the defaults: cutoff_hz, filter_order
    )


def impedance_model() -> Case:
    t = np.arange(150) / FS
    theta = 0.03 * np.sin(20 * t) + 0.01 * np.sin(70 * t)
    kin = np.stack([theta, np.gradient(theta, t), np.gradient(np.gradient(theta, t), t)])
    rng = np.random.default_rng(2)
    torque = np.array([900.0, 3.0, 0.25]) @ kin + 0.2 * rng.standard_normal(t.size)
    return Case(ident.ImpedanceModel, (kin, torque), (kin,), torque, {"stiffness_model": "x"})


def friction_identifier() -> Case:
    data = simulate_ident(protocol=IdentProtocol(speeds_rad_s=(20.0, 40.0), chirp_s=5.0), seed=2)
    chirp = data.chirp[0]
    return Case(
        ident.FrictionIdentifier,
        (data,),
        (chirp.torque_nm,),
        chirp.velocity_rad_s,
        {"window_s": 0.0},
    )


CASES = {
    "ImpulseResponse": impulse_response,
    "PlatformFilters": platform_filters,
    "ImpedanceModel": impedance_model,
    "FrictionIdentifier": friction_identifier,
}


def test_every_estimator_has_a_case():
    def is_estimator(obj: Any) -> bool:
        return inspect.isclass(obj) and all(hasattr(obj, m) for m in ("fit", "predict", "score"))

    assert {name for name in ident.__all__ if is_estimator(getattr(ident, name))} == set(CASES)


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request):
    made = CASES[request.param]()
    made.name = request.param
    return made


def fit(case: Case, estimator: Any) -> Any:
    return estimator.fit(*case.fit_args, **case.fit_kwargs)


def score(case: Case, estimator: Any, y: np.ndarray) -> float:
    return case.score(estimator, y) if case.score else estimator.score(*case.x, y)


def test_predict_before_fit_names_the_class(case):
    with pytest.raises(NotFittedError, match=f"{case.name} is not fitted"):
        case.make().predict(*case.x)


def test_fit_returns_self_and_adds_only_trailing_underscore_attributes(case):
    estimator = case.make()
    params = dict(vars(estimator))
    assert not [k for k in params if k.endswith("_")], "the constructor sets fitted attributes"
    assert fit(case, estimator) is estimator
    added = set(vars(estimator)) - set(params)
    assert added and all(k.endswith("_") for k in added), sorted(added)
    for key, value in params.items():  # fit leaves the parameters as given
        assert vars(estimator)[key] is value


def test_parameters_are_checked_in_fit_not_in_the_constructor(case):
    estimator = case.make(**case.bad_params)  # storing a bad value is allowed
    ((name, value),) = case.bad_params.items()
    with pytest.raises(
        ParameterError, match=rf"^{name}: expected .+, got {re.escape(repr(value))}$"
    ):
        fit(case, estimator)


def test_constructors_take_keywords_only(case):
    estimator = case.make()
    parameters = inspect.signature(type(estimator).__init__).parameters.values()
    assert [p.kind for p in parameters][1:] == [inspect.Parameter.KEYWORD_ONLY] * (
        len(parameters) - 1
    )
    assert set(estimator.get_params()) == {p.name for p in parameters} - {"self"}


def test_sklearn_clone_copies_the_parameters_not_the_fit(case):
    base = pytest.importorskip("sklearn.base")
    estimator = fit(case, case.make())
    copy = base.clone(estimator)
    assert type(copy) is type(estimator) and copy is not estimator
    assert copy.get_params() == estimator.get_params()
    assert not [k for k in vars(copy) if k.endswith("_")]
    with pytest.raises(NotFittedError, match=type(estimator).__name__):
        copy.predict(*case.x)
    name, value = next(iter(case.bad_params.items()))
    assert base.clone(copy.set_params(**{name: value})).get_params()[name] == value


def test_score_is_the_vaf_of_predict_on_the_fitting_data(case):
    estimator = fit(case, case.make())
    predicted = estimator.predict(*case.x)
    assert predicted.shape == case.y.shape
    value = score(case, estimator, case.y)
    assert 90.0 < value <= 100.0
    # the same number from the prediction: VAF pooled over channels, averaged over records
    target = case.target(case.y)
    records = target.reshape(-1, *target.shape[-2:]) if target.ndim > 1 else target[None, None]
    expected = np.mean(vaf(records, predicted.reshape(records.shape), pool=-2))
    assert value == pytest.approx(expected, rel=1e-9)
    # it scores the data it is given: the negated target is explained far worse
    assert score(case, estimator, -case.y) < 0.0
