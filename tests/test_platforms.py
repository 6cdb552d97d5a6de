"""Platform parameter sets: shipped files load, every value has a source, bad files fail clearly."""

from pathlib import Path

import pytest

from anklelab.errors import ParameterError
from anklelab.platforms import PLATFORMS, SOURCE_KINDS, load_platform, platform_file


def leaves(node, prefix=""):
    for key, value in node.items():
        dotted = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict):
            yield from leaves(value, dotted)
        else:
            yield dotted


@pytest.mark.parametrize("name", sorted(PLATFORMS))
def test_every_shipped_value_names_its_source(name):
    params = load_platform(name)
    missing = [key for key in leaves(params.model_dump()) if key not in params.sources]
    assert missing == []
    assert all(source.startswith(SOURCE_KINDS) for source in params.sources.values())


def test_paper_numbers_are_in_the_parameter_sets():
    p = load_platform("perturberator")
    assert p.transmission.ratio == 70.0
    assert p.transmission.peak_output_torque_nm == 653.0
    assert p.transmission.series_stiffness_nm_per_rad == pytest.approx(
        12 * 60 * 180 / 3.141592653589793, rel=1e-6
    )
    assert p.walking.timing_points_ms == (100.0, 225.0, 350.0, 475.0)
    c = load_platform("capstan")
    assert (c.gearhead.ratio, c.capstan.ratio) == (13.8, 20.0)
    assert c.friction.coulomb_ccw_nm == 0.038
    assert c.workspace.angle_limit_rad == pytest.approx(43 * 3.141592653589793 / 180, rel=1e-4)


def test_parameters_are_frozen():
    p = load_platform("capstan")
    with pytest.raises(ValueError, match="frozen"):
        p.motor.resistance_ohm = 1.0


def broken(tmp_path: Path, name: str, old: str, new: str) -> Path:
    text = platform_file(name).read_text()
    assert old in text
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "resistance_ohm = { value = 0.611",
            "resistance_ohm = { value = -0.611",
            r"motor\.resistance_ohm: Input should be greater than 0",
        ),
        (
            "resistance_ohm = { value = 0.611",
            'resistance_ohm = { value = "0.611"',
            r"motor\.resistance_ohm: Input should be a valid number",
        ),
        (
            "inductance_h = ",
            "inductanse_h = ",
            r"motor\.inductanse_h: unknown key \(did you mean 'inductance_h'\?\)",
        ),
        (
            "inductance_h = ",
            "Inductance_h = ",
            r"motor\.Inductance_h: unknown key \('inductance_h' differs from 'Inductance_h' only "
            r"in case; names are case-sensitive\)",
        ),
        ("inductance_h = ", "# inductance_h = ", r"motor\.inductance_h: required key is missing"),
        (
            'source = "paper 001, Table 1: R"',
            'source = "folklore"',
            r"motor\.resistance_ohm: source must start",
        ),
    ],
)
def test_broken_parameter_file_names_file_and_key(tmp_path, old, new, message):
    path = broken(tmp_path, "capstan", old, new)
    with pytest.raises(ParameterError, match=message) as info:
        load_platform("capstan", path)
    assert str(path) in str(info.value)


def test_negative_mass_like_value_in_nested_section(tmp_path):
    path = broken(tmp_path, "perturberator", "ratio = { value = 70.0", "ratio = { value = -70.0")
    with pytest.raises(
        ParameterError, match=r"transmission\.ratio: Input should be greater than 0"
    ):
        load_platform("perturberator", path)


def test_plain_values_without_sources_are_accepted(tmp_path):
    path = tmp_path / "capstan.toml"
    path.write_text(
        platform_file("capstan")
        .read_text()
        .replace(
            'ratio = { value = 20.0, source = "paper 001, Table 1: r_c = 20:1" }', "ratio = 21.0"
        )
    )
    params = load_platform("capstan", path)
    assert params.capstan.ratio == 21.0 and "capstan.ratio" not in params.sources


def test_unknown_platform_and_missing_file():
    with pytest.raises(ParameterError, match="unknown platform 'perturbator'"):
        load_platform("perturbator")
    with pytest.raises(ParameterError, match="not found"):
        load_platform("capstan", "/nonexistent/capstan.toml")


def test_replace_validates_and_keeps_other_sources():
    p = load_platform("capstan")
    q = p.replace({"gearhead.ratio": 14.0})
    assert q.gearhead.ratio == 14.0 and "gearhead.ratio" not in q.sources
    assert q.sources["capstan.ratio"] == p.sources["capstan.ratio"]
    with pytest.raises(ParameterError, match="greater than 0"):
        p.replace({"gearhead.ratio": 0.0})


def test_platform_show_never_cuts_a_parameter_name_at_80_columns():
    import os
    import subprocess
    import sys

    from anklelab._params import dotted_leaves
    from anklelab.platforms import load_platform

    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            "from anklelab.cli import run; run()",
            "platform",
            "show",
            "capstan",
        ],
        capture_output=True,
        text=True,
        env={**os.environ, "COLUMNS": "80"},
        check=True,
    )
    names = dotted_leaves(load_platform("capstan").model_dump())
    assert max(map(len, names)) > 30
    assert all(f" {name} " in proc.stdout for name in names)


def test_hints_point_at_a_valid_name_never_the_users_own(tmp_path):
    from anklelab._params import did_you_mean, found_instead
    from anklelab.pipelines import load_walking_settings

    assert did_you_mean("fz_4", ["fz4"]) == " (did you mean 'fz4'?)"
    assert found_instead("fz4", ["fz_4"]) == " (found 'fz_4': rename it to 'fz4')"
    settings = tmp_path / "settings.toml"
    settings.write_text("lowpass_hz = 15.0\n")
    with pytest.raises(
        ParameterError, match=r"lowpass_hz: unknown key \(did you mean 'cutoff_hz'\?\)"
    ):
        load_walking_settings(settings)


def test_a_timing_point_whose_perturbation_ends_after_toe_off_is_refused():
    """The twin's trial ends with stance: a perturbation or window past toe-off used to stop a
    simulation with an IndexError deep in the kernel's set-up."""
    base = load_platform("perturberator")
    with pytest.raises(ParameterError, match=r"walking\.timing_points_ms: the last \(700 ms "):
        base.replace({"walking.timing_points_ms": (100.0, 700.0)})
    assert base.replace({"walking.timing_points_ms": (100.0, 600.0)}).walking.timing_points_ms
