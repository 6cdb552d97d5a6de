"""The base every estimator shares: declared parameter constraints, one not-fitted check.

In the spirit of scikit-learn's ``BaseEstimator`` and ``_parameter_constraints``: a subclass
stores its keyword-only constructor arguments unchanged, declares what each may be in
``_parameter_constraints``, and calls :meth:`Estimator._validate_params` at the start of
``fit``; one helper writes one message for every estimator, naming the parameter, what is
allowed and the value received. :meth:`Estimator.get_params` makes ``sklearn.base.clone`` work.

The sample rate is a property of the data, not of the estimator: ``fit`` takes it (``fs``, Hz,
or from the data object), stores it as ``fs_``, and ``predict`` and ``score`` use ``fs_`` (the
data they are given must have the same rate).
"""

from __future__ import annotations

import inspect
import numbers
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from anklelab.errors import NotFittedError, ParameterError

__all__ = [
    "Constraint",
    "Estimator",
    "distinct_subset",
    "interval",
    "none",
    "one_of",
    "sequence_of",
    "validate_parameter",
]


@dataclass(frozen=True)
class Constraint:
    """What a parameter may be: a test and its description (for the error message)."""

    description: str
    accepts: Callable[[Any], bool]


def _real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def interval(
    low: float | None = None,
    high: float | None = None,
    *,
    closed: str = "both",
    integer: bool = False,
) -> Constraint:
    """A number in ``[low, high]`` (``closed``: "both", "left", "right" or "neither").

    Examples
    --------
    >>> interval(0, closed="neither").description, interval(1, integer=True).accepts(2.5)
    ('a number > 0', False)
    """
    low_ok = closed in ("both", "left")
    high_ok = closed in ("both", "right")

    def accepts(value: Any) -> bool:
        if not _real(value) or (integer and not isinstance(value, numbers.Integral)):
            return False
        if low is not None and not (value >= low if low_ok else value > low):
            return False
        return high is None or (value <= high if high_ok else value < high)

    kind = "an integer" if integer else "a number"
    bounds = []
    if low is not None:
        bounds.append(f"{'>=' if low_ok else '>'} {low:g}")
    if high is not None:
        bounds.append(f"{'<=' if high_ok else '<'} {high:g}")
    return Constraint(f"{kind} {' and '.join(bounds)}".strip(), accepts)


def one_of(*options: Any) -> Constraint:
    """One of ``options``."""
    return Constraint(" or ".join(repr(o) for o in options), lambda value: value in options)


def none() -> Constraint:
    """None (an optional parameter left out)."""
    return Constraint("None", lambda value: value is None)


def sequence_of(item: Constraint, *, non_empty: bool = True) -> Constraint:
    """A list or tuple whose every item satisfies ``item``."""

    def accepts(value: Any) -> bool:
        return (
            isinstance(value, Sequence)
            and not isinstance(value, str)
            and (len(value) > 0 or not non_empty)
            and all(item.accepts(v) for v in value)
        )

    return Constraint(f"a sequence of {item.description}", accepts)


def distinct_subset(options: Iterable[str]) -> Constraint:
    """A non-empty sequence of distinct names among ``options``."""
    options = tuple(options)

    def accepts(value: Any) -> bool:
        return (
            isinstance(value, Sequence)
            and not isinstance(value, str)
            and len(value) > 0
            and len(set(value)) == len(value)
            and all(v in options for v in value)
        )

    return Constraint(f"distinct names among {', '.join(options)}", accepts)


def validate_parameter(name: str, value: Any, constraints: Sequence[Constraint]) -> None:
    """Raise :class:`ParameterError` unless ``value`` satisfies one of ``constraints``.

    Examples
    --------
    >>> validate_parameter("order", 0, [interval(1, integer=True), none()])
    Traceback (most recent call last):
    ...
    anklelab.errors.ParameterError: order: expected an integer >= 1 or None, got 0
    """
    if not any(c.accepts(value) for c in constraints):
        allowed = " or ".join(c.description for c in constraints)
        raise ParameterError(f"{name}: expected {allowed}, got {value!r}")


class Estimator:
    """Base of anklelab's estimators: ``fit`` returns self, fitted attributes end in ``_``.

    Subclasses declare ``_parameter_constraints`` (constructor parameter -> allowed
    :class:`Constraint` list) and ``_fitted_attribute`` (one attribute ``fit`` always sets).
    """

    _parameter_constraints: ClassVar[Mapping[str, Sequence[Constraint]]] = {}
    _fitted_attribute: ClassVar[str] = ""

    @classmethod
    def _parameter_names(cls) -> list[str]:
        signature = inspect.signature(cls.__init__)
        return [p.name for p in signature.parameters.values() if p.kind is p.KEYWORD_ONLY]

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The constructor parameters, as given (``deep`` is accepted for scikit-learn)."""
        return {name: getattr(self, name) for name in self._parameter_names()}

    def set_params(self, **params: Any) -> Estimator:
        """Change constructor parameters (checked at the next ``fit``); returns self."""
        for name, value in params.items():
            if name not in self._parameter_names():
                raise ParameterError(f"{name}: not a parameter of {type(self).__name__}")
            setattr(self, name, value)
        return self

    def __repr__(self) -> str:
        params = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({params})"

    def _validate_params(self) -> None:
        """Check every parameter against ``_parameter_constraints`` (call first in ``fit``)."""
        for name, constraints in self._parameter_constraints.items():
            validate_parameter(name, getattr(self, name), constraints)

    def _check_fitted(self) -> None:
        """Raise :class:`NotFittedError` naming the class unless ``fit`` has run."""
        if not hasattr(self, self._fitted_attribute):
            raise NotFittedError(f"{type(self).__name__} is not fitted yet; call fit() first")
