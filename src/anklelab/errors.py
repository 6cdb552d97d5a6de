"""Domain exceptions. Each subclasses the built-in a caller would naturally catch."""

from __future__ import annotations

__all__ = [
    "AnklelabError",
    "AnklelabWarning",
    "EventNotFoundError",
    "NotFittedError",
    "OutputError",
    "ParameterError",
    "ResultsFormatError",
    "SafetyLimitError",
    "SessionFormatError",
]


class AnklelabError(Exception):
    """Base class of every anklelab exception."""


class AnklelabWarning(UserWarning):
    """Something in the data deserves attention, but the analysis could go on (e.g. a manifest
    condition whose trials were all dropped)."""


class ParameterError(AnklelabError, ValueError):
    """A parameter file or parameter value is invalid (names the file, key and expectation)."""


class SessionFormatError(AnklelabError, ValueError):
    """A session file or directory does not follow the anklelab session format."""


class OutputError(AnklelabError, OSError):
    """An output cannot be written as asked: it exists (and ``--force`` was not given, or it
    is not an output of the same kind), it lies inside an input, another process is writing
    it, or the file system refused."""


class ResultsFormatError(AnklelabError, ValueError):
    """A results directory or file is not what an anklelab analysis writes."""


class EventNotFoundError(AnklelabError, KeyError):
    """An expected event (heel contact, perturbation onset) is absent from a trial."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class NotFittedError(AnklelabError, ValueError, AttributeError):
    """An estimator was used before ``fit``."""


class SafetyLimitError(AnklelabError, RuntimeError):
    """A controller refused a command or tripped because a safety limit was violated."""
