"""Study files: what a study varies, and the cells it expands into.

A study file is TOML. Its fixed settings are three tables, and what varies is either a
``[grid]`` (every combination) or a seeded ``[sample]`` (random draws); every setting is named
by a dotted key with one of three prefixes:

- ``twin.KEY``: how each session is simulated (:class:`TwinSettings`: foot, trials per timing
  point, unperturbed and calibration trials, a noise scale, a randomised-twin family);
- ``params.SECTION.KEY``: any Perturberator parameter (``params.geometry.misalignment_anterior_m``,
  ``params.walking.amplitude_rad``, ``params.prosthetic.shell_compliance_rad_per_nm``...);
- ``analysis.KEY``: any walking-analysis setting (``analysis.window_ms``, ``analysis.cutoff_hz``,
  ``analysis.bootstrap_reps``...).

::

    name = "misalignment"
    seeds = 4                      # seeds 0..3, or a list: [3, 7, 11]

    [twin]
    trials_per_point = 40

    [analysis]
    bootstrap_reps = 50

    [grid]
    "params.geometry.misalignment_anterior_m" = [0.0, 0.008, 0.016]

A ``[sample]`` draws ``n`` points with its own ``seed``; each key gives ``{uniform = [lo, hi]}``,
``{loguniform = [lo, hi]}``, ``{integers = [lo, hi]}`` (whole numbers, both ends included) or
``{choice = [...]}``. Every point (grid or sample) runs once per seed. The same seeds serve every
point (common random numbers): two settings see the same gait, noise and trial order, so their
difference is not masked by seed-to-seed scatter.

Identical points are one point, computed once: a grid that lists a value twice (``100`` and
``100.0`` are the same value), or a sample whose ``choice`` or ``integers`` draws repeat, has
fewer points than values or draws.

A cell is one (settings, seed): a pure description from which a worker simulates and analyses
one session. Its key is a hash of its content (and of the anklelab version), so a resumed study
knows which cells it has.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import Field, model_validator

from anklelab._params import Parameters, did_you_mean, read_parameter_document
from anklelab._session_limits import MAX_TRIALS_PER_POINT, MAX_UNPERTURBED
from anklelab._version import __version__, code_fingerprint
from anklelab.errors import AnklelabError, ParameterError

__all__ = [
    "MAX_SESSIONS",
    "PREFIXES",
    "Cell",
    "Study",
    "TwinSettings",
    "load_study",
    "study_from_mapping",
]

PREFIXES = ("twin", "params", "analysis")
FORMAT = "anklelab-study/1"
MAX_SESSIONS = 100_000
"""Sessions (points x seeds) one study may hold: counted from the file, before any point is
expanded. A study this size takes days on one machine; beyond it, split the study."""


class TwinSettings(Parameters):
    """How each session of a study is simulated (``twin.*`` keys).

    Attributes
    ----------
    foot : {"prosthetic", "human"}
        What walks on the plate (ignored when ``randomised`` draws the foot).
    trials_per_point, n_unperturbed, n_calibration
        Protocol size; unset means the parameter set's (or, randomised, the draw's). At most
        1000 trials per point and 4000 unperturbed trials, as ``simulate`` takes.
    unperturbed_per_point
        Instead of ``n_unperturbed``: that many unperturbed trials per perturbed trial of one
        timing point (paper 000: 400 for 100, so 4), so that the protocol scales as a whole when
        ``trials_per_point`` varies.
    noise_scale
        Factor on every noise source: force-plate noise and drift, goniometer precision,
        load-cell noise.
    randomised : {"none", "prosthetic", "human", "random"}
        Draw each session's platform, subject and foot from the randomised twin's family
        (:func:`anklelab.experiments.draw_twin`); ``params.*`` keys then apply on top of the draw.
    bench
        Simulate the prosthesis's bench tests (unset: with the prosthetic foot only).
    artefacts
        Measurement artefacts on (paper 000's lab) or off (ideal sensors and gait).
    """

    foot: Literal["prosthetic", "human"] = "prosthetic"
    trials_per_point: int | None = Field(None, ge=1, le=MAX_TRIALS_PER_POINT)
    n_unperturbed: int | None = Field(None, ge=1, le=MAX_UNPERTURBED)
    unperturbed_per_point: float | None = Field(None, gt=0)
    n_calibration: int | None = Field(None, ge=1)
    noise_scale: float = Field(1.0, ge=0)
    randomised: Literal["none", "prosthetic", "human", "random"] = "none"
    bench: bool | None = None
    artefacts: bool = True

    @model_validator(mode="after")
    def _one_unperturbed_count(self) -> TwinSettings:
        if self.n_unperturbed is not None and self.unperturbed_per_point is not None:
            raise ValueError(
                "n_unperturbed and unperturbed_per_point: give one of them (both were given, "
                "and one would be ignored)"
            )
        return self


@dataclass(frozen=True)
class Cell:
    """One session of a study: settings by prefix, and the seed.

    ``twin``, ``params`` and ``analysis`` map keys (without their prefix) to values;
    ``variables`` holds the grid or sample values of this cell by their full dotted key;
    ``base`` is a whole parameter set (from ``params_file``) or None for the shipped one.
    """

    index: int
    seed: int
    twin: dict[str, Any]
    params: dict[str, Any]
    analysis: dict[str, Any]
    variables: dict[str, Any]
    base: dict[str, Any] | None = field(default=None, repr=False)

    @property
    def key(self) -> str:
        """A hash of what the cell computes (not of its position in the study), and of the
        anklelab version and code computing it."""
        content = {
            "anklelab_version": __version__,
            "anklelab_code": code_fingerprint(),
            "seed": self.seed,
            "twin": self.twin,
            "params": self.params,
            "analysis": self.analysis,
            "base": self.base,
        }
        return hashlib.sha256(_canonical_text(content).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Study:
    """A parsed study file.

    Attributes
    ----------
    name : str
    seeds : tuple of int
    fixed : dict
        Fixed settings by full dotted key (``"twin.trials_per_point"``).
    grid : dict
        Grid values by full dotted key (empty for a sample study).
    sample : dict
        ``{"n": ..., "seed": ..., key: distribution}`` (empty for a grid study).
    base : dict or None
        Parameter set from ``params_file`` (already validated).
    params_file : dict or None
        Where ``base`` was read: ``{"path": the file's absolute path, "sha256": its SHA-256}``.
    """

    name: str
    seeds: tuple[int, ...]
    fixed: dict[str, Any]
    grid: dict[str, list[Any]]
    sample: dict[str, Any]
    base: dict[str, Any] | None = None
    params_file: dict[str, str] | None = None

    @property
    def varied(self) -> list[str]:
        """The keys that change from cell to cell (besides the seed), in file order."""
        return list(self.grid) or [k for k in self.sample if k not in ("n", "seed")]

    def points(self) -> list[dict[str, Any]]:
        """The grid's combinations or the sample's draws, each by full dotted key; a point equal
        to an earlier one (``100`` and ``100.0`` are equal) is left out: it is the same
        computation."""
        if self.grid:
            keys, values = list(self.grid), self.grid.values()
            drawn = [dict(zip(keys, v, strict=True)) for v in itertools.product(*values)]
        elif self.sample:
            rng = np.random.default_rng(self.sample["seed"])
            drawn = [
                {key: _draw(rng, self.sample[key]) for key in self.varied}
                for _ in range(self.sample["n"])
            ]
        else:
            drawn = [{}]
        distinct: dict[str, dict[str, Any]] = {}
        for point in drawn:
            distinct.setdefault(_canonical_text(point), point)
        return list(distinct.values())

    def cells(self) -> list[Cell]:
        """Every (point, seed), seeds innermost."""
        out: list[Cell] = []
        for point in self.points():
            split = _by_prefix(self.fixed | point)
            for seed in self.seeds:
                out.append(
                    Cell(len(out), seed, split["twin"], split["params"], split["analysis"],
                         point, self.base)
                )  # fmt: skip
        return out

    def describe(self) -> dict[str, Any]:
        """The study as a JSON-able document (recorded in the output)."""
        return {
            "format": FORMAT,
            "name": self.name,
            "seeds": list(self.seeds),
            "fixed": self.fixed,
            "grid": self.grid,
            "sample": self.sample,
            "params_file": self.params_file,
        }


def load_study(path: str | Path) -> Study:
    """Read and validate a study file (see the module docstring); errors name the file and key.

    Every cell's settings are validated here, before anything runs: a typo in the last grid
    value fails at once rather than hours into the study.
    """
    path = Path(path)
    data = read_parameter_document(path, "toml", what="study file")
    return study_from_mapping(data, origin=str(path), root=path.parent)


def study_from_mapping(data: dict[str, Any], *, origin: str, root: Path | None = None) -> Study:
    """Validate a study document (the parsed TOML); ``root`` resolves ``params_file``."""
    allowed = {"format", "name", "seeds", "params_file", *PREFIXES, "grid", "sample"}
    for key in data:
        if key not in allowed:
            raise ParameterError(f"{origin}: {key}: unknown key{did_you_mean(key, allowed)}")
    _check_finite(data, origin)
    if data.get("format", FORMAT) != FORMAT:
        raise ParameterError(f"{origin}: format: expected {FORMAT!r}, got {data['format']!r}")
    if "grid" in data and "sample" in data:
        raise ParameterError(f"{origin}: give either [grid] or [sample], not both")
    if not {"grid", "sample", "seeds"} & data.keys():
        raise ParameterError(
            f"{origin}: nothing to run: give a [grid] or a [sample] of settings to vary, or "
            "seeds = N to repeat the fixed settings N times"
        )
    name = data.get("name", Path(origin).stem)
    if not isinstance(name, str) or not name:
        raise ParameterError(f"{origin}: name: expected a non-empty string, got {name!r}")
    seeds = _seeds(data.get("seeds", 1), origin)
    fixed: dict[str, Any] = {}
    for prefix in PREFIXES:
        table = data.get(prefix, {})
        if not isinstance(table, dict):
            raise ParameterError(f"{origin}: [{prefix}]: expected a table")
        fixed |= {f"{prefix}.{key}": value for key, value in _flatten(table, prefix).items()}
    for table in ("grid", "sample"):
        if not isinstance(data.get(table, {}), dict):
            raise ParameterError(f"{origin}: [{table}]: expected a table")
    grid = dict(data.get("grid", {}))
    if "grid" in data and not grid:
        raise ParameterError(
            f"{origin}: [grid]: empty; give at least one KEY = [values] (or no [grid], to "
            "repeat the fixed settings over the seeds)"
        )
    for key, values in grid.items():
        _check_nested("grid", key, values, origin)
        _check_key(key, origin, "grid")
        if not isinstance(values, list) or not values:
            raise ParameterError(f"{origin}: grid.{key}: expected a non-empty list of values")
    sample = dict(data.get("sample", {}))
    if "sample" in data:
        _check_sample(sample, origin)
    for key in fixed.keys() & {*grid, *sample}:
        table = "grid" if key in grid else "sample"
        raise ParameterError(
            f"{origin}: {key}: given as a fixed setting and in [{table}]; keep one"
        )
    _check_size(origin, grid, sample, len(seeds))
    base, params_file = _base(data.get("params_file"), origin, root)
    study = Study(name, tuple(seeds), fixed, grid, sample, base, params_file)
    for key in {*fixed, *study.varied}:
        _check_key(key, origin, "grid" if key in grid else "setting")
    _validate_cells(study, origin)
    return study


def _check_finite(node: Any, origin: str, where: str = "") -> None:
    """No NaN or infinity anywhere in a study (no setting means either)."""
    if isinstance(node, float) and not math.isfinite(node):
        raise ParameterError(f"{origin}: {where}: expected a finite number, got {node}")
    if isinstance(node, dict):
        for key, value in node.items():
            _check_finite(value, origin, f"{where}.{key}" if where else str(key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            _check_finite(value, origin, f"{where}[{i}]")


def _flatten(table: dict[str, Any], prefix: str) -> dict[str, Any]:
    """``params`` nests sections (``[params.geometry]``); the other tables are flat."""
    if prefix != "params":
        return table
    out: dict[str, Any] = {}
    for key, value in table.items():
        if isinstance(value, dict):
            out |= {f"{key}.{k}": v for k, v in _flatten(value, prefix).items()}
        else:
            out[key] = value
    return out


def _seeds(value: Any, origin: str) -> Sequence[int]:
    """The seeds a study file gives (a count or a list), not yet expanded: a ``range``."""
    if isinstance(value, int) and not isinstance(value, bool) and value >= 1:
        return range(value)
    if (
        isinstance(value, list)
        and value
        and all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in value)
        and len(set(value)) == len(value)
    ):
        return value
    raise ParameterError(
        f"{origin}: seeds: expected a count >= 1 or a list of distinct seeds >= 0, got {value!r}"
    )


def _check_size(
    origin: str, grid: dict[str, list[Any]], sample: dict[str, Any], seeds: int
) -> None:
    """At most :data:`MAX_SESSIONS` sessions, counted before anything is expanded."""
    sizes = [len(values) for values in grid.values()] or [sample.get("n", 1)]
    total = math.prod(sizes) * seeds
    if total <= MAX_SESSIONS:
        return
    table = "grid" if grid else "sample" if sample else "seeds"
    points = " × ".join(map(str, sizes))
    plural = "" if sizes == [1] else "s"
    raise ParameterError(
        f"{origin}: {table}: {total} sessions ({points} point{plural} × {seeds} seeds); at most "
        f"{MAX_SESSIONS} sessions in one study: split it into several studies"
    )


def _check_key(key: str, origin: str, where: str) -> None:
    prefix = key.split(".", 1)[0]
    if "." not in key or prefix not in PREFIXES:
        raise ParameterError(
            f"{origin}: {where} key {key!r}: expected twin.KEY, params.SECTION.KEY or analysis.KEY"
        )


_DISTRIBUTIONS = ("uniform", "loguniform", "integers", "choice")


def _check_nested(table: str, key: str, value: Any, origin: str) -> None:
    """A table where ``[grid]`` or ``[sample]`` expects a setting is TOML's reading of an unquoted
    dotted key (``params.geometry.x = [...]`` is ``{"params": {"geometry": {"x": [...]}}}``), or
    of a ``[grid.twin]`` table: the message names the key to quote."""
    if "." in key or not isinstance(value, dict):
        return
    parts = [key]
    while isinstance(value, dict) and value and not (table == "sample" and _is_draw(value)):
        name, value = next(iter(value.items()))
        parts.append(name)
    example = "[...]" if table == "grid" else "{...}"
    raise ParameterError(
        f"{origin}: [{table}] {key}: a table, where a setting was expected: TOML reads an "
        f'unquoted dotted key as nested tables; quote the key: "{".".join(parts)}" = {example}'
    )


def _is_draw(spec: Any) -> bool:
    """Whether ``spec`` names one distribution of :data:`_DISTRIBUTIONS` (its arguments aside)."""
    return isinstance(spec, dict) and len(spec) == 1 and next(iter(spec)) in _DISTRIBUTIONS


def _check_sample(sample: dict[str, Any], origin: str) -> None:
    n, seed = sample.get("n"), sample.get("seed")
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise ParameterError(f"{origin}: sample.n: expected a number of points >= 1, got {n!r}")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ParameterError(f"{origin}: sample.seed: expected an integer >= 0, got {seed!r}")
    if not sample.keys() - {"n", "seed"}:
        raise ParameterError(
            f"{origin}: [sample]: no key to draw; give at least one KEY = {{uniform = [lo, hi]}}, "
            "{loguniform = [lo, hi]}, {integers = [lo, hi]} or {choice = [...]}"
        )
    for key, spec in sample.items():
        if key in ("n", "seed"):
            continue
        _check_nested("sample", key, spec, origin)
        _check_key(key, origin, "sample")
        ok = _is_draw(spec)
        kind, args = next(iter(spec.items())) if ok else (None, None)
        if ok and kind != "choice":
            number = int if kind == "integers" else int | float
            ok = (
                isinstance(args, list)
                and len(args) == 2
                and all(isinstance(a, number) and not isinstance(a, bool) for a in args)
                and args[0] <= args[1]
                and (kind != "loguniform" or args[0] > 0)
            )
        elif ok:
            ok = isinstance(args, list) and bool(args)
        if not ok:
            raise ParameterError(
                f"{origin}: sample.{key}: expected one of {{uniform = [lo, hi]}}, "
                f"{{loguniform = [lo, hi]}} (lo > 0), {{integers = [lo, hi]}} (whole numbers) "
                f"or {{choice = [...]}}, got {spec!r}"
            )


def _draw(rng: np.random.Generator, spec: dict[str, Any]) -> Any:
    kind, args = next(iter(spec.items()))
    if kind == "uniform":
        return float(rng.uniform(*args))
    if kind == "loguniform":
        return float(np.exp(rng.uniform(np.log(args[0]), np.log(args[1]))))
    if kind == "integers":
        return int(rng.integers(args[0], args[1] + 1))
    value = args[int(rng.integers(len(args)))]
    return value


def _base(
    path: Any, origin: str, root: Path | None
) -> tuple[dict[str, Any] | None, dict[str, str] | None]:
    """The parameter set of ``params_file`` (relative to ``root``) and where it was read (its
    absolute path and SHA-256); ``(None, None)`` without one."""
    if path is None:
        return None, None
    if not isinstance(path, str):
        raise ParameterError(f"{origin}: params_file: expected a path, got {path!r}")
    from anklelab._runs import sha256_file
    from anklelab.platforms import load_platform

    full = (root or Path.cwd()) / path
    try:
        base = load_platform("perturberator", full).model_dump()
    except AnklelabError as exc:
        raise ParameterError(f"{origin}: params_file = {path!r}: {exc}") from None
    return base, {"path": str(full.resolve()), "sha256": sha256_file(full)}


def _validate_cells(study: Study, origin: str) -> None:
    """Build every distinct point's twin settings, parameters and analysis settings once."""
    from anklelab.pipelines.walking import WalkingSettings
    from anklelab.platforms import load_platform
    from anklelab.platforms.perturberator import PerturberatorParameters

    base = (
        load_platform("perturberator")
        if study.base is None
        else PerturberatorParameters.model_validate(study.base)
    )

    def check(settings: dict[str, dict[str, Any]], where: str) -> None:
        checks = (
            ("twin", TwinSettings().replace),
            ("params", base.replace),
            ("analysis", WalkingSettings().replace),
        )
        built: dict[str, Any] = {}
        for prefix, replace in checks:
            try:
                built[prefix] = replace(settings[prefix])
            except ParameterError as exc:
                reason = " ".join(str(exc).replace("replace(): invalid parameters:", "").split())
                raise ParameterError(f"{origin}: {where}: [{prefix}] {reason}") from None
        params = built["params"]
        if built["twin"].randomised != "none" and "gait.stance_s" not in settings["params"]:
            from anklelab.experiments.randomised import STANCE_RANGE_S

            # each session draws its stance: checked against the shortest it can draw
            shortest = params.gait.model_copy(update={"stance_s": STANCE_RANGE_S[0]})
            params = params.model_copy(update={"gait": shortest})
        if problem := _analysis_misfit(params, built["analysis"]):
            raise ParameterError(f"{origin}: {where}: [analysis] {problem}")

    check(_by_prefix(study.fixed), "fixed settings")  # alone first: its mistakes are not the grid's
    for cell in study.cells()[:: len(study.seeds)]:
        point = ", ".join(f"{k} = {v!r}" for k, v in cell.variables.items())
        check(
            {"twin": cell.twin, "params": cell.params, "analysis": cell.analysis},
            point or "fixed settings",
        )


def _by_prefix(settings: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Settings by full dotted key (``"twin.trials_per_point"``) as one table per prefix of
    :data:`PREFIXES`, keyed without it."""
    split: dict[str, dict[str, Any]] = {prefix: {} for prefix in PREFIXES}
    for dotted, value in settings.items():
        prefix, key = dotted.split(".", 1)
        split[prefix][key] = value
    return split


def _analysis_misfit(params: Any, analysis: Any) -> str:
    """What keeps ``analysis`` (WalkingSettings) from analysing the twin's sessions of
    ``params``, found before a session is simulated (empty when nothing does)."""
    nyquist = params.daq.sample_rate_hz / 2
    if analysis.cutoff_hz >= nyquist:
        return (
            f"cutoff_hz = {analysis.cutoff_hz:g}: expected below the twin's Nyquist frequency, "
            f"{nyquist:g} Hz"
        )
    last = max(params.walking.timing_points_ms)
    window = max(analysis.windows_ms())
    if last + window > 1000.0 * params.gait.stance_s:
        return (
            f"window_ms: the {window:g} ms window of the last timing point ({last:g} ms) ends "
            f"after toe-off (gait.stance_s = {params.gait.stance_s:g} s)"
        )
    return ""


def _canonical_text(content: Any) -> str:
    """``content`` as JSON in one spelling per value: keys sorted, tuples as lists, a whole
    float as the integer it equals (``100.0`` as ``100``: the same value of a number setting,
    and an integer setting refuses ``100.0`` before any cell runs).

    >>> _canonical_text({"b": (1.0, 2.5), "a": 100})
    '{"a": 100, "b": [1, 2.5]}'
    """
    return json.dumps(_canonical(content), sort_keys=True)


def _canonical(value: Any) -> Any:
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, list | tuple):
        return [_canonical(v) for v in value]
    if isinstance(value, dict):
        return {key: _canonical(v) for key, v in value.items()}
    return value
