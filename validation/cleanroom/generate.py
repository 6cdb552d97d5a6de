"""One clean-room session in memory: :func:`generate` builds an anklelab ``Session``.

The session follows DESIGN §4 (calibration, walking trials with their manifest, bench tests)
and carries ``truth`` (README.md, "Ground truth") and ``provenance``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from anklelab import __version__ as anklelab_version
from anklelab.data import BenchTest, Recording, Session, SessionInfo, WalkingTrial
from anklelab.forceplate import PlateGeometry
from validation.cleanroom.acquisition import (
    acquire_forces,
    acquire_goniometer,
    acquire_motor_angle,
)
from validation.cleanroom.calibration import simulate_calibration
from validation.cleanroom.config import Config, ProstheticFoot
from validation.cleanroom.foot import bench_tests, stiffness
from validation.cleanroom.plate import CHANNELS
from validation.cleanroom.protocol import walking_plan
from validation.cleanroom.truth import DIRECTION_NAMES, reference_truth
from validation.cleanroom.walking import simulate_walking

__all__ = ["GENERATOR", "generate"]

GENERATOR = "validation.cleanroom"


def _recordings(
    names: list[str], time_s: np.ndarray, columns: dict[str, np.ndarray]
) -> list[Recording]:
    """One recording per trial from arrays shaped (n_trials, n_times) (channels: (8, ...))."""
    recordings = []
    for i, name in enumerate(names):
        data = {"time_s": time_s.copy()}
        for key, value in columns.items():
            if key == "channels":
                data.update({ch: value[j, i].copy() for j, ch in enumerate(CHANNELS)})
            else:
                data[key] = value[i].copy()
        recordings.append(Recording(name, data))
    return recordings


def generate(config: Config, seed: int | np.random.Generator) -> Session:
    """Simulate one session of the Perturberator experiment.

    Parameters
    ----------
    config : Config
        Everything physical and the protocol (see :func:`validation.cleanroom.draw_config`).
    seed : int or numpy.random.Generator
        Fixes every trial-to-trial variation and all noise: the same ``(config, seed)`` gives
        the same bytes.

    Returns
    -------
    anklelab.data.Session
        Calibration recordings, walking trials (manifest order = recording order), bench
        tests (prosthetic feet with ``bench_distances_m``), ``truth`` and ``provenance``.

    Examples
    --------
    >>> from validation.cleanroom import draw_config
    >>> config = draw_config("nominal", 1, trials_per_point=2, n_calibration=1,
    ...                      calibration_duration_s=2.0)
    >>> session = generate(config, 1)
    >>> len(session.walking), len(session.calibration)
    (16, 1)
    """
    protocol = config.protocol
    plan_rng, walk_rng, cal_rng, bench_rng, noise_rng = np.random.default_rng(seed).spawn(5)
    plan = walking_plan(protocol, plan_rng)
    sim = simulate_walking(config, plan, walk_rng)
    cal = simulate_calibration(config, cal_rng)
    noise = config.noise

    width = max(4, len(str(plan.n_trials)))
    names = [f"trial_{i:0{width}d}.csv" for i in range(1, plan.n_trials + 1)]
    walking_columns = {
        "motor_angle": acquire_motor_angle(sim.motor_angle, noise, noise_rng),
        "ankle_angle": acquire_goniometer(sim.ankle_angle, noise, noise_rng),
        "channels": acquire_forces(sim.channels, sim.time_s, noise, noise_rng),
    }
    walking = tuple(
        WalkingTrial(
            trial=i + 1,
            recording=recording,
            perturbed=bool(plan.perturbed[i]),
            direction=DIRECTION_NAMES.get(float(plan.sign[i]), "none"),
            delay_ms=float(plan.delay_ms[i]),
        )
        for i, recording in enumerate(_recordings(names, sim.time_s, walking_columns))
    )
    cal_columns = {
        "motor_angle": acquire_motor_angle(cal.motor_angle, noise, noise_rng),
        "channels": acquire_forces(cal.channels, cal.time_s, noise, noise_rng),
    }
    cal_names = [f"calibration_{i:02d}.csv" for i in range(1, protocol.n_calibration + 1)]
    calibration = tuple(_recordings(cal_names, cal.time_s, cal_columns))

    truth = reference_truth(config, plan, sim)
    truth["config"] = config.to_dict()
    bench: tuple[BenchTest, ...] = ()
    if isinstance(config.foot, ProstheticFoot) and protocol.bench_distances_m:
        distances = np.asarray(protocol.bench_distances_m, dtype=float)
        k = stiffness(config.foot, np.zeros_like(distances), distances)
        truth["bench"] = {"distances_m": distances, "stiffness_nm_per_rad": k}
        tests = bench_tests(
            config.foot, protocol, noise.scale * noise.bench_force_noise_n, bench_rng
        )
        bench = tuple(
            BenchTest(
                test=i,
                recording=Recording(
                    f"bench_{i:02d}.csv",
                    {"time_s": time, "displacement_m": displacement, "force_n": force},
                ),
                distance_m=float(distance),
            )
            for i, (distance, time, displacement, force) in enumerate(tests, start=1)
        )

    plate = config.plate
    info = SessionInfo(
        platform="perturberator",
        sample_rate_hz=float(protocol.sample_rate_hz),
        subject=f"cleanroom-{config.kind}",
        force_plate=PlateGeometry(
            a_m=plate.a_m, b_m=plate.b_m, az0_m=plate.az0_m, anterior_axis=plate.anterior_axis
        ),
        ankle_height_m=float(config.foot.ankle_height_m),
        heel_to_ankle_m=float(config.foot.heel_to_ankle_m),
    )
    provenance: dict[str, Any] = {
        "generator": GENERATOR,
        "kind": config.kind,
        "seed": seed if isinstance(seed, int) else "numpy.random.Generator",
        "anklelab_version": anklelab_version,
    }
    return Session(info, calibration, walking, bench, truth, provenance)
