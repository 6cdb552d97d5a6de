"""Terrain scenes (shipped examples, validation, error by component) and teleoperation over a
delayed network."""

import math
from pathlib import Path

import numpy as np
import pytest

from anklelab.control.scene import Scene, TerrainSegment, load_scene, scene_profile
from anklelab.errors import ParameterError
from anklelab.experiments.capstan import CapstanSetup
from anklelab.experiments.capstan.config import Channel
from anklelab.experiments.capstan.scene import render_scene
from anklelab.experiments.capstan.teleop import teleoperate
from anklelab.sim.capstan.remote import arrivals

SCENES = sorted((Path(__file__).resolve().parents[1] / "examples" / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_shipped_scenes_render_without_fault(path):
    _run, metrics, profile = render_scene(load_scene(path))
    assert metrics.fault == 0
    assert metrics.slope_rms_error_rad < 0.15 * max(metrics.slope_rms_rad, math.radians(1))
    for patch in metrics.patches:  # the soft ground is felt (loose sand: -20 % stiffness)
        assert abs(patch.stiffness_error_percent) < 25 and abs(patch.damping_error_percent) < 10
    rendered = profile.slope_rad + profile.bumps_rad
    assert np.max(np.abs(rendered)) < CapstanSetup().params.safety.angle_limit_rad


def test_scene_profile_and_validation(tmp_path):
    step = TerrainSegment(kind="step", length_m=1.0, height_m=0.05)
    scene = Scene(name="one step", walking_speed_m_s=1.0, terrain=(step,))
    p = scene_profile(scene, 1000.0, lead_s=0.0)
    # a 5 cm step under a 25 cm foot tilts it by atan(0.2) while the edge is under the foot
    assert np.degrees(p.slope_rad.max()) == pytest.approx(math.degrees(math.atan(0.2)), rel=1e-3)
    bad = tmp_path / "bad.toml"
    bad.write_text(
        'name = "x"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "slpoe"\nlength_m = 1\n'
    )
    with pytest.raises(ParameterError, match=r"(?s)bad.toml.*terrain.0.kind"):
        load_scene(bad)
    bad.write_text(
        'name = "x"\nwalking_speed_m_s = 1.0\n[[terrain]]\nkind = "slope"\nlength_m = 1\n'
    )
    with pytest.raises(ParameterError, match="needs a nonzero grade_deg"):
        load_scene(bad)
    steep = Scene(
        name="wall",
        walking_speed_m_s=1.0,
        terrain=(TerrainSegment(kind="slope", length_m=3.0, grade_deg=39.0),),
    )
    with pytest.raises(ParameterError, match="beyond 90 %"):
        render_scene(steep)


def test_arrivals_hold_the_newest_packet():
    assert arrivals(5, 1000.0, 0.0, 0.0).tolist() == [-1, 0, 1, 2, 3]
    newest = arrivals(2000, 1000.0, 0.05, 0.05, seed=1)
    assert np.all(np.diff(newest) >= 0)  # never an older packet after a newer one
    lag = np.arange(2000) - newest
    assert lag[newest >= 0].min() >= 50 and lag[newest >= 0].max() <= 101


def test_wave_teleoperation_is_stable_at_200_ms_with_jitter_and_direct_is_not():
    setup = CapstanSetup()
    _run, wave = teleoperate(setup, Channel("wave", 0.2, 0.05), duration_s=10.0)
    assert wave.stable and wave.channel_energy_min_j >= -1e-9
    assert wave.position_rms_error_rad < 0.8 * wave.remote_rms_rad
    _, direct = teleoperate(setup, Channel("direct", 0.2, 0.0), duration_s=10.0)
    assert not direct.stable


def test_tracking_degrades_with_delay():
    setup = CapstanSetup()
    errors = [
        teleoperate(setup, Channel("wave", d, 0.0), duration_s=10.0)[1].position_rms_error_rad
        for d in (0.0, 0.2)
    ]
    assert errors[0] < errors[1]
