"""Study files (:mod:`anklelab.studies.spec`): what a study file may say, the points and cells it
expands into, and the one ``error:`` line naming the file and key when it is wrong."""

from __future__ import annotations

import pytest

from anklelab.errors import ParameterError
from anklelab.studies import load_study, study_from_mapping

BASE = {
    "name": "spec",
    "seeds": [0, 1],
    "twin": {"trials_per_point": 3, "n_unperturbed": 6, "n_calibration": 2, "bench": False},
    "analysis": {"bootstrap_reps": 10},
}


def test_a_value_listed_twice_in_a_grid_is_one_point_computed_once():
    """``100`` and ``100.0`` are the same window: the summary counted them as independent
    sessions (n doubled, the sd over seeds shrunk)."""
    study = study_from_mapping(
        BASE | {"grid": {"analysis.window_ms": [100.0, 100.0, 100, 75.0]}}, origin="s"
    )
    assert study.points() == [{"analysis.window_ms": 100.0}, {"analysis.window_ms": 75.0}]
    cells = study.cells()
    assert len(cells) == 2 * 2 and len({cell.key for cell in cells}) == len(cells)
    assert [cell.index for cell in cells] == [0, 1, 2, 3]


def test_repeated_draws_of_a_sample_are_one_point():
    sample = {"n": 6, "seed": 3, "analysis.window_ms": {"choice": [75.0, 100]}}
    study = study_from_mapping(BASE | {"sample": sample}, origin="s")
    windows = [point["analysis.window_ms"] for point in study.points()]
    assert sorted(windows) == [75.0, 100]
    assert len(study.cells()) == 2 * 2


def test_a_cell_key_is_the_same_for_a_whole_float_and_its_integer():
    def key(window: float | int) -> str:
        doc = BASE | {"grid": {"analysis.window_ms": [window]}}
        return study_from_mapping(doc, origin="s").cells()[0].key

    assert key(100) == key(100.0) != key(100.5)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", r"nothing to run: give a \[grid\] or a \[sample\] of settings to vary, or seeds"),
        ('name = "x"\n[twin]\ntrials_per_point = 3\n', r"nothing to run"),
        ("seeds = 2\n[grid]\n", r"\[grid\]: empty; give at least one KEY = \[values\]"),
        (
            "[sample]\nn = 2\nseed = 1\n",
            r"\[sample\]: no key to draw; give at least one KEY = \{uniform = \[lo, hi\]\}",
        ),
        ("[sample]\n", r"sample\.n: expected a number of points >= 1, got None"),
    ],
)
def test_a_study_that_varies_nothing_is_refused_naming_what_is_missing(tmp_path, text, match):
    path = tmp_path / "study.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError, match=rf"^{path}: .*{match}"):
        load_study(path)


def test_seeds_alone_are_a_study():
    doc = {key: value for key, value in BASE.items() if key != "grid"}
    assert len(study_from_mapping(doc, origin="s").cells()) == 2


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"seeds": 100_001}, r"seeds: 100001 sessions \(1 point × 100001 seeds\)"),
        ({"seeds": 10**12}, r"seeds: 1000000000000 sessions \(1 point × 1000000000000 seeds\)"),
        (
            {"grid": {"analysis.window_ms": [100.0] * 400, "twin.noise_scale": [1.0] * 300}},
            r"grid: 240000 sessions \(400 × 300 points × 2 seeds\)",
        ),
        (
            {"sample": {"n": 10**9, "seed": 0, "twin.noise_scale": {"uniform": [1.0, 2.0]}}},
            r"sample: 2000000000 sessions \(1000000000 points × 2 seeds\)",
        ),
    ],
)
def test_a_study_too_large_is_refused_before_anything_is_expanded(change, match):
    with pytest.raises(ParameterError, match=rf"^s\.toml: {match}; at most 100000 sessions in one"):
        study_from_mapping(BASE | change, origin="s.toml")


@pytest.mark.parametrize(
    ("content", "match"),
    [
        (None, r"nonexistent\.toml: parameter file not found"),
        ("[geometry]\ncolour = 1\n", r"colour"),
        ("not toml", r"not valid TOML"),
    ],
)
def test_a_bad_params_file_is_named_with_the_study_file_and_its_key(tmp_path, content, match):
    name = "nonexistent.toml" if content is None else "platform.toml"
    if content is not None:
        (tmp_path / name).write_text(content, encoding="utf-8")
    doc = BASE | {"params_file": name}
    with pytest.raises(ParameterError, match=rf"(?s)^s\.toml: params_file = '{name}': .*{match}"):
        study_from_mapping(doc, origin="s.toml", root=tmp_path)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            "[grid]\nparams.geometry.misalignment_anterior_m = [0.0, 0.01]\n",
            r'\[grid\] params: .*quote the key: "params\.geometry\.misalignment_anterior_m" = \[',
        ),
        (
            '[grid.twin]\nfoot = ["human"]\n',
            r'\[grid\] twin: .*quote the key: "twin\.foot" = \[',
        ),
        (
            "[sample]\nn = 2\nseed = 1\ntwin.noise_scale = {uniform = [1.0, 2.0]}\n",
            r'\[sample\] twin: .*quote the key: "twin\.noise_scale" = \{',
        ),
    ],
)
def test_an_unquoted_dotted_key_gets_the_hint_to_quote_it(tmp_path, text, match):
    """TOML reads ``params.geometry.x = [...]`` as nested tables: the message said only that
    the key was not of the form twin.KEY, params.SECTION.KEY or analysis.KEY."""
    path = tmp_path / "study.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError, match=rf"^{path}: {match}"):
        load_study(path)


@pytest.mark.parametrize("bounds", [[6.9, 8.2], [6.0, 8.0], [True, 8]])
def test_integers_are_drawn_between_whole_numbers_only(bounds):
    """``{integers = [6.9, 8.2]}`` drew 6, below its lower end."""
    sample = {"n": 3, "seed": 1, "twin.noise_scale": {"integers": bounds}}
    match = r"sample\.twin\.noise_scale: expected one of .*\{integers = \[lo, hi\]\} \(whole"
    with pytest.raises(ParameterError, match=match):
        study_from_mapping(BASE | {"sample": sample}, origin="s.toml")


def test_the_study_record_names_its_params_file_and_its_sha256(tmp_path):
    """run.json recorded only ``"params_file": true``: which file, with what content?"""
    import shutil

    from anklelab._runs import sha256_file
    from anklelab.platforms.registry import platform_file

    path = tmp_path / "platform.toml"
    shutil.copyfile(platform_file("perturberator"), path)
    study = study_from_mapping(BASE | {"params_file": "platform.toml"}, origin="s", root=tmp_path)
    record = study.describe()["params_file"]
    assert record == {"path": str(path.resolve()), "sha256": sha256_file(path)}
    assert study_from_mapping(BASE, origin="s").describe()["params_file"] is None
