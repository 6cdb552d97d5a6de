"""What the C3D and MATLAB mapping files share: channel conversions and the session table.

A mapping names, for each session column, where its values are in the lab's file and how to
turn them into the column's SI unit: ``value = stored * scale * unit factor``, negated when
``flip`` is true. The unit must be one of the column's quantity
(:data:`~anklelab.data._units.UNITS`): angles for ``motor_angle`` and ``ankle_angle``, lengths
for ``*_m`` columns, forces for ``*_n`` and the force channels, moments for ``mx``, ``my``,
``mz``, times for ``time_s``.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import AfterValidator, Field, model_validator
from pydantic_core import PydanticCustomError

from anklelab._params import Parameters, parameters_from_mapping, read_parameter_document
from anklelab.data._checks import info_from_mapping
from anklelab.data._units import UNITS
from anklelab.data.session import SessionInfo
from anklelab.errors import ParameterError, SessionFormatError
from anklelab.forceplate import CHANNELS, SIX_AXIS_CHANNELS

__all__ = [
    "ColumnMap",
    "column_quantity",
    "import_provenance",
    "key_error",
    "naming_the_mapping",
    "read_map",
    "session_info",
]

M = TypeVar("M", bound=Parameters)


def key_error(message: str) -> PydanticCustomError:
    """A validator's error that the mapping's message prefixes with the dotted key it concerns
    (and suffixes with the value given), like pydantic's own errors."""
    return PydanticCustomError("mapping", "{message}", {"message": message})


def _not_zero(value: float) -> float:
    if value == 0:
        raise key_error("expected a finite number other than 0")
    return value


def column_quantity(column: str) -> str | None:
    """The quantity of a session column (``None`` for an extra column of unknown unit)."""
    if column in ("motor_angle", "ankle_angle"):
        return "angle"
    if column == "time_s":
        return "time"
    if column in CHANNELS or column in SIX_AXIS_CHANNELS[:3] or column.endswith("_n"):
        return "force"
    if column in SIX_AXIS_CHANNELS[3:]:
        return "moment"
    if column.endswith("_m"):
        return "length"
    return None


class ColumnMap(Parameters):
    """How a stored signal becomes a session column.

    Attributes
    ----------
    units : str, optional
        The unit of ``stored * scale`` (see :data:`~anklelab.data._units.UNITS`); default the
        column's SI unit.
    scale : float
        Factor applied first (e.g. a gear ratio, a volts-to-units gain); finite, not 0.
    flip : bool
        Negate (the lab's axis or angle points the other way).
    """

    units: str | None = None
    scale: Annotated[float, Field(allow_inf_nan=False), AfterValidator(_not_zero)] = 1.0
    flip: bool = False

    def convert(self, values: ArrayLike, column: str) -> NDArray[np.float64]:
        """``values`` in the SI unit of ``column``."""
        factor = self.factor(column) * self.scale * (-1.0 if self.flip else 1.0)
        with np.errstate(over="ignore"):  # an overflow is an infinite value, refused by name
            return np.asarray(values, dtype=np.float64) * factor

    def factor(self, column: str) -> float:
        """The unit's factor to the SI unit of ``column`` (1 when no unit is given)."""
        quantity = column_quantity(column)
        if self.units is None:
            return 1.0
        if quantity is None:
            raise ParameterError(
                f"{column}.units: {self.units!r} given for a column of unknown quantity; give "
                "only a scale"
            )
        units = UNITS[quantity]
        if self.units not in units:
            raise ParameterError(
                f"{column}.units: expected one of {', '.join(units)} for a {quantity}, got "
                f"{self.units!r}"
            )
        return units[self.units]


class SessionTable(Parameters):
    """The ``[session]`` table: what ``session.toml`` says that the lab's files do not.

    ``platform``, ``subject`` and ``[session.geometry]`` as in ``session.toml``; any other key
    is kept (``SessionInfo.extra``).
    """

    model_config = Parameters.model_config | {"extra": "allow"}
    platform: str = "perturberator"
    subject: str = Field(min_length=1)
    geometry: dict[str, float]

    @model_validator(mode="after")
    def _no_derived_keys(self) -> SessionTable:
        derived = {"format", "sample_rate_hz", "force_plate"} & set(self.model_extra or {})
        if derived:
            raise ValueError(
                f"{', '.join(sorted(derived))}: come from the lab's files and the mapping, not "
                "from [session]"
            )
        return self


def read_map(path: str | Path, model: type[M], fmt: str) -> M:
    """Read and validate a mapping TOML file whose ``format`` must be ``fmt``.

    Raises
    ------
    ParameterError
        Naming the file and the dotted key (unknown keys get a "did you mean" hint).
    """
    path = Path(path)
    document = read_parameter_document(path, "toml", what="mapping file")
    if document.get("format") != fmt:
        raise ParameterError(f"{path}: format: expected {fmt!r}, got {document.get('format')!r}")
    try:
        return parameters_from_mapping(model, document, origin=str(path), with_sources=False)
    except ParameterError as exc:  # one line: "invalid parameters: key: ...; key: ..."
        raise ParameterError(str(exc).replace(":\n  ", ": ").replace("\n  ", "; ")) from None


def session_info(
    table: SessionTable, sample_rate_hz: float, force_plate: Mapping[str, Any]
) -> SessionInfo:
    """The session's metadata from the mapping's ``[session]``, the rate and the plate.

    Raises
    ------
    ParameterError
        Naming the mapping's key (``session.geometry.ankle_height_m``, ``plate.a_m``); the
        caller prefixes the mapping file.
    """
    document = {
        "format": "anklelab-session/1",
        "sample_rate_hz": float(sample_rate_hz),
        "force_plate": dict(force_plate),
        **table.model_dump(),
    }
    try:
        return info_from_mapping(document, "<map>", "session.")
    except SessionFormatError as exc:
        message = str(exc).removeprefix("<map>: ").replace("session.force_plate.", "plate.")
        raise ParameterError(message) from None


@contextmanager
def naming_the_mapping(path: Path) -> Iterator[None]:
    """Prefix the mapping file to a :class:`ParameterError` (an error in one of its keys)."""
    try:
        yield
    except ParameterError as exc:
        raise ParameterError(f"{path}: {exc}") from None


def import_provenance(
    source: Path, importer: str, mapping: Path, files: Sequence[Path] = ()
) -> dict[str, Any]:
    """The provenance of a session imported from ``source`` through ``mapping``: anklelab's
    version, the source's content hash and the mapping's SHA-256.

    The source's hash is that of the file ``source``, or, for a directory, of the ``files``
    inside it that were read, in order (:func:`~anklelab.data.directory.files_hash`).
    """
    from anklelab._version import __version__
    from anklelab.data.directory import files_hash
    from anklelab.data.store import session_hash

    return {
        "anklelab_version": __version__,
        "source_sha256": files_hash(source, files) if files else session_hash(source),
        "import": {
            "anklelab_version": __version__,
            "importer": importer,
            "source_name": source.name,
            "mapping": mapping.name,
            "mapping_sha256": hashlib.sha256(mapping.read_bytes()).hexdigest(),
        },
    }
