"""``anklelab capstan render / scene / zwidth / teleop``: haptic rendering, terrain and VR
scenes, the Z-width and teleoperation on the capstan twin (registered by
:mod:`anklelab.commands.capstan`)."""

from __future__ import annotations

import math
from dataclasses import asdict
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from anklelab.commands._capstan_options import (
    SetupOptions,
    checked,
    explain_faults,
    fail_on_fault,
    fault_text,
    numbers,
    table,
    with_setup_options,
)
from anklelab.errors import ParameterError


class RenderMode(StrEnum):
    """How the virtual environment is rendered."""

    admittance = "admittance"
    impedance = "impedance"


class Scheme(StrEnum):
    """How teleoperation crosses the network."""

    wave = "wave"
    direct = "direct"


def _percent(value: float) -> str:
    return f"{value:+.1f} %" if math.isfinite(value) else "(nothing to compare)"


def _terrain(spec: str | None, length_m: float, seed: int) -> Any:
    """``hills``, or a CSV file ``distance_m,height_m`` read as a terrain profile."""
    import csv

    import numpy as np

    from anklelab.control.haptics import TerrainProfile

    if spec is None:
        return None
    if spec == "hills":
        return TerrainProfile.hills(length_m, seed=seed)
    from anklelab.commands._files import check_input

    path = check_input(Path(spec), what="a terrain file (CSV: distance_m,height_m)", kinds=["file"])
    try:
        with path.open(encoding="utf-8", newline="") as handle:
            rows = list(csv.reader(handle))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ParameterError(f"{path}: not a readable CSV file: {exc}") from None
    if not rows or [c.strip() for c in rows[0]] != ["distance_m", "height_m"]:
        raise ParameterError(f"{path}: the first line must be 'distance_m,height_m'")
    values = []
    for line, row in enumerate(rows[1:], start=2):
        try:
            pair = [float(cell) for cell in row]
        except ValueError:
            pair = []
        if len(pair) != 2 or not all(math.isfinite(v) for v in pair):
            raise ParameterError(
                f"{path}: line {line}: expected two finite numbers; got {row!r:.60}"
            )
        values.append(pair)
    if len(values) < 2:
        raise ParameterError(f"{path}: needs at least two rows of distance_m,height_m")
    table_ = np.array(values)
    return TerrainProfile(table_[:, 0], table_[:, 1])


@with_setup_options()
def render(
    stiffness: Annotated[
        float,
        checked(
            "Virtual stiffness, N·m/rad (inf: rigid, admittance only).", low=0.0, infinite=True
        ),
    ] = 50.0,
    damping: Annotated[
        float,
        checked("Virtual damping, N·m·s/rad.", low=0.0, high=1000.0),
    ] = 5.0,
    inertia: Annotated[
        float,
        checked("Virtual inertia (admittance), kg·m².", low=0.0, high=10.0, strict=True),
    ] = 0.2,
    mode: Annotated[
        RenderMode, typer.Option(help="admittance (observer-based) or impedance.")
    ] = RenderMode.admittance,
    passivity_control: Annotated[
        bool,
        typer.Option(
            "--passivity-control/--no-passivity-control",
            metavar="",
            help="Impedance: dissipate what the passivity observer finds the rendering produced.",
        ),
    ] = False,
    terrain: Annotated[
        str | None,
        typer.Option(
            metavar="hills|FILE",
            help="'hills' or a CSV file (distance_m,height_m): follow its slope.",
            show_default=False,
        ),
    ] = None,
    speed: Annotated[
        float,
        checked("Walking speed over the terrain, m/s.", low=0.0, high=3.0, strict=True),
    ] = 1.0,
    torque_rms: Annotated[
        float,
        checked("User's voluntary torque RMS, N·m.", low=0.0, high=20.0, strict=True),
    ] = 2.0,
    duration: Annotated[
        float,
        checked("Trial length, s (at least 6).", low=6.0, high=600.0),
    ] = 30.0,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """Render a virtual spring-damper, or a terrain's slope, to the user's foot."""
    import numpy as np

    from anklelab.control.haptics import VirtualEnvironment
    from anklelab.experiments.capstan import render as run_render

    if mode is RenderMode.impedance and not math.isfinite(stiffness):
        raise ParameterError("--stiffness: impedance rendering needs a finite stiffness")
    settings = {
        "stiffness_nm_per_rad": stiffness,
        "damping_nms_per_rad": damping,
        "inertia_kgm2": inertia,
        "mode": mode,
        "passivity_control": passivity_control,
        "terrain": terrain,
        "speed_m_s": speed,
        "torque_rms_nm": torque_rms,
        "duration_s": duration,
    }
    terrain_file = [] if terrain in (None, "hills") else [Path(terrain)]
    with options.output("render", settings, terrain_file) as written:
        profile = _terrain(terrain, speed * duration + 1.0, options.seed)
        setup = options.setup(
            feedforward=True, lag_compensation=True, passivity_control=passivity_control
        )
        env = VirtualEnvironment(
            stiffness_nm_per_rad=stiffness, damping_nms_per_rad=damping, inertia_kgm2=inertia
        )
        result, m = run_render(
            setup,
            env,
            mode=mode.value,  # type: ignore[arg-type]
            terrain=profile,
            walking_speed_m_s=speed,
            duration_s=duration,
            torque_rms_nm=torque_rms,
            seed=options.seed,
        )
        code = int(result["fault"].max())
        rigid = not math.isfinite(stiffness)
        felt = [
            [
                "stiffness",
                f"{m.stiffness_nm_per_rad:.1f} N·m/rad "
                + (
                    "(rigid ground: the loop's and the cable's)"
                    if rigid
                    else f"({_percent(m.stiffness_error_percent)})"
                ),
            ]
        ]
        if not rigid:  # on rigid ground the foot barely moves: no damping or inertia to fit
            felt += [
                [
                    "damping",
                    f"{m.damping_nms_per_rad:.2f} N·m·s/rad ({_percent(m.damping_error_percent)})",
                ],
                ["inertia", f"{m.inertia_kgm2:.3f} kg·m²"],
            ]
        table(
            f"{mode.value} rendering of K = {'rigid' if rigid else f'{stiffness:g} N·m/rad'}, "
            f"B = {damping:g} N·m·s/rad" + (f" over {terrain} terrain" if terrain else ""),
            ["felt by the foot", "value"],
            [
                *felt,
                [
                    "rms deviation from equilibrium",
                    f"{math.degrees(m.equilibrium_rms_error_rad):.2f} deg",
                ],
                ["safety fault", fault_text(code)],
            ],
        )
        written.json("render.json", asdict(m))
        if (figure := written.path("render.png")) is not None:
            from anklelab.report.figures_capstan import render_figure

            eq = (
                np.zeros(result.n_samples)
                if profile is None
                else profile.equilibrium(duration, options.sample_rate, speed)
            )
            render_figure(result, eq, figure, title=f"{mode.value} rendering")
    fail_on_fault("render", code, "the rendering")


@with_setup_options(exclude=("person",))
def scene(
    scene_file: Annotated[
        Path,
        typer.Argument(metavar="SCENE", help="Scene file (TOML): terrain, speed, patches, person."),
    ],
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """Walk a terrain scene on the platform: slope by position control, bumps within the
    display envelope, compliant patches by admittance; the error by component."""
    from anklelab.control.scene import load_scene
    from anklelab.experiments.capstan.scene import SPLIT_HZ, render_scene

    with options.output("scene", {}, [scene_file]) as written:
        walk = load_scene(scene_file)
        setup = options.setup(feedforward=True, lag_compensation=True)
        result, m, profile = render_scene(walk, setup, seed=options.seed)
        deg = math.degrees
        rows = [
            [
                "slope",
                f"{deg(m.slope_rms_rad):.2f} deg rms",
                f"{deg(m.slope_rms_error_rad):.3f} deg rms",
            ],
            [
                "bumps",
                f"{deg(m.bumps_rms_rad):.3f} deg rms",
                f"{deg(m.bumps_rms_error_rad):.3f} deg rms",
            ],
        ]
        for k, p in enumerate(m.patches):
            k_error, b_error = (
                _percent(p.stiffness_error_percent),
                _percent(p.damping_error_percent),
            )
            rows += [
                [
                    f"patch {k + 1}: stiffness",
                    f"{p.stiffness_nm_per_rad:g} N·m/rad",
                    f"{p.felt_stiffness_nm_per_rad:.1f} N·m/rad ({k_error})",
                ],
                [
                    f"patch {k + 1}: damping",
                    f"{p.damping_nms_per_rad:g} N·m·s/rad",
                    f"{p.felt_damping_nms_per_rad:.2f} N·m·s/rad ({b_error})",
                ],
            ]
        table(
            f"scene {walk.name!r}: {walk.path_length_m:g} m at {walk.walking_speed_m_s:g} m/s, "
            f"{walk.person} person; slope below and bumps above {SPLIT_HZ:g} Hz",
            ["component", "rendered / commanded", "error / felt"],
            rows,
        )
        scaled = {band: s for band, s in m.bump_scales.items() if s < 1.0}
        if scaled:
            typer.echo(
                "bumps scaled to stay within the display envelope: "
                + ", ".join(f"{band} x{s:.2f}" for band, s in scaled.items())
            )
        typer.echo(f"safety fault: {fault_text(m.fault)}")
        written.json("scene.json", asdict(m))
        if (figure := written.path("scene.png")) is not None:
            from anklelab.report.figures_capstan import scene_figure

            scene_figure(result, profile, figure, title=walk.name)
    fail_on_fault("scene", m.fault, "the walk")


@with_setup_options()
def zwidth(
    damping: Annotated[
        str,
        typer.Option(metavar="B,...", help="Virtual damping values, N·m·s/rad, comma-separated."),
    ] = "0,0.5,1,2,5",
    iterations: Annotated[
        int, typer.Option(help="Bisection steps per boundary.", min=1, max=20)
    ] = 10,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """The Z-width: which virtual stiffness and damping impedance rendering keeps passive,
    analytic and measured on the twin with a human-like ankle, and the passivity controller
    twice outside the boundary."""
    import dataclasses

    from anklelab.experiments.capstan.zwidth import measure_zwidth, passivity_cost, push_trial

    values = numbers(damping, "--damping", low=0.0, high=100.0)
    with options.output(
        "zwidth", {"damping_nms_per_rad": values, "iterations": iterations}
    ) as written:
        setup = options.setup()
        z = measure_zwidth(setup, values, iterations=iterations, seed=options.seed)
        a = z.analytic
        stomp, nudge = z.error_percent("stomp", "viscous"), z.error_percent("nudge", "quantization")
        rows = [
            [
                f"{b:g}",
                f"{a.viscous_nm_per_rad[k]:.0f}",
                f"{z.measured_nm_per_rad['stomp'][k]:.0f} ({_percent(stomp[k])})",
                f"{a.quantization_nm_per_rad:.0f}",
                f"{z.measured_nm_per_rad['nudge'][k]:.0f} ({_percent(nudge[k])})",
            ]
            for k, b in enumerate(values)
        ]
        table(
            f"Z-width at {options.sample_rate:g} Hz, person {options.person.value} "
            f"(largest stiffness, N·m/rad)",
            [
                "damping (N·m·s/rad)",
                "viscous mode",
                "stomp (twin)",
                "quantisation mode",
                "nudge (twin)",
            ],
            rows,
        )
        controlled = dataclasses.replace(setup, passivity_control=True)
        outside = []
        for push, stiffness, b in (
            ("stomp", 2 * a.viscous_nm_per_rad[0], values[0]),
            ("nudge", 2 * a.quantization_nm_per_rad, values[0]),
        ):
            if stiffness > 0:
                plain = push_trial(setup, stiffness, b, push, seed=options.seed)
                with_pc = push_trial(controlled, stiffness, b, push, seed=options.seed)
                outside.append(
                    {
                        "push": push,
                        "stiffness_nm_per_rad": stiffness,
                        "damping_nms_per_rad": b,
                        "stable_without_control": plain,
                        "stable_with_control": with_pc,
                    }
                )
                typer.echo(
                    f"twice outside ({push}, K = {stiffness:.0f} N·m/rad, B = {b:g}): "
                    f"{'stable' if plain else 'unstable'} without, "
                    f"{'stable' if with_pc else 'unstable'} with the passivity controller"
                )
        cost = passivity_cost(setup, [(2 * a.viscous_nm_per_rad[0], values[0])], seed=options.seed)
        for c in cost:
            felt, controlled_felt = c.without, c.with_control
            typer.echo(
                f"fidelity cost at K = {c.stiffness_nm_per_rad:.0f}: felt stiffness "
                f"{felt.stiffness_nm_per_rad:.0f} -> {controlled_felt.stiffness_nm_per_rad:.0f} "
                f"N·m/rad, felt damping {felt.damping_nms_per_rad:.2f} -> "
                f"{controlled_felt.damping_nms_per_rad:.2f} N·m·s/rad, "
                f"{c.dissipated_j * 1e3:.2f} mJ dissipated"
            )
        results = {
            "damping_nms_per_rad": values,
            "analytic": {
                "viscous_nm_per_rad": a.viscous_nm_per_rad,
                "quantization_nm_per_rad": a.quantization_nm_per_rad,
                "damper_leak": a.leak,
                "platform_damping_nms_per_rad": a.platform_damping_nms_per_rad,
                "ankle_damping_nms_per_rad": a.ankle_damping_nms_per_rad,
            },
            "measured_nm_per_rad": z.measured_nm_per_rad,
            "twice_outside": outside,
            "fidelity_cost": [asdict(c) for c in cost],
        }
        written.json("zwidth.json", results)
        if (figure := written.path("zwidth.png")) is not None:
            from anklelab.report.figures_capstan import zwidth_figure

            zwidth_figure(z, figure)


@with_setup_options()
def teleop(
    delays: Annotated[
        str, typer.Option(metavar="MS,...", help="One-way network delays, ms, comma-separated.")
    ] = "0,50,100,200",
    jitter: Annotated[
        float,
        checked("Random extra delay per packet, up to this, ms.", low=0.0, high=1000.0),
    ] = 0.0,
    scheme: Annotated[
        Scheme,
        typer.Option(help="wave: wave variables (passive); direct: angle forward, torque back."),
    ] = Scheme.wave,
    duration: Annotated[float, checked("Trial length per delay, s.", low=4.0, high=600.0)] = 20.0,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """Teleoperate a remote robot's foot over a delayed network: tracking and stability
    against delay."""
    from anklelab.experiments.capstan.config import Channel
    from anklelab.experiments.capstan.teleop import teleoperate

    values = numbers(delays, "--delays", low=0.0, high=2000.0)
    settings = {"delays_ms": values, "jitter_ms": jitter, "scheme": scheme, "duration_s": duration}
    with options.output("teleop", settings) as written:
        setup = options.setup()
        runs = [
            teleoperate(
                setup,
                Channel(scheme.value, d / 1e3, jitter / 1e3),  # type: ignore[arg-type]
                duration_s=duration,
                seed=options.seed,
            )
            for d in values
        ]
        deg = math.degrees
        table(
            f"teleoperation, {scheme.value} scheme, jitter up to {jitter:g} ms",
            [
                "delay",
                "stable",
                "angle error",
                "lag removed",
                "torque error",
                "lag removed",
                "fault",
            ],
            [
                [
                    f"{d:g} ms",
                    "yes" if m.stable else "NO",
                    f"{deg(m.position_rms_error_rad):.2f} deg",
                    f"{deg(m.position_rms_error_lagged_rad):.2f} deg",
                    f"{m.force_rms_error_nm:.2f} N·m",
                    f"{m.force_rms_error_lagged_nm:.2f} N·m",
                    fault_text(m.fault),
                ]
                for d, (_, m) in zip(values, runs, strict=True)
            ],
        )
        explain_faults(m.fault for _, m in runs)
        results = [{"delay_ms": d, **asdict(m)} for d, (_, m) in zip(values, runs, strict=True)]
        written.json("teleop.json", results)
        if (figure := written.path("teleop.png")) is not None:
            from anklelab.report.figures_capstan import teleop_figure

            teleop_figure(runs, values, figure, title=f"{scheme.value} scheme")
