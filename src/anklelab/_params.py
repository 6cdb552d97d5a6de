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
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, PrivateAttr, ValidationError

from anklelab.errors import ParameterError

__all__ = [
    "SOURCE_KINDS",
    "Parameters",
    "did_you_mean",
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


def did_you_mean(key: str, options: Iterable[str]) -> str:
    """A hint naming the option closest to ``key`` (``""`` if none is close).

    Names are case-sensitive, but a case slip is the likeliest typo, so an option that differs
    from ``key`` only in case is named first, and said to be one.

    >>> did_you_mean("fz4", ["fz1", "fz3", "Fz4"])
    " ('Fz4' differs from 'fz4' only in case; names are case-sensitive)"
    >>> did_you_mean("fz_3", ["fz1", "fz3"])
    " (did you mean 'fz3'?)"
    """
    options = list(options)
    folded = [option.casefold() for option in options]
    close = difflib.get_close_matches(key.casefold(), folded, n=1)
    if not close:
        return ""
    match = options[folded.index(close[0])]
    if close[0] == key.casefold():
        return f" ({match!r} differs from {key!r} only in case; names are case-sensitive)"
    return f" (did you mean {match!r}?)"


def _split_sources(node: Any, prefix: str, sources: dict[str, str], origin: str) -> Any:
    """Replace ``{value, source}`` leaves by their value, collecting sources by dotted key.

    TOML arrays become tuples (parameter objects are immutable).
    """
    if isinstance(node, list):
        return tuple(node)
    if not isinstance(node, dict):
        return node
    if "value" in node and set(node) <= {"value", "source"}:
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


def _model_at(model: type[BaseModel], loc: tuple[Any, ...]) -> type[BaseModel]:
    for key in loc:
        field = model.model_fields.get(str(key))
        annotation = getattr(field, "annotation", None)
        if not (isinstance(annotation, type) and issubclass(annotation, BaseModel)):
            break
        model = annotation
    return model


def _describe(error: Mapping[str, Any], model: type[BaseModel]) -> str:
    loc = tuple(error["loc"])
    key = ".".join(str(part) for part in loc)
    if error["type"] == "missing":
        return f"{key}: required key is missing"
    if error["type"] == "extra_forbidden":
        parent = _model_at(model, loc[:-1])
        return f"{key}: unknown key{did_you_mean(str(loc[-1]), parent.model_fields)}"
    return f"{key}: {error['msg']}; got {error.get('input')!r}"


def parameters_from_mapping(model: type[P], data: Mapping[str, Any], *, origin: str) -> P:
    """Validate a nested mapping into ``model``; errors name ``origin`` and the dotted key."""
    sources: dict[str, str] = {}
    values = _split_sources(dict(data), "", sources, origin)
    try:
        params = model.model_validate(values)
    except ValidationError as exc:
        lines = "\n  ".join(_describe(err, model) for err in exc.errors())
        raise ParameterError(f"{origin}: invalid parameters:\n  {lines}") from None
    params._sources = sources
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
