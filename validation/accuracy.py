"""Accuracy of the walking analysis over many generated sessions, against their ground truth.

Each session comes from a generator (``twin``: anklelab's randomised twin; ``cleanroom``: the
independently written generator in :mod:`validation.cleanroom`) drawn with a seed; it is
analysed with default (or given) settings, whose window must be the truth's 100 ms (a
changing stiffness has another average over another window), and every timing point becomes
one row: the truth, the estimate with its interval and flags, and the errors. The summary
gives, per generator and kind, the distribution of the stiffness error (median, 95th
percentile, max), the inertia and damping errors, the lever-arm bias, interval coverage, and the
false-alarm and miss rates of the "stiffness changes within the window" diagnostic.

Run::

    python -m validation.accuracy --generator twin --kind random --sessions 200 --out rows.csv
    python -m validation.accuracy --summarise rows.csv [more.csv ...]

Sessions can be cached as HDF5 (``--cache DIR``) so that a change to the analysis is re-scored
without simulating again. The clean-room generator's protocol can be changed from the drawn one
(``--protocol sample_rate_hz=2000 "timing_points_ms=(150, 300, 450)"``, fields of
:class:`validation.cleanroom.config.ProtocolConfig`), to check the analysis on protocols other
than paper 000's.
"""

from __future__ import annotations

import argparse
import ast
import csv
import dataclasses
import hashlib
import math
import multiprocessing
import sys
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

QUANTITIES = {
    "stiffness": "stiffness_nm_per_rad",
    "damping": "damping_nms_per_rad",
    "inertia": "inertia_kgm2",
}
CHANGE_SMALL, CHANGE_LARGE = 0.15, 0.25  # the diagnostic's calibration bands (issue 9)


Protocol = tuple[tuple[str, Any], ...]
"""Clean-room protocol fields that replace the drawn ones, as ``(name, value)`` pairs."""


def generate(generator: str, kind: str, seed: int, protocol: Protocol = ()) -> Any:
    """One session with ground truth from ``generator`` (``twin`` or ``cleanroom``)."""
    if generator == "twin":
        from anklelab.experiments import simulate_randomised

        if protocol:
            raise ValueError("--protocol: only the cleanroom generator takes it")
        return simulate_randomised(seed, kind=kind, time_courses=False)
    if generator == "cleanroom":
        from validation.cleanroom import draw_config
        from validation.cleanroom import generate as cleanroom_generate

        changes = dict(protocol)
        rate = changes.pop("sample_rate_hz", 1000.0)  # the draw derives its filters from it
        config = draw_config(kind, seed, sample_rate_hz=rate)
        config = dataclasses.replace(
            config, protocol=dataclasses.replace(config.protocol, **changes)
        )
        return cleanroom_generate(config, seed)
    raise SystemExit(f"error: --generator: expected twin or cleanroom, got {generator!r}")


def parse_protocol(items: Sequence[str]) -> Protocol:
    """``NAME=VALUE`` items (values as Python literals) as :data:`Protocol` pairs, checked by
    the clean-room protocol's own validation (on its defaults) before anything is generated."""
    from validation.cleanroom.config import ProtocolConfig

    known = {field.name for field in dataclasses.fields(ProtocolConfig)}
    pairs = []
    for item in items:
        name, sep, text = (part.strip() for part in item.partition("="))
        try:
            value = ast.literal_eval(text) if sep else None
        except (ValueError, SyntaxError):
            sep = ""
        if not sep or name not in known:
            raise SystemExit(
                f"error: --protocol: expected NAME=VALUE, NAME a field of the clean-room "
                f"protocol ({', '.join(sorted(known))}) and VALUE a Python literal; got {item!r}"
            )
        pairs.append((name, value))
    try:
        dataclasses.replace(ProtocolConfig(), **dict(pairs))
    except (TypeError, ValueError) as exc:
        raise SystemExit(f"error: --protocol: {exc}") from None
    return tuple(pairs)


def load_or_generate(
    generator: str, kind: str, seed: int, cache: Path | None, protocol: Protocol = ()
) -> Any:
    """The session, from ``cache`` when it holds it (written there after generating)."""
    from anklelab.data import load_session, save_session

    tag = f"-{hashlib.sha256(repr(protocol).encode()).hexdigest()[:8]}" if protocol else ""
    path = cache / f"{generator}-{kind}-{seed}{tag}.h5" if cache else None
    if path is not None and path.exists():
        return load_session(path)
    session = generate(generator, kind, seed, protocol)
    if path is not None:
        save_session(session, path)
    return session


def session_rows(
    generator: str,
    kind: str,
    seed: int,
    settings_file: str | None,
    cache: Path | None,
    protocol: Protocol = (),
) -> list[dict[str, Any]]:
    """Analyse one session and compare every timing point with its truth."""
    from anklelab.pipelines import analyze_walking, load_walking_settings

    t0 = time.perf_counter()
    try:
        session = load_or_generate(generator, kind, seed, cache, protocol)
        t1 = time.perf_counter()
        results = analyze_walking(session, load_walking_settings(settings_file))
    except Exception as exc:  # a failed session is a row, never silently dropped
        return [{"generator": generator, "kind": kind, "seed": seed, "error": repr(exc)}]
    t2 = time.perf_counter()
    document = results.to_dict(session=f"{generator}-{kind}-{seed}")
    truth = session.truth or {}
    draw = _draw(truth)
    rows = []
    for tp in document["timing_points"]:
        reference = truth["reference"][tp["direction"]][f"{tp['delay_ms']:g}"]
        row: dict[str, Any] = {
            "generator": generator,
            "kind": kind,
            "seed": seed,
            **({"protocol": " ".join(f"{k}={v!r}" for k, v in protocol)} if protocol else {}),
            **draw,
            "direction": tp["direction"],
            "delay_ms": tp["delay_ms"],
            "n_perturbed": tp["n_perturbed"],
            "cop_true_m": reference["cop_m"],
            "cop_m": tp["cop_m"],
            "cop_error_mm": 1000 * (tp["cop_m"] - reference["cop_m"]),
            "change_true": reference.get("stiffness_change_fraction", math.nan),
            "model": tp.get("stiffness_model", document["settings"]["stiffness_model"]),
            "change_flagged": int(bool(tp.get("stiffness_changes", tp.get("warnings")))),
            **_change(tp),
            "adjustment_explained": tp.get("adjustment_explained", ""),
            "angle_gain": tp.get("angle_gain", ""),
            "angle_gain_pooled": tp.get("angle_gain_pooled", ""),
            "generate_s": t1 - t0,
            "analyse_s": t2 - t1,
        }
        for name, key in QUANTITIES.items():
            estimate, true = tp[key], reference[key]
            low, high = estimate.get("ci95") or (math.nan, math.nan)
            row |= {
                f"{name}_true": true,
                f"{name}": estimate["mean"],
                f"{name}_sd": estimate["sd"],
                f"{name}_low": low,
                f"{name}_high": high,
                f"{name}_error_pct": 100 * (estimate["mean"] / true - 1),
                f"{name}_covered": int(low <= true <= high) if math.isfinite(low) else "",
                f"{name}_flagged": int(bool(estimate.get("poorly_determined", False))),
            }
        rows.append(row)
    return rows


def _change(tp: dict[str, Any]) -> dict[str, Any]:
    """The estimated change of the stiffness over the window, with its interval."""
    change = tp.get("stiffness_change_fraction") or {}
    low, high = change.get("ci95") or ("", "")
    return {
        "change": change.get("mean", ""),
        "change_low": low,
        "change_high": high,
        "change_probability": tp.get("stiffness_change_probability", ""),
        "change_verdict": tp.get("stiffness_change_verdict") or "",
    }


def _draw(truth: dict[str, Any]) -> dict[str, Any]:
    """Descriptors of the drawn session (foot, noise, trials per point, growth, mounting)."""
    if "draw" in truth:  # the randomised twin
        draw = truth["draw"]
        axis = truth["parameters"]["force_plate"]["anterior_axis"]
        keep = ("foot", "noise_scale", "trials_per_point", "human_growth_per_150ms")
        return {key: draw[key] for key in keep} | {"anterior_axis": axis}
    config = truth.get("config", {})  # the clean-room generator
    foot = config.get("foot", {})
    return {
        "foot": "human" if foot.get("model") == "human" else "prosthetic",
        "noise_scale": config.get("noise", {}).get("scale", ""),
        "trials_per_point": config.get("protocol", {}).get("trials_per_point", ""),
        "human_growth_per_150ms": foot.get("rise_per_150ms", 0.0) or 0.0,
        "anterior_axis": config.get("plate", {}).get("anterior_axis", ""),
    }


def _task(args: tuple[str, str, int, str | None, Path | None, Protocol]) -> list[dict[str, Any]]:
    return session_rows(*args)


def run(
    generator: str,
    kind: str,
    seeds: Iterable[int],
    settings_file: str | None,
    cache: Path | None,
    workers: int,
    protocol: Protocol = (),
) -> list[dict[str, Any]]:
    """Rows of every session, computed on ``workers`` processes."""
    tasks = [(generator, kind, seed, settings_file, cache, protocol) for seed in seeds]
    if cache:
        cache.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    with multiprocessing.get_context("fork").Pool(workers) as pool:
        for i, result in enumerate(pool.imap(_task, tasks), 1):
            rows += result
            print(f"\r{i}/{len(tasks)} sessions", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    return rows


def write_rows(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    """Rows as CSV (columns: the union of every row's keys, in first-seen order)."""
    columns = list(dict.fromkeys(key for row in rows for key in row))
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, columns, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


def read_rows(paths: Sequence[Path]) -> list[dict[str, Any]]:
    """Rows of one or more CSV files written by :func:`write_rows`, numbers parsed."""
    rows = []
    for path in paths:
        with open(path, newline="") as f:
            rows += [{k: _number(v) for k, v in row.items()} for row in csv.DictReader(f)]
    return rows


def _number(text: str) -> Any:
    try:
        return float(text)
    except ValueError:
        return text


def summarise(rows: Sequence[dict[str, Any]]) -> str:
    """The distributions the issue asks for, per generator and kind, as text."""
    lines = []
    failed = [r for r in rows if r.get("error")]
    for r in failed:
        lines.append(f"FAILED {r['generator']} {r['kind']} seed {r['seed']:g}: {r['error']}")
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in rows:
        if not r.get("error"):
            groups.setdefault((r["generator"], r["kind"]), []).append(r)
    for (generator, kind), group in groups.items():
        sessions = len({r["seed"] for r in group})
        lines.append(f"\n== {generator} / {kind}: {sessions} sessions, {len(group)} points")
        lines += _distribution_lines(group)
    return "\n".join(lines)


def _distribution_lines(group: Sequence[dict[str, Any]]) -> list[str]:
    def column(name: str, subset: Sequence[dict[str, Any]] = group) -> np.ndarray:
        return np.array([float(r[name]) for r in subset if r.get(name, "") != ""], dtype=float)

    out = []
    noise = column("noise_scale")
    bands = [("all", group)]
    if noise.size == len(group):
        bands += [
            ("noise<1.5", [r for r in group if float(r["noise_scale"]) < 1.5]),
            ("noise>=2.5", [r for r in group if float(r["noise_scale"]) >= 2.5]),
        ]
    feet = sorted({str(r.get("foot", "")) for r in group} - {""})
    bands += [(f"foot={f}", [r for r in group if r.get("foot") == f]) for f in feet]
    for label, subset in bands:
        if not subset:
            continue
        for name in QUANTITIES:
            err = column(f"{name}_error_pct", subset)
            flagged = column(f"{name}_flagged", subset).astype(bool)
            shown = np.abs(err[~flagged]) if flagged.size == err.size else np.abs(err)
            covered = column(f"{name}_covered", subset)
            if covered.size == flagged.size and (~flagged).any():
                covered = covered[~flagged]  # the criterion: covered, or flagged
            cover = f"coverage {100 * covered.mean():5.1f} %" if covered.size else "no ci95"
            half = 50 * (column(f"{name}_high", subset) - column(f"{name}_low", subset))
            half /= np.abs(column(name, subset))
            out.append(
                f"  {label:11s} {name:9s} |err| median {np.median(shown):6.2f} p95 "
                f"{np.percentile(shown, 95):6.2f} max {shown.max():7.2f} %  bias "
                f"{np.mean(err):+6.2f} %  flagged {flagged.mean():5.1%}  {cover} of unflagged"
                f"  ci half-width median {np.nanmedian(half):5.1f} %"
                if shown.size
                else f"  {label:11s} {name:9s} all flagged"
            )
    cop = column("cop_error_mm")
    out.append(
        f"  lever arm error mm: mean {cop.mean():+.2f} median {np.median(cop):+.2f} "
        f"min {cop.min():+.2f} max {cop.max():+.2f}"
    )
    change, flagged = column("change_true"), column("change_flagged").astype(bool)
    small, large = np.abs(change) < CHANGE_SMALL, np.abs(change) >= CHANGE_LARGE
    if small.any():
        out.append(f"  diagnostic false alarms {flagged[small].mean():6.1%} of {small.sum()}")
    if large.any():
        out.append(f"  diagnostic misses       {(~flagged[large]).mean():6.1%} of {large.sum()}")
    verdicts = np.array([str(r.get("change_verdict", "")) for r in group])
    if (verdicts != "").any():
        for name, members in (("true change < 15 %", small), ("true change >= 25 %", large)):
            if not members.any():
                continue
            said = {
                v: (verdicts[members] == v).mean() for v in ("changes", "constant", "undetermined")
            }
            out.append(f"  verdicts, {name}: " + ", ".join(f"{v} {r:.1%}" for v, r in said.items()))
    return out


TRUTH_WINDOW_MS = 100.0
"""The window both generators' truth (stiffness, damping, lever arm) is averaged over, ms."""


def check_window(settings_file: str | None) -> None:
    """Refuse analysis settings whose window is not the truth's: a stiffness that changes within
    the window has another average over another window, and every error would be off by it."""
    from anklelab.pipelines.walking import load_walking_settings

    window = load_walking_settings(settings_file).window_ms
    if window != TRUTH_WINDOW_MS:
        raise SystemExit(
            f"error: --settings {settings_file}: window_ms = {window:g}; the generators' truth "
            f"is averaged over {TRUTH_WINDOW_MS:g} ms, so the errors would compare different "
            "things (a study, which takes the twin's truth over the analysed window, can)"
        )


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m validation.accuracy", description=__doc__)
    parser.add_argument("--generator", default="twin", choices=("twin", "cleanroom"))
    parser.add_argument("--kind", default="random")
    parser.add_argument("--sessions", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--settings", default=None, help="WalkingSettings TOML")
    parser.add_argument("--cache", type=Path, default=None, help="directory of cached sessions")
    parser.add_argument(
        "--protocol", nargs="*", default=[], help="clean-room protocol fields NAME=VALUE"
    )
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="CSV of the rows")
    parser.add_argument("--summarise", type=Path, nargs="*", help="summarise these row files")
    args = parser.parse_args(argv)
    if args.summarise:
        print(summarise(read_rows(args.summarise)))
        return
    seeds = range(args.first_seed, args.first_seed + args.sessions)
    protocol = parse_protocol(args.protocol)
    if protocol and args.generator != "cleanroom":
        raise SystemExit("error: --protocol: only the cleanroom generator takes it")
    check_window(args.settings)
    rows = run(args.generator, args.kind, seeds, args.settings, args.cache, args.workers, protocol)
    if args.out:
        write_rows(args.out, rows)
    print(summarise(rows))
    if any(row.get("error") for row in rows):
        raise SystemExit(1)  # the failed sessions are named in the summary


if __name__ == "__main__":
    main()
