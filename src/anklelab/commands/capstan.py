"""``anklelab capstan``: the capstan haptic ankle platform of paper 001 on its digital twin."""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

app = typer.Typer(
    help="Capstan haptic ankle platform (paper 001): gains, set-points, chirp, observer, "
    "haptic rendering on the twin.",
    no_args_is_help=True,
)

ParamsOption = Annotated[
    Path | None, typer.Option("--params", help="A capstan parameter file instead of the shipped.")
]
RateOption = Annotated[
    float, typer.Option("--fs", min=1000.0, max=10000.0, help="Control rate, Hz (1000-10000).")
]
UserOption = Annotated[bool, typer.Option(help="Put the user's foot on the platform.")]
GravityOption = Annotated[bool, typer.Option(help="Feed-forward gravity compensation.")]
FrictionCompOption = Annotated[
    float, typer.Option("--friction-comp", help="Fraction of the model friction compensated.")
]
FrictionModelOption = Annotated[
    Path | None,
    typer.Option(
        "--friction-model",
        help="friction.json from `identify friction`: the controller's and observer's model.",
    ),
]
SettlingOption = Annotated[
    float, typer.Option("--settling-time", help="Design settling time of the PD loop, s.")
]
OutOption = Annotated[
    Path | None, typer.Option("--out", "-o", help="Directory for results JSON and figures.")
]
SeedOption = Annotated[int, typer.Option(help="Random seed.")]


def _setup(
    params: Path | None,
    fs: float,
    user: bool,
    gravity: bool,
    friction_comp: float,
    friction_model: Path | None,
    settling_time: float,
    **extra: Any,
) -> Any:
    from anklelab.control.pid import design_critically_damped
    from anklelab.experiments.capstan import CapstanSetup
    from anklelab.ident.friction import read_friction_json
    from anklelab.platforms import load_platform

    platform = load_platform("capstan", params)
    model = None
    if friction_model is not None:
        model = read_friction_json(
            friction_model, stribeck_exponent=platform.friction.stribeck_exponent
        )
    return CapstanSetup(
        params=platform,
        gains=design_critically_damped(platform, settling_time_s=settling_time),
        fs=fs,
        with_user=user,
        gravity_compensation=gravity,
        friction_compensation=friction_comp,
        model_friction=model,
        **extra,
    )


def _write_json(out: Path | None, name: str, content: Any) -> None:
    if out is None:
        return
    from anklelab._atomic import write_text_atomic

    write_text_atomic(out / name, json.dumps(content, indent=2, default=float) + "\n")


def _table(title: str, columns: list[str], rows: list[list[str]]) -> None:
    table = Table(title=title)
    for k, column in enumerate(columns):
        table.add_column(column, justify="left" if k == 0 else "right")
    for row in rows:
        table.add_row(*row)
    Console().print(table)


def _hz(value: float, top: float) -> str:
    return f"{value:.2f} Hz" if math.isfinite(value) else f"> {top:g} Hz (not reached)"


def _at(metrics: Any, frequency: float, name: str) -> float:
    import numpy as np

    return float(np.interp(frequency, metrics.frequency_hz, getattr(metrics, name)))


@app.command("tune")
def tune(
    params: ParamsOption = None,
    settling_time: SettlingOption = 0.2,
    integral_fraction: Annotated[
        float, typer.Option(help="Ki as a fraction of J w0^3 (0 for PD).")
    ] = 0.2,
    user: Annotated[bool, typer.Option(help="Include the user's ankle in the design.")] = False,
    out: OutOption = None,
) -> None:
    """Design critically damped PID gains from the platform model (paper 001, section 3.2)."""
    import numpy as np

    from anklelab.control.pid import design_critically_damped
    from anklelab.platforms import load_platform
    from anklelab.sim.capstan import disturbance_to_angle, linear_platform, reference_to_angle

    platform = load_platform("capstan", params)
    gains = design_critically_damped(
        platform,
        settling_time_s=settling_time,
        integral_fraction=integral_fraction,
        with_user=user,
    )
    lin = linear_platform(platform, platform.user if user else None)
    args = (platform, gains.kp_nm_per_rad, gains.kd_nms_per_rad, gains.ki_nm_per_rad_s)
    tracking = reference_to_angle(*args, user=platform.user if user else None)
    compliance = disturbance_to_angle(*args, user=platform.user if user else None)
    freqs = np.logspace(-1, 2, 600)
    response = tracking.frequency_response(2 * np.pi * freqs)
    gain = np.abs(np.squeeze(response.complex))
    below = np.flatnonzero(gain < 10 ** (-3 / 20))
    bandwidth = float(freqs[below[0]]) if below.size else math.inf
    poles = np.sort_complex(tracking.poles())
    compliance_1hz = float(np.abs(np.squeeze(compliance.frequency_response(2 * np.pi).complex)))
    _table(
        "critically damped platform-angle PID",
        ["quantity", "value"],
        [
            ["platform inertia J (kg·m²)", f"{lin.inertia_kgm2:.4f}"],
            ["platform damping b (N·m·s/rad)", f"{lin.damping_nms_per_rad:.3f}"],
            ["Kp (N·m/rad)", f"{gains.kp_nm_per_rad:.2f}"],
            ["Kd (N·m·s/rad)", f"{gains.kd_nms_per_rad:.3f}"],
            ["Ki (N·m/(rad·s))", f"{gains.ki_nm_per_rad_s:.2f}"],
            ["integral error limit (deg)", f"{math.degrees(gains.integral_error_limit_rad):.2f}"],
            ["closed-loop poles (1/s)", ", ".join(f"{p:.1f}" for p in poles)],
            ["eq. 8 -3 dB bandwidth (Hz)", f"{bandwidth:.2f}"],
            ["eq. 9 compliance at 1 Hz (deg/N·m)", f"{math.degrees(compliance_1hz):.4f}"],
        ],
    )
    _write_json(out, "gains.json", gains.model_dump())


@app.command("step")
def step(
    degrees: Annotated[str, typer.Option(help="Set-points, degrees, comma-separated.")] = "5,10,15",
    hold: Annotated[float, typer.Option(help="Hold time after each step, s.")] = 1.5,
    params: ParamsOption = None,
    fs: RateOption = 1000.0,
    user: UserOption = True,
    gravity: GravityOption = True,
    friction_comp: FrictionCompOption = 0.0,
    friction_model: FrictionModelOption = None,
    settling_time: SettlingOption = 0.2,
    seed: SeedOption = 0,
    out: OutOption = None,
) -> None:
    """Set-point steps (paper 001: 5, 10, 15 deg reached within 300 ms)."""
    from anklelab.experiments.capstan import step_response

    setup = _setup(params, fs, user, gravity, friction_comp, friction_model, settling_time)
    runs = [
        step_response(setup, math.radians(float(d)), hold_s=hold, seed=seed)
        for d in degrees.split(",")
    ]
    _table(
        f"set-point steps at {fs:g} Hz (gravity comp. {gravity}, friction comp. {friction_comp})",
        ["set-point", "rise 10-90 %", "settle 5 %", "settle 2 %", "overshoot", "ss error", "fault"],
        [
            [
                f"{math.degrees(m.amplitude_rad):g} deg",
                f"{m.rise_time_s * 1e3:.0f} ms",
                f"{m.settling_time_5_s * 1e3:.0f} ms",
                f"{m.settling_time_s * 1e3:.0f} ms",
                f"{m.overshoot_percent:.1f} %",
                f"{math.degrees(m.steady_state_error_rad):+.3f} deg",
                str(int(r["fault"].max())),
            ]
            for r, m in runs
        ],
    )
    _write_json(out, "steps.json", [asdict(m) for _, m in runs])
    if out is not None:
        from anklelab.report.figures_capstan import step_figure

        step_figure(runs, out / "steps.png")


@app.command("chirp")
def chirp(
    amplitude: Annotated[float, typer.Option(help="Amplitude, degrees.")] = 5.0,
    f0: Annotated[float, typer.Option(help="Start frequency, Hz.")] = 0.2,
    f1: Annotated[float, typer.Option(help="End frequency, Hz.")] = 5.0,
    duration: Annotated[float, typer.Option(help="Sweep duration, s.")] = 10.0,
    params: ParamsOption = None,
    fs: RateOption = 1000.0,
    user: UserOption = True,
    gravity: GravityOption = True,
    friction_comp: FrictionCompOption = 0.0,
    friction_model: FrictionModelOption = None,
    settling_time: SettlingOption = 0.2,
    seed: SeedOption = 0,
    out: OutOption = None,
) -> None:
    """Chirp tracking (paper 001: 5 deg, 0.2 to 5 Hz over 10 s, good up to about 3 Hz)."""
    from anklelab.experiments.capstan import chirp_tracking

    setup = _setup(params, fs, user, gravity, friction_comp, friction_model, settling_time)
    result, m = chirp_tracking(
        setup,
        amplitude_rad=math.radians(amplitude),
        f0_hz=f0,
        f1_hz=f1,
        duration_s=duration,
        seed=seed,
    )
    _table(
        f"chirp {amplitude:g} deg, {f0:g}-{f1:g} Hz over {duration:g} s at {fs:g} Hz",
        ["quantity", "value"],
        [
            ["rms tracking error", f"{math.degrees(m.rms_error_rad):.3f} deg"],
            ["rms error below 3 Hz", f"{math.degrees(m.rms_error_to_3hz_rad):.3f} deg"],
            ["max error", f"{math.degrees(m.max_error_rad):.3f} deg"],
            ["-3 dB bandwidth", _hz(m.bandwidth_3db_hz, f1)],
            ["45 deg lag bandwidth", _hz(m.bandwidth_45deg_hz, f1)],
            ["gain at 3 Hz", f"{_at(m, 3.0, 'gain'):.3f}"],
            ["phase at 3 Hz", f"{_at(m, 3.0, 'phase_deg'):.1f} deg"],
            ["safety fault", str(int(result["fault"].max()))],
        ],
    )
    _write_json(
        out,
        "chirp.json",
        {k: v.tolist() if hasattr(v, "tolist") else v for k, v in asdict(m).items()},
    )
    if out is not None:
        from anklelab.report.figures_capstan import chirp_tracking_figure

        chirp_tracking_figure(result, m, out / "chirp.png")


@app.command("observe")
def observe(
    task: Annotated[
        str, typer.Option(help="hold (level set-point) or track (slow multisine).")
    ] = "hold",
    cutoff: Annotated[float, typer.Option(help="Q-filter cut-off, Hz.")] = 20.0,
    torque_rms: Annotated[float, typer.Option(help="Voluntary torque RMS, N·m.")] = 3.0,
    band: Annotated[float, typer.Option(help="Voluntary torque up to this frequency, Hz.")] = 3.0,
    duration: Annotated[float, typer.Option(help="Trial length, s.")] = 20.0,
    params: ParamsOption = None,
    fs: RateOption = 1000.0,
    friction_model: FrictionModelOption = None,
    seed: SeedOption = 0,
    out: OutOption = None,
) -> None:
    """Estimate the user's ankle torque from current and encoder (disturbance observer)."""
    from anklelab.experiments.capstan import observer_trial

    setup = _setup(params, fs, True, True, 0.0, friction_model, 0.2, observer_cutoff_hz=cutoff)
    result, m = observer_trial(
        setup, task, duration_s=duration, torque_rms_nm=torque_rms, band_hz=(0.1, band), seed=seed
    )
    _table(
        f"disturbance observer ({task}, Q cut-off {cutoff:g} Hz, {fs:g} Hz)",
        ["quantity", "value"],
        [
            ["VAF", f"{m.vaf_percent:.1f} %"],
            ["delay", f"{m.delay_s * 1e3:.0f} ms"],
            ["VAF, delay removed", f"{m.vaf_delay_compensated_percent:.1f} %"],
            ["rms error", f"{m.rms_error_nm:.3f} N·m"],
        ],
    )
    _write_json(out, f"observer_{task}.json", asdict(m))
    if out is not None:
        from anklelab.report.figures_capstan import observer_figure

        observer_figure(result, out / f"observer_{task}.png", title=f"observer while {task}ing")


@app.command("render")
def render(
    stiffness: Annotated[float, typer.Option(help="Virtual stiffness, N·m/rad.")] = 50.0,
    damping: Annotated[float, typer.Option(help="Virtual damping, N·m·s/rad.")] = 5.0,
    inertia: Annotated[float, typer.Option(help="Virtual inertia (admittance), kg·m².")] = 0.2,
    mode: Annotated[
        str, typer.Option(help="admittance (observer-based) or impedance.")
    ] = "admittance",
    terrain: Annotated[
        str | None,
        typer.Option(help="'hills' or a CSV file (distance_m, height_m): follow its slope."),
    ] = None,
    speed: Annotated[float, typer.Option(help="Walking speed over the terrain, m/s.")] = 1.0,
    torque_rms: Annotated[float, typer.Option(help="User's voluntary torque RMS, N·m.")] = 2.0,
    duration: Annotated[float, typer.Option(help="Trial length, s.")] = 30.0,
    params: ParamsOption = None,
    fs: RateOption = 1000.0,
    friction_model: FrictionModelOption = None,
    seed: SeedOption = 0,
    out: OutOption = None,
) -> None:
    """Render a virtual spring-damper, or a terrain's slope, to the user's foot."""
    import numpy as np

    from anklelab.control.haptics import TerrainProfile, VirtualEnvironment
    from anklelab.experiments.capstan import render as run_render

    if mode not in ("admittance", "impedance"):
        raise typer.BadParameter(
            f"got {mode!r}; expected admittance or impedance", param_hint="--mode"
        )
    setup = _setup(params, fs, True, True, 0.0, friction_model, 0.2)
    profile = None
    if terrain == "hills":
        profile = TerrainProfile.hills(speed * duration + 1.0, seed=seed)
    elif terrain is not None:
        table = np.loadtxt(terrain, delimiter=",", skiprows=1, ndmin=2)
        profile = TerrainProfile(table[:, 0], table[:, 1])
    env = VirtualEnvironment(
        stiffness_nm_per_rad=stiffness, damping_nms_per_rad=damping, inertia_kgm2=inertia
    )
    result, m = run_render(
        setup,
        env,
        mode=mode,  # type: ignore[arg-type]
        terrain=profile,
        walking_speed_m_s=speed,
        duration_s=duration,
        torque_rms_nm=torque_rms,
        seed=seed,
    )
    _table(
        f"{mode} rendering of K = {stiffness:g} N·m/rad, B = {damping:g} N·m·s/rad"
        + (f" over {terrain} terrain" if terrain else ""),
        ["felt by the foot", "value"],
        [
            [
                "stiffness",
                f"{m.stiffness_nm_per_rad:.1f} N·m/rad ({m.stiffness_error_percent:+.1f} %)",
            ],
            [
                "damping",
                f"{m.damping_nms_per_rad:.2f} N·m·s/rad ({m.damping_error_percent:+.1f} %)",
            ],
            ["inertia", f"{m.inertia_kgm2:.3f} kg·m²"],
            [
                "rms deviation from equilibrium",
                f"{math.degrees(m.equilibrium_rms_error_rad):.2f} deg",
            ],
            ["safety fault", str(int(result["fault"].max()))],
        ],
    )
    _write_json(out, "render.json", asdict(m))
    if out is not None:
        from anklelab.report.figures_capstan import render_figure

        eq = (
            np.zeros(result.n_samples)
            if profile is None
            else profile.equilibrium(duration, fs, speed)
        )
        render_figure(result, eq, out / "render.png", title=f"{mode} rendering")
