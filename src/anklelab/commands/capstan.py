"""``anklelab capstan``: the capstan haptic ankle platform of paper 001 on its digital twin:
gains, set-points, chirp tracking, the display envelope, the torque observer (this module) and
haptic rendering, scenes, the Z-width and teleoperation (:mod:`.capstan_haptics`)."""

from __future__ import annotations

import math
from dataclasses import asdict
from enum import StrEnum
from typing import Annotated

import typer

from anklelab.commands import capstan_haptics
from anklelab.commands._capstan_options import (
    OutOption,
    ParamsOption,
    Person,
    SettlingOption,
    SetupOptions,
    checked,
    explain_faults,
    fail_on_fault,
    fault_text,
    numbers,
    table,
    with_setup_options,
)
from anklelab.commands._options import ForceOption

app = typer.Typer(
    help="Capstan haptic ankle platform (paper 001) on its twin: gains, set-points, chirp, "
    "display envelope, torque observer, haptic rendering, terrain scenes, Z-width, "
    "teleoperation.",
    no_args_is_help=True,
)


class Tracking(StrEnum):
    """How the platform follows a known trajectory."""

    pid = "pid"
    feedforward = "feedforward"
    zpetc = "zpetc"


class Task(StrEnum):
    """What the platform does while the observer estimates the user's torque."""

    hold = "hold"
    track = "track"


def _hz(value: float, top: float) -> str:
    return f"{value:.2f} Hz" if math.isfinite(value) else f"> {top:g} Hz (sweep end)"


@app.command("tune")
def tune(
    params: ParamsOption = None,
    settling_time: SettlingOption = 0.2,
    integral_fraction: Annotated[
        float,
        checked("Ki as a fraction of J w0^3 (0 for PD).", low=0.0, high=10.0),
    ] = 0.2,
    with_user: Annotated[
        bool,
        typer.Option("--user/--no-user", metavar="", help="Include the seated user's ankle."),
    ] = False,
    out: OutOption = None,
    force: ForceOption = False,
) -> None:
    """Design critically damped PID gains from the platform model (paper 001, section 3.2)."""
    import numpy as np

    from anklelab.control.pid import design_critically_damped
    from anklelab.sim.capstan import disturbance_to_angle, linear_platform, reference_to_angle

    options = SetupOptions(
        params=params,
        sample_rate=1000.0,
        person=Person.none,
        gravity=True,
        friction_comp=0.0,
        friction_model=None,
        settling_time=settling_time,
        seed=0,
        out=out,
        force=force,
    )
    settings = {"integral_fraction": integral_fraction, "with_user": with_user}
    with options.output("tune", settings) as written:
        platform = options.platform()
        gains = design_critically_damped(
            platform,
            settling_time_s=settling_time,
            integral_fraction=integral_fraction,
            with_user=with_user,
        )
        written.json("gains.json", gains.model_dump())
    user = platform.user if with_user else None
    lin = linear_platform(platform, user)
    args = (platform, gains.kp_nm_per_rad, gains.kd_nms_per_rad, gains.ki_nm_per_rad_s)
    tracking = reference_to_angle(*args, user=user)
    compliance = disturbance_to_angle(*args, user=user)
    freqs = np.logspace(-1, 2, 600)
    gain = np.abs(np.squeeze(tracking.frequency_response(2 * np.pi * freqs).complex))
    below = np.flatnonzero(gain < 10 ** (-3 / 20))
    bandwidth = float(freqs[below[0]]) if below.size else math.inf
    poles = np.sort_complex(tracking.poles())
    compliance_1hz = float(np.abs(np.squeeze(compliance.frequency_response(2 * np.pi).complex)))
    table(
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


@app.command("step")
@with_setup_options()
def step(
    degrees: Annotated[
        str,
        typer.Option(
            metavar="DEG,...",
            help="Set-points, degrees, comma-separated (the monitor refuses NaN/inf).",
        ),
    ] = "5,10,15",
    hold: Annotated[
        float,
        checked("Hold after each step, s.", low=0.0, high=60.0, strict=True),
    ] = 1.5,
    feedforward: Annotated[
        bool,
        typer.Option(
            "--feedforward/--no-feedforward", metavar="", help="Inverse-dynamics feed-forward."
        ),
    ] = False,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """Set-point steps (paper 001: 5, 10, 15 deg reached within 300 ms)."""
    from anklelab.experiments.capstan import step_response

    set_points = numbers(degrees, "--degrees", low=-90.0, high=90.0, finite=False)
    with options.output("step", {"degrees": set_points, "hold_s": hold}) as written:
        setup = options.setup(feedforward=feedforward)
        runs = [
            step_response(setup, math.radians(d), hold_s=hold, seed=options.seed)
            for d in set_points
        ]
        rows = []
        for (run, m), d in zip(runs, set_points, strict=True):
            code = int(run["fault"].max())
            figures = (
                [
                    f"{m.rise_time_s * 1e3:.0f} ms",
                    f"{m.settling_time_5_s * 1e3:.0f} ms",
                    f"{m.settling_time_s * 1e3:.0f} ms",
                    f"{m.overshoot_percent:.1f} %",
                    f"{math.degrees(m.steady_state_error_rad):+.3f} deg",
                ]
                if code == 0
                else ["-"] * 5
            )
            rows.append([f"{d:g} deg", *figures, fault_text(code)])
        table(
            f"set-point steps at {options.sample_rate:g} Hz (gravity compensation "
            f"{options.gravity}, friction compensation {options.friction_comp:g})",
            ["set-point", "rise 10-90 %", "settle 5 %", "settle 2 %", "overshoot", "ss error",
             "fault"],
            rows,
        )  # fmt: skip
        explain_faults(run["fault"].max() for run, _ in runs)
        results = [
            {"set_point_deg": d, "fault": fault_text(run["fault"].max()), **asdict(m)}
            for (run, m), d in zip(runs, set_points, strict=True)
        ]
        written.json("steps.json", results)
        if (figure := written.path("steps.png")) is not None:
            from anklelab.report.figures_capstan import step_figure

            step_figure(runs, figure)
    worst = max(int(run["fault"].max()) for run, _ in runs)
    fail_on_fault("step", worst, "a set-point")


@app.command("chirp")
@with_setup_options()
def chirp(
    amplitude: Annotated[
        float,
        checked("Amplitude, degrees.", low=0.0, high=40.0, strict=True),
    ] = 5.0,
    f0: Annotated[
        float,
        checked("Start frequency, Hz.", low=0.0, high=100.0, strict=True),
    ] = 0.2,
    f1: Annotated[
        float,
        checked("End frequency, Hz.", low=0.0, high=100.0, strict=True),
    ] = 5.0,
    duration: Annotated[float, checked("Sweep duration, s.", low=0.5, high=600.0)] = 10.0,
    tracking: Annotated[
        Tracking,
        typer.Option(
            help="pid: the PID alone (paper 001); feedforward: plus inverse dynamics; zpetc: "
            "plus the zero-phase-error tracking controller for the known chirp."
        ),
    ] = Tracking.pid,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """Chirp tracking (paper 001: 5 deg, 0.2 to 5 Hz over 10 s, good up to about 3 Hz)."""
    import numpy as np

    from anklelab.errors import ParameterError
    from anklelab.experiments.capstan import chirp_tracking

    if not f0 < f1:
        raise ParameterError(f"--f1 must exceed --f0; got {f0:g} and {f1:g} Hz")
    settings = {"amplitude_deg": amplitude, "f0_hz": f0, "f1_hz": f1, "duration_s": duration}
    with options.output("chirp", settings | {"tracking": tracking}) as written:
        setup = options.setup(feedforward=tracking is not Tracking.pid)
        result, m = chirp_tracking(
            setup,
            amplitude_rad=math.radians(amplitude),
            f0_hz=f0,
            f1_hz=f1,
            duration_s=duration,
            zpetc=tracking is Tracking.zpetc,
            seed=options.seed,
        )
        code = int(result["fault"].max())

        def at(frequency: float, values: np.ndarray) -> float:
            return float(np.interp(frequency, m.frequency_hz, values))

        table(
            f"chirp {amplitude:g} deg, {f0:g}-{f1:g} Hz over {duration:g} s at "
            f"{options.sample_rate:g} Hz, tracking: {tracking.value}",
            ["quantity", "value"],
            [
                ["rms tracking error", f"{math.degrees(m.rms_error_rad):.3f} deg"],
                ["rms error below 3 Hz", f"{math.degrees(m.rms_error_to_3hz_rad):.3f} deg"],
                ["max error", f"{math.degrees(m.max_error_rad):.3f} deg"],
                ["tracks within 1 dB and 20 deg up to", _hz(m.tracking_limit_hz, f1)],
                ["-3 dB bandwidth", _hz(m.bandwidth_3db_hz, f1)],
                ["45 deg lag bandwidth", _hz(m.bandwidth_45deg_hz, f1)],
                ["gain at 3 Hz", f"{20 * math.log10(at(3.0, m.gain)):+.2f} dB"],
                ["phase at 3 Hz", f"{at(3.0, m.phase_deg):.1f} deg"],
                ["safety fault", fault_text(code)],
            ],
        )
        written.json("chirp.json", asdict(m))
        if (figure := written.path("chirp.png")) is not None:
            from anklelab.report.figures_capstan import chirp_tracking_figure

            chirp_tracking_figure(result, m, figure)
    fail_on_fault("chirp", code, "the chirp")


@app.command("envelope")
@with_setup_options()
def envelope(
    low: Annotated[float, checked("Lowest frequency, Hz.", low=0.01, high=100.0)] = 0.1,
    high: Annotated[float, checked("Highest frequency, Hz.", low=0.01, high=100.0)] = 20.0,
    points: Annotated[int, typer.Option(help="Frequencies, log-spaced.", min=2, max=60)] = 13,
    check: Annotated[
        bool,
        typer.Option(
            "--check/--no-check",
            metavar="",
            help="Find the envelope on the twin too (a few seconds).",
        ),
    ] = True,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """The display envelope: the largest amplitude the platform renders at each frequency,
    from the model and (--check) found on the twin, with paper 001's 5 deg / 3 Hz."""
    import numpy as np

    from anklelab.errors import ParameterError
    from anklelab.experiments.capstan.envelope import analytic_envelope, check_envelope

    if not low < high or high >= options.sample_rate / 4:
        raise ParameterError(
            f"--low must be below --high, and --high below a quarter of the sample rate; got "
            f"{low:g}, {high:g} Hz"
        )
    settings = {"low_hz": low, "high_hz": high, "points": points, "check": check}
    with options.output("envelope", settings) as written:
        setup = options.setup(feedforward=True)
        frequencies = np.geomspace(low, high, points)
        checked = check_envelope(setup, frequencies, seed=options.seed) if check else None
        analytic = checked.analytic if checked else analytic_envelope(setup, frequencies)
        rows = []
        for k, f in enumerate(frequencies):
            row = [
                f"{f:.3g} Hz",
                f"{math.degrees(analytic.amplitude_rad[k]):.3f} deg",
                analytic.limiting[k],
            ]
            if checked:
                row += [
                    f"{math.degrees(checked.simulated_rad[k]):.3f} deg",
                    f"{checked.error_percent[k]:+.1f} %",
                    checked.reasons[k],
                ]
            rows.append(row)
        columns = ["frequency", "model", "limited by"]
        columns += ["twin", "twin - model", "twin stopped by"] if checked else []
        table(
            f"display envelope (torque for motion {analytic.torque_limit_nm:.1f} N·m, person "
            f"{options.person.value}); closed-loop bandwidth with feed-forward "
            f"{_hz(analytic.fidelity_hz, 100.0)}",
            columns,
            rows,
        )
        results = {
            "frequency_hz": frequencies,
            "amplitude_rad": analytic.amplitude_rad,
            "limiting": analytic.limiting,
            "bounds_rad": analytic.bounds,
            "torque_limit_nm": analytic.torque_limit_nm,
            "bandwidth_hz": analytic.fidelity_hz,
        }
        if checked:
            results |= {
                "twin_amplitude_rad": checked.simulated_rad,
                "twin_minus_model_percent": checked.error_percent,
                "twin_stopped_by": checked.reasons,
            }
        written.json("envelope.json", results)
        if (figure := written.path("envelope.png")) is not None:
            from anklelab.report.figures_capstan import envelope_figure

            envelope_figure(analytic, checked, figure)


@app.command("observe")
@with_setup_options()
def observe(
    task: Annotated[
        Task, typer.Option(help="hold (level set-point) or track (slow multisine).")
    ] = Task.hold,
    cutoff: Annotated[
        float,
        checked("Q-filter cut-off, Hz.", low=0.0, high=5000.0, strict=True),
    ] = 20.0,
    torque_rms: Annotated[
        float,
        checked("Voluntary torque RMS, N·m.", low=0.0, high=20.0, strict=True),
    ] = 3.0,
    band: Annotated[
        float,
        checked("Voluntary torque up to this frequency, Hz.", low=0.2, high=50.0),
    ] = 3.0,
    duration: Annotated[float, checked("Trial length, s.", low=2.0, high=600.0)] = 20.0,
    options: SetupOptions = None,  # type: ignore[assignment]
) -> None:
    """Estimate the user's ankle torque from current and encoder (disturbance observer)."""
    from anklelab.experiments.capstan import observer_trial

    name = f"observer_{task.value}"
    settings = {"task": task, "cutoff_hz": cutoff, "torque_rms_nm": torque_rms, "band_hz": band}
    with options.output("observe", settings | {"duration_s": duration}) as written:
        setup = options.setup(observer_cutoff_hz=cutoff)
        result, m = observer_trial(
            setup,
            task.value,  # type: ignore[arg-type]
            duration_s=duration,
            torque_rms_nm=torque_rms,
            band_hz=(0.1, band),
            seed=options.seed,
        )
        code = int(result["fault"].max())
        table(
            f"disturbance observer ({task.value}, Q cut-off {cutoff:g} Hz, "
            f"{options.sample_rate:g} Hz)",
            ["quantity", "value"],
            [
                ["VAF", f"{m.vaf_percent:.1f} %"],
                ["delay", f"{m.delay_s * 1e3:.0f} ms"],
                ["VAF, delay removed", f"{m.vaf_delay_compensated_percent:.1f} %"],
                ["rms error", f"{m.rms_error_nm:.3f} N·m"],
                ["safety fault", fault_text(code)],
            ],
        )
        written.json(f"{name}.json", asdict(m))
        if (figure := written.path(f"{name}.png")) is not None:
            from anklelab.report.figures_capstan import observer_figure

            observer_figure(result, figure, title=f"observer while {task.value}ing")
    fail_on_fault("observe", code, "the trial")


for _name in ("render", "scene", "zwidth", "teleop"):
    app.command(_name)(getattr(capstan_haptics, _name))
