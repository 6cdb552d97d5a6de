"""What the ``anklelab capstan`` commands share: one options object for the platform, control
rate, person, compensation, friction model, seed and output, the option types with their
checks, and the output side: ``--out DIR`` is one run of one command, checked before any work,
locked, built whole and recorded in its run manifest (:mod:`anklelab.commands._files`).

Nothing here imports the implementation (numpy, the twin): ``anklelab --help`` stays fast.
"""

import functools
import inspect
import json
import math
import typing
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from enum import Enum, StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from anklelab.commands._options import ForceOption, SeedOption
from anklelab.errors import ParameterError


class Person(StrEnum):
    """Who stands on the platform."""

    none = "none"
    seated = "seated"
    standing = "standing"
    walking = "walking"


def number(
    *,
    low: float | None = None,
    high: float | None = None,
    strict: bool = False,
    infinite: bool = False,
) -> Callable[[Any, Any, float], float]:
    """An option callback accepting only finite numbers within ``[low, high]`` (``strict``:
    ``(low, high]``); ``infinite`` also accepts ``inf``."""

    def check(ctx: Any, param: Any, value: float) -> float:
        name = "/".join(param.opts) if param is not None else "value"
        bounds = []
        if low is not None:
            bounds.append(f"{'>' if strict else '>='} {low:g}")
        if high is not None:
            bounds.append(f"<= {high:g}")
        kind = "a number (or inf)" if infinite else "a finite number"
        wanted = f"{kind} {' and '.join(bounds)}" if bounds else kind
        bad = math.isnan(value) or (math.isinf(value) and not (infinite and value > 0))
        bad |= low is not None and (value <= low if strict else value < low)
        bad |= high is not None and value > high
        if bad:
            raise ParameterError(f"{name}: expected {wanted}; got {value:g}")
        return value

    return check


def numbers(text: str, option: str, *, low: float, high: float, finite: bool = True) -> list[float]:
    """Comma-separated numbers of an option, each within ``[low, high]``; with
    ``finite=False`` NaN and infinities pass (they are for the safety monitor to refuse)."""
    values = []
    for item in text.split(","):
        try:
            value = float(item)
        except ValueError:
            raise ParameterError(
                f"{option}: {item.strip()!r} is not a number; expected comma-separated numbers"
            ) from None
        out_of_range = math.isfinite(value) and not low <= value <= high
        if out_of_range or (finite and not math.isfinite(value)):
            raise ParameterError(
                f"{option}: expected numbers in [{low:g}, {high:g}]; got {item.strip()}"
            )
        values.append(value)
    return values


def checked(
    help: str,
    *,
    low: float | None = None,
    high: float | None = None,
    strict: bool = False,
    infinite: bool = False,
) -> Any:
    """A number option with its help and range (see :func:`number`)."""
    callback = number(low=low, high=high, strict=strict, infinite=infinite)
    return typer.Option(help=help, callback=callback, metavar="NUMBER")


# ------------------------------------------------------------------------- the shared options

ParamsOption = Annotated[
    Path | None,
    typer.Option(
        "--params",
        help="A capstan parameter file (TOML, like `anklelab platform show capstan`) instead "
        "of the shipped one.",
        show_default=False,
    ),
]
RateOption = Annotated[
    float,
    typer.Option(
        "--sample-rate",
        help="Control rate, Hz (1000-10000).",
        callback=number(low=1000.0, high=10000.0),
        metavar="NUMBER",
    ),
]
PersonOption = Annotated[
    Person,
    typer.Option(
        help="Who is on the platform: nobody, the relaxed seated user, or a standing or "
        "stepping person (the twin's human ankle, body weight, sway and stretch reflex).",
    ),
]
GravityOption = Annotated[
    bool,
    typer.Option("--gravity/--no-gravity", metavar="", help="Feed-forward gravity compensation."),
]
FrictionCompOption = Annotated[
    float,
    typer.Option(
        "--friction-comp",
        help="Fraction (0-1) of the model friction compensated.",
        callback=number(low=0.0, high=1.0),
        metavar="NUMBER",
    ),
]
FrictionModelOption = Annotated[
    Path | None,
    typer.Option(
        "--friction-model",
        help="friction.json from `anklelab identify friction`: the controller's and "
        "observer's model (default: the twin's true friction).",
        show_default=False,
    ),
]
SettlingOption = Annotated[
    float,
    typer.Option(
        "--settling-time",
        help="Design settling time of the position loop, s.",
        callback=number(low=0.0, high=10.0, strict=True),
        metavar="NUMBER",
    ),
]
OutOption = Annotated[
    Path | None,
    typer.Option(
        "--out",
        "-o",
        help="Directory to write: the results (JSON), the figure (PNG) and run.json.",
        show_default=False,
    ),
]


class Written:
    """Where a capstan command writes its files: the run's directory, or nowhere (no ``--out``).

    Attributes
    ----------
    directory : Path or None
        The run's directory (renamed into place when the command ends), or ``None``.
    """

    def __init__(self, directory: Path | None) -> None:
        self.directory = directory

    def json(self, name: str, results: Any) -> None:
        """Write ``name``: one object, ``results`` (non-finite numbers as ``null``)."""
        if self.directory is None:
            return
        from anklelab._atomic import write_text_atomic

        text = json.dumps({"results": _jsonable(results)}, indent=2, allow_nan=False) + "\n"
        write_text_atomic(self.directory / name, text)

    def path(self, name: str) -> Path | None:
        """Where to write the file ``name`` (a figure); ``None`` without ``--out``."""
        return None if self.directory is None else self.directory / name


@dataclass(frozen=True)
class SetupOptions:
    """The options every simulating ``capstan`` command takes, gathered."""

    params: Path | None
    sample_rate: float
    person: Person
    gravity: bool
    friction_comp: float
    friction_model: Path | None
    settling_time: float
    seed: int
    out: Path | None
    force: bool

    def setup(self, **changes: Any) -> Any:
        """The :class:`~anklelab.experiments.capstan.CapstanSetup` these options describe;
        ``changes`` override or add fields (e.g. ``feedforward=True``)."""
        from anklelab.experiments.capstan import CapstanSetup
        from anklelab.ident.friction import read_friction_json

        platform = self.platform()
        model = None
        if self.friction_model is not None:
            model = read_friction_json(
                self.friction_model, stribeck_exponent=platform.friction.stribeck_exponent
            )
        person = self.person.value
        fields: dict[str, Any] = {
            "params": platform,
            "settling_time_s": self.settling_time,
            "fs": self.sample_rate,
            "with_user": person == "seated",
            "person": person if person in ("standing", "walking") else None,
            "gravity_compensation": self.gravity,
            "friction_compensation": self.friction_comp,
            "model_friction": model,
        }
        return CapstanSetup(**(fields | changes))

    def platform(self) -> Any:
        """The capstan parameters (``--params`` or the shipped set)."""
        from anklelab.platforms import load_platform

        return load_platform("capstan", self.params)

    @contextmanager
    def output(
        self, command: str, settings: Mapping[str, Any], inputs: Sequence[Path] = ()
    ) -> Iterator[Written]:
        """The output of ``anklelab capstan COMMAND``, checked before any work.

        With ``--out``, the directory is checked (not replaced without ``--force``, never a
        different command's output, never inside an input), locked, built whole and published
        with its ``run.json``: these options and ``settings``, and each input file named
        (``--params``, ``--friction-model`` and ``inputs``) with its SHA-256. Without ``--out``
        nothing is written.
        """
        if self.out is None:
            yield Written(None)
            return
        from anklelab.commands._files import output_directory

        named = [p for p in (self.params, self.friction_model, *inputs) if p is not None]
        with output_directory(
            self.out, command=f"capstan {command}", force=self.force, inputs=named
        ) as run:
            yield Written(run.directory)
            shared = {k: v for k, v in asdict(self).items() if k not in ("out", "force")}
            run.settings.update(_jsonable(shared | dict(settings)))
            for path in named:
                run.add_input(path)


def _jsonable(value: Any) -> Any:
    """Plain JSON values: enums by value, paths as text, arrays as lists, non-finite as None."""
    if isinstance(value, Enum):
        return value.value
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if hasattr(value, "tolist"):
        return _jsonable(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


_SHARED: tuple[tuple[str, Any, Any], ...] = (
    ("params", ParamsOption, None),
    ("sample_rate", RateOption, 1000.0),
    ("person", PersonOption, Person.seated),
    ("gravity", GravityOption, True),
    ("friction_comp", FrictionCompOption, 0.0),
    ("friction_model", FrictionModelOption, None),
    ("settling_time", SettlingOption, 0.2),
    ("seed", SeedOption, 0),
    ("out", OutOption, None),
    ("force", ForceOption, False),
)


def with_setup_options(
    *, exclude: tuple[str, ...] = (), **defaults: Any
) -> Callable[[Callable[..., None]], Callable[..., None]]:
    """Give a command the shared options; it receives them as ``options: SetupOptions``.

    ``defaults`` change a shared option's default for this command; ``exclude`` leaves some
    out (the command then gets their default, e.g. the scene file names its person).
    """

    def decorate(command: Callable[..., None]) -> Callable[..., None]:
        hints = typing.get_type_hints(command, include_extras=True)
        own = [
            p.replace(annotation=hints.get(p.name, p.annotation))
            for p in inspect.signature(command).parameters.values()
            if p.name != "options"
        ]
        shared = [
            inspect.Parameter(
                name,
                inspect.Parameter.KEYWORD_ONLY,
                default=defaults.get(name, default),
                annotation=annotation,
            )
            for name, annotation, default in _SHARED
        ]

        @functools.wraps(command)
        def run(**kwargs: Any) -> None:
            options = SetupOptions(**{name: kwargs.pop(name) for name, _, _ in _SHARED})
            command(options=options, **kwargs)

        parameters = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY) for p in own] + shared
        run.__signature__ = inspect.Signature(parameters)  # type: ignore[attr-defined]
        run.__annotations__ = {p.name: p.annotation for p in parameters}
        del run.__wrapped__  # typer must read the new signature, not the wrapped one
        return run

    return decorate


# --------------------------------------------------------------------------------- printing


def table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]]) -> None:
    """Print a table: the first column left-aligned, the others right-aligned."""
    out = Table(title=title)
    for k, column in enumerate(columns):
        out.add_column(column, justify="left" if k == 0 else "right")
    for row in rows:
        out.add_row(*row)
    Console().print(out)


def fault_text(code: float) -> str:
    """A latched fault code as its name (``none`` when nothing tripped); tables list the
    meanings below them (:func:`explain_faults`)."""
    from anklelab.control.safety import Fault

    return "none" if int(code) == 0 else Fault(int(code)).name


def explain_faults(codes: Iterable[float]) -> None:
    """Print one line per fault that tripped: its name and what it means."""
    from anklelab.control.safety import Fault

    for code in sorted({int(c) for c in codes if c}):
        Console().print(Fault(code).describe())


def fail_on_fault(command: str, code: float, what: str) -> None:
    """After the results are printed: a run that latched a fault ends in one ``error:`` line."""
    from anklelab.control.safety import Fault

    if code:
        raise ParameterError(f"capstan {command}: {what} latched {Fault(int(code)).describe()}")
