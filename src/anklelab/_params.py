"""Typed, validated, frozen parameter objects loaded from TOML.

A parameter file is a TOML document whose tables mirror a pydantic model. A leaf is either a
plain value or an inline table ``{value = ..., source = "..."}``; the source says where the number
comes from and starts with ``paper 000``, ``paper 001``, ``datasheet`` or ``assumed``. Loading
rejects a missing key, an unknown key (with a "did you mean" hint), a wrong type or a value out
of range with one message that names the file and the dotted key.
"""

from __future__ import annotations

import difflib
import json
import os
import stat
import tomllib
import types
import typing
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, PrivateAttr, ValidationError

from anklelab.errors import ParameterError

__all__ = [
    "SOURCE_KINDS",
    "SYNONYMS",
    "Parameters",
    "did_you_mean",
    "dotted_leaves",
    "found_instead",
    "load_parameters",
    "parameters_from_mapping",
    "read_parameter_document",
]

SOURCE_KINDS = ("paper 000", "paper 001", "datasheet", "assumed")

P = TypeVar("P", bound="Parameters")


class Parameters(BaseModel):
    """Base of every parameter section: frozen, strict types, unknown keys rejected."""

    model_config = ConfigDict(frozen=True, strict=True, extra="forbid")
    _sources: dict[str, str] = PrivateAttr(default_factory=dict)

    @property
    def sources(self) -> dict[str, str]:
        """Where each value comes from, by dotted key (only values whose file gave a source)."""
        return dict(self._sources)

    def replace(self: P, changes: Mapping[str, Any]) -> P:
        """Return a validated copy with dotted keys changed.

        Parameters
        ----------
        changes : mapping
            ``{"foot.inertia_kgm2": 0.25, ...}``; each key is a dotted path into this object.

        Examples
        --------
        >>> from anklelab.platforms import load_platform
        >>> p = load_platform("capstan")
        >>> p.replace({"gearhead.ratio": 14.0}).gearhead.ratio
        14.0
        """
        data = self.model_dump()
        for dotted, value in changes.items():
            node = data
            *parents, leaf = dotted.split(".")
            for key in parents:
                if not isinstance(node.get(key), dict):
                    raise ParameterError(f"{dotted!r}: {key!r} is not a parameter section")
                node = node[key]
            if leaf not in node:
                raise ParameterError(f"{dotted!r}: unknown parameter{did_you_mean(leaf, node)}")
            node[leaf] = value
        changed = parameters_from_mapping(type(self), data, origin="replace()")
        changed._sources = {k: v for k, v in self._sources.items() if k not in changes}
        return changed


SYNONYMS = {
    "lowpass_hz": "cutoff_hz",
    "low_pass_hz": "cutoff_hz",
    "cutoff": "cutoff_hz",
    "cut_off_hz": "cutoff_hz",
    "fs": "sample_rate_hz",
    "fs_hz": "sample_rate_hz",
    "sampling_rate_hz": "sample_rate_hz",
    "sample_rate": "sample_rate_hz",
    "window": "window_ms",
    "n_bootstrap": "bootstrap_reps",
    "bootstrap": "bootstrap_reps",
    "random_state": "seed",
}
"""Names users write for a setting that anklelab spells otherwise (other tools' words)."""


def did_you_mean(given: str, valid: Iterable[str]) -> str:
    """A hint naming the valid name closest to the name the user ``given`` (``""`` if none).

    ``valid`` are the names anklelab accepts: the hint always names one of them, never the
    user's own spelling. Names are case-sensitive, but a case slip is the likeliest typo, so a
    valid name that differs only in case is named first, and said to be one; a known synonym
    (:data:`SYNONYMS`, e.g. ``lowpass_hz`` for ``cutoff_hz``) comes next.

    >>> did_you_mean("Fz4", ["fz1", "fz3", "fz4"])
    " ('fz4' differs from 'Fz4' only in case; names are case-sensitive)"
    >>> did_you_mean("fz_3", ["fz1", "fz3"])
    " (did you mean 'fz3'?)"
    >>> did_you_mean("lowpass_hz", ["cutoff_hz", "filter_order"])
    " (did you mean 'cutoff_hz'?)"
    >>> did_you_mean("walking", ["walking", "calibration"])
    ''
    """
    options = [option for option in valid if option != given]
    key = given
    if SYNONYMS.get(key) in options and key.casefold() not in map(str.casefold, options):
        return f" (did you mean {SYNONYMS[key]!r}?)"
    folded = [option.casefold() for option in options]
    close = difflib.get_close_matches(key.casefold(), folded, n=1)
    if not close:
        return ""
    match = options[folded.index(close[0])]
    if close[0] == key.casefold():
        return f" ({match!r} differs from {key!r} only in case; names are case-sensitive)"
    return f" (did you mean {match!r}?)"


def found_instead(required: str, present: Iterable[str]) -> str:
    """A hint for a required name that is missing: the present name that looks like it.

    The hint points at the name to write (``required``), never offers the user's spelling as
    the answer.

    >>> found_instead("fz4", ["fz1", "fz_4"])
    " (found 'fz_4': rename it to 'fz4')"
    >>> found_instead("fz4", ["Fz4"])
    " (found 'Fz4': rename it to 'fz4'; names are case-sensitive)"
    """
    present = list(present)
    folded = [name.casefold() for name in present]
    synonym = [name for name in present if SYNONYMS.get(name) == required]
    close = synonym or [
        present[folded.index(m)]
        for m in difflib.get_close_matches(required.casefold(), folded, n=1)
    ]
    if not close:
        return ""
    case = "; names are case-sensitive" if close[0].casefold() == required.casefold() else ""
    return f" (found {close[0]!r}: rename it to {required!r}{case})"


def dotted_leaves(tree: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """The leaves of a nested mapping by dotted key.

    >>> dotted_leaves({"motor": {"kt": 0.1, "poles": 8}, "name": "x"})
    {'motor.kt': 0.1, 'motor.poles': 8, 'name': 'x'}
    """
    leaves: dict[str, Any] = {}
    for key, value in tree.items():
        dotted = f"{prefix}.{key}" if prefix else str(key)
        leaves |= dotted_leaves(value, dotted) if isinstance(value, Mapping) else {dotted: value}
    return leaves


def _split_sources(node: Any, prefix: str, sources: dict[str, str] | None, origin: str) -> Any:
    """Replace ``{value, source}`` leaves by their value, collecting sources by dotted key
    (with ``sources=None``, a document without sources: every table is kept as it is).

    TOML arrays become tuples (parameter objects are immutable).
    """
    if isinstance(node, list):
        return tuple(node)
    if not isinstance(node, dict):
        return node
    if sources is not None and "value" in node and set(node) <= {"value", "source"}:
        source = node.get("source", "")
        if not isinstance(source, str) or not source.startswith(SOURCE_KINDS):
            raise ParameterError(
                f"{origin}: {prefix}: source must start with one of {', '.join(SOURCE_KINDS)}; "
                f"got {source!r}"
            )
        sources[prefix] = source
        return _split_sources(node["value"], prefix, {}, origin)
    return {
        key: _split_sources(value, f"{prefix}.{key}" if prefix else key, sources, origin)
        for key, value in node.items()
    }


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """The model an annotation holds: itself, or the model of ``X | None``, ``tuple[X, ...]``,
    ``dict[str, X]``..."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    return next(filter(None, map(_model_in, typing.get_args(annotation))), None)


def _without_none(annotation: Any) -> Any:
    """``X`` for ``X | None``; any other annotation as it is."""
    members = [a for a in typing.get_args(annotation) if a is not type(None)]
    union = isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is typing.Union
    return members[0] if union and len(members) == 1 else annotation


def _tagged(annotation: Any, tag: Any) -> type[BaseModel] | None:
    """The member of a union of models whose ``Literal`` field takes the value ``tag`` (the
    discriminator pydantic puts in an error's location), or ``None``."""
    for member in typing.get_args(annotation):
        found = _model_in(member)
        for field in found.model_fields.values() if found is not None else ():
            if typing.get_origin(field.annotation) is typing.Literal and tag in typing.get_args(
                field.annotation
            ):
                return found
    return None


def _model_at(
    model: type[BaseModel], loc: tuple[Any, ...]
) -> tuple[type[BaseModel] | None, tuple[Any, ...]]:
    """The model at ``loc`` (``("walking", 0)`` is an element of the tuple ``walking``), or
    ``None`` where the location is not in a model; and ``loc`` without the discriminators of
    unions of models (``trials.events.ignore`` is ``[trials] ignore`` in the file)."""
    annotation: Any = model
    shown = []
    for i, key in enumerate(loc):
        annotation = _without_none(annotation)
        origin = typing.get_origin(annotation)
        if origin in (tuple, list, dict):  # the key is an index or a mapping key
            annotation = typing.get_args(annotation)[1 if origin is dict else 0]
            shown.append(key)
            continue
        if (member := _tagged(annotation, key)) is not None:
            annotation = member
            continue
        shown.append(key)
        current = _model_in(annotation)
        field = current.model_fields.get(str(key)) if current is not None else None
        if field is None:
            return None, (*shown, *loc[i + 1 :])
        annotation = field.annotation
    return _model_in(annotation), tuple(shown)


def _describe(error: Mapping[str, Any], model: type[BaseModel]) -> str:
    loc = tuple(error["loc"])
    _, shown = _model_at(model, loc)
    key = ".".join(str(part) for part in shown)
    if error["type"] == "missing":
        return f"{key}: required key is missing"
    if error["type"] == "extra_forbidden":
        parent, _ = _model_at(model, loc[:-1])
        hint = did_you_mean(str(loc[-1]), parent.model_fields) if parent is not None else ""
        return f"{key}: unknown key{hint}"
    if error["type"] == "value_error":  # a model validator's own message names its keys
        return str(error["ctx"]["error"])
    return f"{key}: {error['msg']}; got {error.get('input')!r}"


def parameters_from_mapping(
    model: type[P], data: Mapping[str, Any], *, origin: str, with_sources: bool = True
) -> P:
    """Validate a nested mapping into ``model``; errors name ``origin`` and the dotted key.

    With ``with_sources`` (parameter files), a leaf may be ``{value = ..., source = "..."}``;
    without (documents whose own tables have a ``value`` key, such as a mapping's constant
    column ``{ value = 0 }``), every table is validated as it is.
    """
    sources: dict[str, str] | None = {} if with_sources else None
    values = _split_sources(dict(data), "", sources, origin)
    try:
        params = model.model_validate(values)
    except ValidationError as exc:
        lines = "\n  ".join(_describe(err, model) for err in exc.errors())
        raise ParameterError(f"{origin}: invalid parameters:\n  {lines}") from None
    params._sources = sources or {}
    return params


def load_parameters(model: type[P], path: str | Path) -> P:
    """Load and validate a TOML parameter file.

    Parameters
    ----------
    model : type
        The :class:`Parameters` subclass describing the file.
    path : str or Path
        The TOML file.

    Returns
    -------
    Parameters
        A frozen instance; its ``sources`` give where each value comes from.
    """
    data = read_parameter_document(path, "toml", what="parameter file")
    return parameters_from_mapping(model, data, origin=str(path))


_MAX_DOCUMENT_BYTES = 64 << 20


def _read_text(path: Path, what: str) -> str:
    """The UTF-8 text of a regular file of at most 64 MiB (never blocks on a FIFO)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        raise ParameterError(f"{path}: {what} not found") from None
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read the {what}: {exc.strerror}") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        kind = "a directory" if stat.S_ISDIR(mode) else "not a regular file"
        raise ParameterError(f"{path}: {kind}; expected a {what}")
    with os.fdopen(fd, "rb") as f:
        data = f.read(_MAX_DOCUMENT_BYTES + 1)
    if len(data) > _MAX_DOCUMENT_BYTES:
        raise ParameterError(f"{path}: larger than {_MAX_DOCUMENT_BYTES >> 20} MiB; not a {what}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ParameterError(
            f"{path}: not UTF-8 text (byte {data[exc.start]:#04x} at offset {exc.start}); "
            f"expected a {what}"
        ) from None


def read_parameter_document(
    path: str | Path, kind: Literal["toml", "json"], *, what: str
) -> dict[str, Any]:
    """Parse a TOML or JSON file whose top level is a table / object.

    Parameters
    ----------
    path : str or Path
        The file.
    kind : {"toml", "json"}
        Its syntax.
    what : str
        What the file is, for the message when it is missing (``"filter file"``).

    Raises
    ------
    ParameterError
        Naming the file: missing, not a regular file, not UTF-8, not valid TOML/JSON (with the
        parser's position), nested too deeply, or not a table at the top level.
    """
    path = Path(path)
    text = _read_text(path, what)
    try:
        data = tomllib.loads(text) if kind == "toml" else json.loads(text)
    except (tomllib.TOMLDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"{path}: not valid {kind.upper()}: {exc}") from None
    except RecursionError:
        raise ParameterError(f"{path}: not a {what}: tables nested too deeply") from None
    if not isinstance(data, dict):
        raise ParameterError(f"{path}: expected a JSON object, got {type(data).__name__}")
    return data
