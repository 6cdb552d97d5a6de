"""Study files (:mod:`anklelab.studies.spec`): what a study file may say, the points and cells it
expands into, and the one ``error:`` line naming the file and key when it is wrong."""

from __future__ import annotations

from anklelab.studies import study_from_mapping

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
